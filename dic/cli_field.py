"""``jointwear dic field``: full-field 2D or stereo DIC over a ROI (thin layer over
:func:`jointwear.dic.measure_field`)."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import Annotated

import typer

from jointwear._cli import Overwrite
from jointwear._cli_dataclass import options_from
from jointwear.dic import _cli_options as opt
from jointwear.dic.field._params import FieldParams

#: the library's defaults (every option's default and help are read from them)
_P = FieldParams


def _refuse_misapplied(p: dict) -> None:
    """Usage errors (exit 2): 2D and stereo inputs mixed, stereo options on a 2D field."""
    stereo = bool(p["left"] or p["right"])
    if stereo and p["images"]:
        raise typer.BadParameter("give either IMAGES (2D) or --left/--right (stereo)")
    if stereo and not (p["left"] and p["right"]):
        raise typer.BadParameter("stereo needs both --left and --right")
    if not stereo and not p["images"]:
        raise typer.BadParameter("give the images (2D) or --left/--right (stereo)")
    if stereo and p["calibration"] is None:
        raise typer.BadParameter("stereo needs --calibration")
    if not stereo and p["calibration"] is not None:
        raise typer.BadParameter("--calibration needs --left/--right images (stereo)")
    if not stereo:
        opt.refuse_given(
            ((p["frame"], "--frame"), (p["epipolar_max"], "--epipolar-max")),
            "a stereo field (--left/--right/--calibration); a 2D field is in image pixels",
        )
    if p["points"] is not None and p["roi"] is not None:
        raise typer.BadParameter("give either --points or --roi, not both")
    entries = [*(p["images"] or ()), *(p["left"] or ()), *(p["right"] or ())]
    if len(entries) > 1 + stereo and all(Path(e).is_file() for e in entries):
        opt.refuse_given(
            ((p["fps"], "--fps"),),
            "a filmed sequence (a folder, quoted pattern or video), not to still images given "
            "one by one (their time axis is the image index); omit --fps, or give the frames "
            "as a folder or quoted pattern",
        )
    if p["points"] is not None and p["strain_window"]:
        raise typer.BadParameter(
            "--strain-window: scattered --points have no grid to fit strain over; drop "
            "--strain-window, or use --roi for a grid with strain"
        )


@options_from("params", FieldParams, *opt.CORRELATION)
def field_cmd(
    ctx: typer.Context,
    images: Annotated[
        list[str] | None,
        typer.Argument(
            help="2D: reference and deformed images, or one folder / quoted pattern "
            "('f/*.tif'); the first image is the reference."
        ),
    ] = None,
    left: Annotated[
        list[Path] | None,
        typer.Option("--left", help="Stereo: left images (repeatable) or a folder/pattern."),
    ] = None,
    right: Annotated[
        list[Path] | None,
        typer.Option("--right", help="Stereo: right images (repeatable) or a folder/pattern."),
    ] = None,
    calibration: opt.CalibrationOpt = None,
    roi: Annotated[
        str | None,
        typer.Option("--roi", help="x0,y0,x1,y1 (pixels), a polygon .toml or a mask image (left)."),
    ] = None,
    params: FieldParams = _P(),
    strain_window: Annotated[
        int | None,
        typer.Option(
            "--strain-window",
            help="Strain fit window (grid points, odd; 0: none). "
            f"Default {_P.strain_window} (0 with --points).",
        ),
    ] = None,
    points: opt.PointsOpt = None,
    frame: Annotated[
        str | None,
        typer.Option(
            "--frame",
            help=f"Stereo output frame: world or plane (best fit). Default {_P.frame}.",
        ),
    ] = None,
    fps: opt.FpsOpt = None,
    epipolar_max: Annotated[
        float | None,
        typer.Option(
            "--epipolar-max",
            help="Stereo: flag pairs whose rays miss by more (pixels, RMS reprojection). "
            f"Default {_P.epipolar_max_px:g}.",
        ),
    ] = None,
    origin: opt.OriginOpt = "measured",
    out: opt.OutOpt = Path("field.nc"),
    csv: Annotated[
        Path | None,
        typer.Option("--csv", help="Also write CSV (one file per image, VIC-3D-like)."),
    ] = None,
    plot: opt.PlotOpt = None,
    allow_empty: opt.AllowEmptyOpt = False,
    overwrite: Overwrite = False,
) -> None:
    """Displacement, shape and strain of a surface over a ROI (2D, or stereo with
    --left/--right/--calibration); still images need no --fps."""
    from jointwear.dic._flag_report import check_flags
    from jointwear.dic.field._files import measure_field_files

    _refuse_misapplied(ctx.params)
    given = dict(frame=frame, epipolar_max_px=epipolar_max, strain_window=strain_window)
    if points is not None and strain_window is None:
        given["strain_window"] = 0  # scattered points: no grid to fit strain on
    params = replace(params, **{k: v for k, v in given.items() if v is not None})
    ds, elapsed, files = measure_field_files(
        images,
        out,
        left=left,
        right=right,
        calibration=calibration,
        params=params,
        roi=roi,
        points=points,
        frame_rate=fps,
        data_origin=origin,
        csv=csv,
        plot=plot,
    )
    ok = ds["flag"].values[-1] == 0
    msg = f"{out}: {ok.sum()}/{ok.size} points ok in the last image, {elapsed:.1f} s"
    if files:
        msg += f"; CSV {files[0]}" + (f" ... ({len(files)} files)" if len(files) > 1 else "")
    if plot is not None:
        msg += f"; figure {plot}"
    typer.echo(msg)
    check_flags(ds, allow_empty=allow_empty, names=list(ds.image_left.values))


def register(app: typer.Typer) -> None:
    """Add ``field`` and ``import-field`` to the ``jointwear dic`` group."""
    register_import(app)
    app.command("field")(field_cmd)


def import_field_cmd(
    files: Annotated[
        list[str],
        typer.Argument(help="One file per image (reference first), or a quoted pattern."),
    ],
    format: Annotated[str, typer.Option("--format", help="vic3d-csv (VIC-3D CSV export) or dice.")],
    origin: opt.OriginOpt,
    length_unit: Annotated[
        str | None,
        typer.Option("--length-unit", help="Unit of the files' lengths (mm, m, ...; stereo)."),
    ] = None,
    fps: opt.FpsOpt = None,
    out: opt.OutOpt = Path("field.nc"),
    overwrite: Overwrite = False,
) -> None:
    """Another DIC code's full-field results as a jointwear field dataset."""
    import numpy as np

    from jointwear._version import source_attribute
    from jointwear.dic.field._import import _files, read_field
    from jointwear.io import check_writable, save

    check_writable(out)
    paths = _files(files[0] if len(files) == 1 else files)
    times = np.arange(len(paths)) / fps if fps else None
    ds = read_field(paths, format=format, length_unit=length_unit, data_origin=origin, times=times)
    save(
        ds,
        out,
        inputs=paths,
        parameters={"format": format, "length_unit": length_unit, "fps": fps},
        source=source_attribute(f"dic.import-field from {format}"),
    )
    from jointwear.dic.field._import import import_summary

    typer.echo(f"{out}: {len(paths)} images, {import_summary(ds)}")


def register_import(app: typer.Typer) -> None:
    """Add ``import-field`` to the ``jointwear dic`` group."""
    app.command("import-field")(import_field_cmd)
