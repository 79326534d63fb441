"""``jointwear dic field``: full-field 2D or stereo DIC over a ROI (thin layer over
:func:`jointwear.dic.measure_field`)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from jointwear._cli import Overwrite
from jointwear.errors import BadInputError


def _images(values: list[str] | None, what: str):
    """One folder/pattern, or several image files (first = reference)."""
    if not values:
        return None
    if len(values) == 1:
        from jointwear.dic.footage._video import is_image_sequence

        if is_image_sequence(values[0]):
            return values[0]
        if not Path(values[0]).is_file():
            raise BadInputError(f"{what} '{values[0]}' does not exist")
    for v in values:
        if not Path(v).is_file():
            raise BadInputError(f"{what} image '{v}' does not exist")
    return [Path(v) for v in values]


def _inputs(values: list[str] | None) -> list[Path]:
    from jointwear.dic.footage._video import is_image_sequence, list_image_sequence

    out: list[Path] = []
    for v in values or []:
        if is_image_sequence(v):
            out += list_image_sequence(v)[0]
        elif Path(v).is_file():
            out.append(Path(v))
    return out


def register(app: typer.Typer) -> None:
    """Add ``field`` and ``import-field`` to the ``jointwear dic`` group."""
    register_import(app)

    @app.command("field")
    def field_cmd(
        images: Annotated[
            list[str] | None,
            typer.Argument(
                help="2D: reference and deformed images, or one folder / quoted pattern "
                "('f/*.tif'); the first image is the reference."
            ),
        ] = None,
        left: Annotated[
            list[str] | None,
            typer.Option("--left", help="Stereo: left images (repeatable) or a folder/pattern."),
        ] = None,
        right: Annotated[
            list[str] | None,
            typer.Option("--right", help="Stereo: right images (repeatable) or a folder/pattern."),
        ] = None,
        calibration: Annotated[
            Path | None, typer.Option("--calibration", help="Stereo calibration (.nc).")
        ] = None,
        roi: Annotated[
            str | None,
            typer.Option(
                "--roi", help="x0,y0,x1,y1 (pixels), a polygon .toml or a mask image (left)."
            ),
        ] = None,
        subset: Annotated[int, typer.Option("--subset", help="Subset size (pixels), odd.")] = 31,
        step: Annotated[int, typer.Option("--step", help="Grid step (pixels).")] = 10,
        strain_window: Annotated[
            int,
            typer.Option("--strain-window", help="Strain fit window (grid points, odd; 0: none)."),
        ] = 5,
        frame: Annotated[
            str, typer.Option("--frame", help="Stereo output frame: world or plane (best fit).")
        ] = "world",
        fps: Annotated[
            float | None,
            typer.Option("--fps", help="Frames per second (omit for still images)."),
        ] = None,
        zncc_min: Annotated[
            float, typer.Option("--zncc-min", help="Flag matches below this ZNCC.")
        ] = 0.8,
        epipolar_max: Annotated[
            float,
            typer.Option("--epipolar-max", help="Flag pairs whose rays miss by more (pixels)."),
        ] = 1.0,
        search_radius: Annotated[
            int, typer.Option("--search-radius", help="Seed search half-width (pixels).")
        ] = 48,
        origin: Annotated[
            str, typer.Option("--origin", help="What the images are: measured or synthetic.")
        ] = "measured",
        out: Annotated[Path, typer.Option("--out", help="Output netCDF file.")] = Path("field.nc"),
        csv: Annotated[
            Path | None,
            typer.Option("--csv", help="Also write CSV (one file per image, VIC-3D-like)."),
        ] = None,
        plot: Annotated[
            Path | None, typer.Option("--plot", help="Contour figure of the last image (png).")
        ] = None,
        threads: Annotated[int, typer.Option("--threads", help="numba threads (0: auto).")] = 0,
        overwrite: Overwrite = False,
    ) -> None:
        """Displacement, shape and strain of a surface over a ROI (2D, or stereo with
        --left/--right/--calibration); still images need no --fps."""
        import time as _time

        from jointwear._version import __version__
        from jointwear.dic.field._io import save_field_plot, write_field_csv
        from jointwear.dic.field._measure import FieldParams, measure_field
        from jointwear.io import check_writable, save

        stereo = bool(left or right)
        if stereo and images:
            raise typer.BadParameter("give either IMAGES (2D) or --left/--right (stereo)")
        if stereo and not (left and right):
            raise typer.BadParameter("stereo needs both --left and --right")
        if not stereo and not images:
            raise typer.BadParameter("give the images (2D) or --left/--right (stereo)")
        if stereo and calibration is None:
            raise typer.BadParameter("stereo needs --calibration")
        if not stereo and calibration is not None:
            raise typer.BadParameter("--calibration needs --left/--right images (stereo)")
        check_writable(out)
        for p, what in ((plot, "figure"), (csv, "CSV")):
            if p is not None:
                check_writable(p, what=what)
        roi_spec = roi  # text rectangle, polygon TOML or mask image: read_roi decides
        params = FieldParams(
            subset_size=subset,
            step=step,
            strain_window=strain_window,
            frame=frame,  # type: ignore[arg-type]
            zncc_min=zncc_min,
            epipolar_max_px=epipolar_max,
            search_radius=search_radius,
            threads=threads,
        )
        t0 = _time.perf_counter()
        if stereo:
            from jointwear.dic.calibration._importers import read_calibration

            cal = read_calibration(calibration)
            ds = measure_field(
                _images(left, "--left"),
                _images(right, "--right"),
                calibration=cal,
                roi=roi_spec,
                frame_rate=fps,
                data_origin=origin,
                params=params,
            )
            inputs = _inputs(left) + _inputs(right) + [calibration]
        else:
            ds = measure_field(
                _images(images, "IMAGES"),
                roi=roi_spec,
                frame_rate=fps,
                data_origin=origin,
                params=params,
            )
            inputs = _inputs(images)
        if roi is not None and Path(roi).is_file():
            inputs.append(Path(roi))
        elapsed = _time.perf_counter() - t0
        save(
            ds,
            out,
            inputs=inputs,
            parameters=params,
            source=f"jointwear {__version__} (dic.field)",
        )
        ok = ds["flag"].values[-1] == 0
        msg = f"{out}: {ok.sum()}/{ok.size} points ok in the last image, {elapsed:.1f} s"
        if csv is not None:
            files = write_field_csv(ds, csv)
            msg += f"; CSV {files[0]}" + (f" ... ({len(files)} files)" if len(files) > 1 else "")
        if plot is not None:
            save_field_plot(ds, plot)
            msg += f"; figure {plot}"
        typer.echo(msg)


def register_import(app: typer.Typer) -> None:
    """Add ``import-field`` to the ``jointwear dic`` group."""

    @app.command("import-field")
    def import_field_cmd(
        files: Annotated[
            list[str],
            typer.Argument(help="One file per image (reference first), or a quoted pattern."),
        ],
        format: Annotated[
            str, typer.Option("--format", help="vic3d-csv (VIC-3D CSV export) or dice.")
        ],
        origin: Annotated[
            str, typer.Option("--origin", help="What the images were: measured or synthetic.")
        ],
        length_unit: Annotated[
            str | None,
            typer.Option("--length-unit", help="Unit of the files' lengths (mm, m, ...; stereo)."),
        ] = None,
        fps: Annotated[
            float | None, typer.Option("--fps", help="Frames per second (omit: still images).")
        ] = None,
        out: Annotated[Path, typer.Option("--out", help="Output netCDF file.")] = Path("field.nc"),
        overwrite: Overwrite = False,
    ) -> None:
        """Another DIC code's full-field results as a jointwear field dataset."""
        import numpy as np

        from jointwear._version import __version__
        from jointwear.dic.field._import import _files, read_field
        from jointwear.io import check_writable, save

        check_writable(out)
        paths = _files(files[0] if len(files) == 1 else files)
        times = np.arange(len(paths)) / fps if fps else None
        ds = read_field(
            paths, format=format, length_unit=length_unit, data_origin=origin, times=times
        )
        save(
            ds,
            out,
            inputs=paths,
            parameters={"format": format, "length_unit": length_unit, "fps": fps},
            source=f"jointwear {__version__} (dic.import-field from {format})",
        )
        ok = ds.flag.values[-1] == 0
        typer.echo(f"{out}: {len(paths)} images, {ok.sum()}/{ok.size} points with data")
