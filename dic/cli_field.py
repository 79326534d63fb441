"""``jointwear dic field``: full-field 2D or stereo DIC over a ROI (thin layer over
:func:`jointwear.dic.measure_field`)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from jointwear._cli import Overwrite
from jointwear.errors import BadInputError


def _images(values: list[str] | None, what: str):
    """One folder/pattern, several image files, or a reference file followed by a folder or
    pattern of the later images (the first image is the reference)."""
    if not values:
        return None
    from jointwear.dic.footage._video import is_image_sequence, list_image_sequence

    if len(values) == 1 and is_image_sequence(values[0]):
        return values[0]
    out: list[Path] = []
    for k, v in enumerate(values):
        if Path(v).is_file():
            out.append(Path(v))
        elif k > 0 and is_image_sequence(v):
            out += list_image_sequence(v, what=f"{what} images")[0]
        elif is_image_sequence(v):
            raise BadInputError(
                f"{what}: '{v}' is a folder or pattern of images, which can only follow the "
                "reference image (or stand alone)"
            )
        else:
            raise BadInputError(f"{what} image '{v}' does not exist")
    return out


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
            int | None,
            typer.Option(
                "--strain-window",
                help="Strain fit window (grid points, odd; 0: none). Default 5 (0 with --points).",
            ),
        ] = None,
        points: Annotated[
            Path | None,
            typer.Option(
                "--points",
                help="Text file of subset centres 'x, y' (pixels, left reference image, one "
                "per line) instead of a grid over --roi; no strain.",
            ),
        ] = None,
        frame: Annotated[
            str | None,
            typer.Option(
                "--frame", help="Stereo output frame: world or plane (best fit). Default world."
            ),
        ] = None,
        fps: Annotated[
            float | None,
            typer.Option("--fps", help="Frames per second (omit for still images)."),
        ] = None,
        zncc_min: Annotated[
            float, typer.Option("--zncc-min", help="Flag matches below this ZNCC.")
        ] = 0.8,
        epipolar_max: Annotated[
            float | None,
            typer.Option(
                "--epipolar-max",
                help="Stereo: flag pairs whose rays miss by more (pixels, RMS reprojection). "
                "Default 1.",
            ),
        ] = None,
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
        allow_empty: Annotated[
            bool,
            typer.Option(
                "--allow-empty",
                help="Exit 0 even when an image has no valid point (otherwise exit 1).",
            ),
        ] = False,
        overwrite: Overwrite = False,
    ) -> None:
        """Displacement, shape and strain of a surface over a ROI (2D, or stereo with
        --left/--right/--calibration); still images need no --fps."""
        import time as _time

        from jointwear._version import __version__
        from jointwear.dic._flag_report import check_flags
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
        if not stereo:
            for given, flag in ((frame, "--frame"), (epipolar_max, "--epipolar-max")):
                if given is not None:
                    raise typer.BadParameter(
                        f"{flag} applies to a stereo field (--left/--right/--calibration); "
                        "a 2D field is in image pixels"
                    )
        if points is not None and roi is not None:
            raise typer.BadParameter("give either --points or --roi, not both")
        if points is not None and strain_window:
            raise typer.BadParameter(
                "--strain-window: scattered --points have no grid to fit strain over; drop "
                "--strain-window, or use --roi for a grid with strain"
            )
        check_writable(out)
        for p, what in ((plot, "figure"), (csv, "CSV")):
            if p is not None:
                check_writable(p, what=what)
        roi_spec = roi  # text rectangle, polygon TOML or mask image: read_roi decides
        params = FieldParams(
            subset_size=subset,
            step=step,
            strain_window=(0 if points is not None else 5)
            if strain_window is None
            else strain_window,
            frame=frame or "world",  # type: ignore[arg-type]
            zncc_min=zncc_min,
            epipolar_max_px=1.0 if epipolar_max is None else epipolar_max,
            search_radius=search_radius,
            threads=threads,
        )
        pts = None
        if points is not None:
            from jointwear.dic.cli_correlate import read_points_file

            pts = read_points_file(points)
        t0 = _time.perf_counter()
        if stereo:
            from jointwear.dic.calibration._importers import read_calibration

            cal = read_calibration(calibration)
            ds = measure_field(
                _images(left, "--left"),
                _images(right, "--right"),
                calibration=cal,
                roi=roi_spec,
                points=pts,
                frame_rate=fps,
                data_origin=origin,
                params=params,
            )
            inputs = _inputs(left) + _inputs(right) + [calibration]
        else:
            ds = measure_field(
                _images(images, "IMAGES"),
                roi=roi_spec,
                points=pts,
                frame_rate=fps,
                data_origin=origin,
                params=params,
            )
            inputs = _inputs(images)
        for extra in (roi, points):
            if extra is not None and Path(extra).is_file():
                inputs.append(Path(extra))
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
        check_flags(ds, allow_empty=allow_empty, names=list(ds.image_left.values))


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
