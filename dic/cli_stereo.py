"""``jointwear dic calibrate | import-calibration | track | plot-track``: stereo rig commands."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Literal

import typer

from jointwear._cli import FigureOut, Overwrite, Scheduler
from jointwear.dic import _cli_options as opt
from jointwear.dic.calibration import _defaults as defaults


def _board(board, squares, square, unit, square_u, square_mm, marker, marker_mm, dictionary):
    """The calibration board of the options, and the square side and unit as given; usage
    errors (exit 2) for a missing square size, an unknown unit or marker options on a
    chessboard."""
    from jointwear.dic.calibration._board import CalibrationBoard
    from jointwear.dic.calibration._importers import _LENGTH_UNITS

    if square_mm is not None:
        if square is not None:
            raise typer.BadParameter("give --square (with --unit), not also --square-mm")
        square, unit = square_mm, "mm"
    if square is None:
        raise typer.BadParameter(
            "the board's square size is required: --square 25 --unit mm (or --square 1 "
            "--unit square for lengths in squares)",
            param_hint="--square",
        )
    if unit == "square":
        scale, length_unit = 1.0, "square"
    elif unit in _LENGTH_UNITS:
        scale, length_unit = _LENGTH_UNITS[unit], "m"
    else:
        raise typer.BadParameter(
            f"{unit!r}: expected one of {', '.join(_LENGTH_UNITS)} or square",
            param_hint="--unit",
        )
    if board == "chessboard":
        opt.refuse_given(
            ((marker, "--marker"), (marker_mm, "--marker-mm"), (dictionary, "--dictionary")),
            "a ChArUco board (--board charuco), not a chessboard",
        )
    if marker is not None:
        marker_m = marker * scale
    else:
        marker_m = marker_mm * 1e-3 if marker_mm is not None else 0.75 * square * scale
    b = CalibrationBoard(
        board,
        squares[0],
        squares[1],
        square * scale,
        marker_m,
        dictionary or defaults.CHARUCO_DICTIONARY,
        length_unit=length_unit,
        square_size_u=None if square_u is None else square_u * scale,
    )
    return b, square, unit


def _calibration_lines(cal, out: Path) -> list[str]:
    from jointwear.dic.calibration._gate import view_table

    lu = "mm" if cal.length_unit == "m" else cal.length_unit + "s"
    ls = 1e3 if cal.length_unit == "m" else 1.0
    u = (
        f" (relative length uncertainty {cal.length_scale_u_rel:.1e})"
        if cal.length_scale_u_rel is not None
        else ""
    )
    head = (
        f"calibrated from {cal.views_used} views ({cal.views_rejected} rejected): RMS "
        f"{cal.rms:.3f} px, baseline {cal.baseline * ls:.2f} {lu}{u}, focal "
        f"{cal.left.focal[0]:.1f}/{cal.right.focal[0]:.1f} px -> {out}"
    )
    return [head, *view_table(cal)]


def calibrate_cmd(
    left: Annotated[
        Path,
        typer.Option(
            "--left",
            help="Left board images (folder or quoted pattern 'cal/*_0.tif') or video.",
        ),
    ],
    right: Annotated[
        Path,
        typer.Option(
            "--right",
            help="Right board images (folder or quoted pattern 'cal/*_1.tif') or video.",
        ),
    ],
    out: opt.CalibrationOutOpt = Path("calibration.nc"),
    overwrite: Overwrite = False,
    board: Annotated[
        Literal["chessboard", "charuco"], typer.Option(help="chessboard or charuco.")
    ] = defaults.BOARD_KIND,
    squares: Annotated[
        tuple[int, int], typer.Option(help="Squares along x and y (not inner corners).")
    ] = defaults.BOARD_SQUARES,
    square: Annotated[
        float | None,
        typer.Option(help="Side of one board square, in --unit (required)."),
    ] = None,
    unit: Annotated[
        str,
        typer.Option(
            help="Unit of --square/--marker/--square-u: m, mm, cm, um, in, or 'square' "
            "(lengths in board squares; such a calibration cannot measure)."
        ),
    ] = "mm",
    square_u: Annotated[
        float | None,
        typer.Option(help="Standard uncertainty of the square side, in --unit."),
    ] = None,
    square_mm: Annotated[
        float | None, typer.Option(hidden=True, help="Deprecated: --square N --unit mm.")
    ] = None,
    marker: Annotated[float | None, typer.Option(help="ChArUco marker side, in --unit.")] = None,
    marker_mm: Annotated[float | None, typer.Option(hidden=True)] = None,
    dictionary: Annotated[
        str | None,
        typer.Option(help=f"ChArUco ArUco dictionary (default {defaults.CHARUCO_DICTIONARY})."),
    ] = None,
    world_view: Annotated[
        int | None,
        typer.Option(help="Index of the view whose board pose becomes the world frame."),
    ] = None,
    min_views: Annotated[
        int, typer.Option(min=1, help="Fewest usable views.")
    ] = defaults.MIN_VIEWS,
    every: Annotated[
        int | None,
        typer.Option(min=1, help=f"Videos: use every N-th frame (default {defaults.VIDEO_EVERY})."),
    ] = None,
    max_rms: Annotated[
        float, typer.Option(help="Largest acceptable stereo reprojection RMS (px).")
    ] = defaults.MAX_RMS_PX,
    max_view_rms: Annotated[
        float,
        typer.Option(help="Views above this per-camera reprojection RMS (px) are dropped."),
    ] = defaults.MAX_VIEW_RMS_PX,
    accept_poor: Annotated[
        bool,
        typer.Option(
            help="Write a calibration that fails the sanity checks instead of refusing it."
        ),
    ] = False,
) -> None:
    """Calibrate a stereo pair from simultaneous views of a chessboard or ChArUco board.

    The result passes a sanity gate (reprojection RMS, field of view, pixel aspect,
    principal point, baseline, camera order); a calibration that fails it is written to
    <out>.rejected.nc for inspection and the command exits with code 1 (--accept-poor
    writes it to --out instead).
    """
    from jointwear.dic.calibration._files import calibrate_files, rejected_path
    from jointwear.dic.calibration._gate import PoorCalibration, view_table
    from jointwear.dic.footage._video import is_image_sequence

    b, square, unit = _board(
        board, squares, square, unit, square_u, square_mm, marker, marker_mm, dictionary
    )
    if every is not None and is_image_sequence(left):
        opt.refuse_given(((every, "--every"),), "videos, not a folder or pattern of images")
    params = {
        "board": b.__dict__,
        "world_view": world_view,
        "square": square,
        "unit": unit,
        "max_rms_px": max_rms,
        "accept_poor": accept_poor,
    }
    try:
        cal = calibrate_files(
            left,
            right,
            out,
            b,
            every=defaults.VIDEO_EVERY if every is None else every,
            parameters=params,
            min_views=min_views,
            world_view=world_view,
            max_rms=max_rms,
            max_view_rms=max_view_rms,
            accept_poor=accept_poor,
        )
    except PoorCalibration as exc:
        for line in view_table(exc.calibration):
            typer.echo(line, err=True)
        typer.echo(f"rejected calibration kept for inspection -> {rejected_path(out)}", err=True)
        raise
    for line in _calibration_lines(cal, out):
        typer.echo(line)
    if cal.status != "accepted":
        typer.echo(f"WARNING: {cal.status}", err=True)


def import_calibration_cmd(
    paths: Annotated[
        list[Path],
        typer.Argument(
            help="OpenCV YAML/XML file(s) (stereo_calib: intrinsics.yml extrinsics.yml) or "
            "one VIC-3D cal.xml / project XML / .z3d.",
            show_default=False,
        ),
    ],
    fmt: Annotated[Literal["opencv", "vic3d"], typer.Option("--format", help="opencv or vic3d.")],
    out: opt.CalibrationOutOpt = Path("calibration.nc"),
    overwrite: Overwrite = False,
    length_unit: Annotated[
        str | None,
        typer.Option(help="OpenCV: unit of T (m, mm, cm, um, in, or metres per unit)."),
    ] = None,
    image_size: Annotated[
        tuple[int, int] | None, typer.Option(help="Image width and height (px) if absent.")
    ] = None,
    extrinsics: Annotated[
        Path | None,
        typer.Option("--extrinsics", help="OpenCV: a second file with R and T (extrinsics.yml)."),
    ] = None,
) -> None:
    """Import a calibration made elsewhere (OpenCV FileStorage, VIC-3D) as a jointwear file."""
    from jointwear.dic.calibration._importers import (
        read_opencv_calibration,
        read_vic3d_calibration,
    )
    from jointwear.errors import BadInputError

    inputs = [*paths, *([extrinsics] if extrinsics is not None else [])]
    if fmt == "opencv":
        if length_unit is None:
            raise BadInputError(
                "--length-unit is required for OpenCV files (the unit of T, i.e. of the board "
                "square size used when calibrating: m, mm, cm, um or in, or metres per unit)"
            )
        cal = read_opencv_calibration(inputs, length_unit=length_unit, image_size=image_size)
    elif fmt == "vic3d":
        if length_unit is not None:
            raise typer.BadParameter(
                "--length-unit applies to OpenCV files; a VIC-3D calibration states its "
                "own unit (millimetres)"
            )
        if len(inputs) != 1:
            raise BadInputError(
                f"--format vic3d takes one file (cal.xml, project XML or .z3d), got "
                f"{len(inputs)}: {', '.join(str(p) for p in inputs)}"
            )
        cal = read_vic3d_calibration(inputs[0], image_size=image_size)
    else:
        raise BadInputError(f"--format {fmt!r}: expected 'opencv' or 'vic3d'")
    cal.save(out, inputs=inputs, parameters={"format": fmt, "length_unit": length_unit})
    typer.echo(
        f"imported {fmt} calibration ({cal.left.image_size[0]}x{cal.left.image_size[1]} px, "
        f"baseline {cal.baseline * 1e3:.2f} mm) -> {out}"
    )


def _track_config(bodies: Path, **overrides):
    """Options and bodies of the TOML file with the command's overrides; a bad override is a
    usage error (exit 2) naming its flag."""
    from jointwear.dic.footage._config import read_bodies
    from jointwear.dic.footage._files import with_overrides
    from jointwear.errors import ParameterError

    cfg, specs = read_bodies(bodies)
    try:
        return with_overrides(cfg, **overrides), specs
    except ParameterError as exc:
        flag = "--" + str(exc).split("=")[0].removeprefix("track.").replace("_", "-")
        raise typer.BadParameter(str(exc), param_hint=flag) from None


def _track_lines(ds, cfg, out: Path) -> tuple[list[str], list[str]]:
    """(stdout lines, stderr lines) that summarise a tracking run."""
    import json

    dup = ds.attrs.get("duplicated_frames", "[]")
    lines = [
        f"tracked {ds.attrs['frames_processed']} frames in {ds.attrs.get('wall_time_s', 0):.1f} s; "
        f"duplicated frames: {dup}; dropped frames (time gaps): "
        f"{ds.attrs.get('dropped_frames_estimated', 0)} -> {out}"
    ]
    counts = json.loads(ds.attrs.get("sift_reinitialisations", "{}"))
    errs = []
    if any(counts.values()):
        lines.append(
            "tracking lost and found again from SIFT features (re-initialisations): "
            + ", ".join(f"{k} {v}" for k, v in counts.items())
            + f" (limit {cfg.max_reinit} per body, --max-reinit; frames in "
            "<body>_reinitialised)"
        )
        full = [k for k, v in counts.items() if v >= cfg.max_reinit]
        if full:
            errs.append(
                f"WARNING: {', '.join(full)} reached the re-initialisation limit; later "
                "lost frames are flagged tracking_failed"
            )
    return lines, errs


def track_cmd(
    left: Annotated[
        Path,
        typer.Option(
            "--left",
            help="Left video, image folder, quoted pattern ('images/*_0.tif') or multi-page TIFF.",
        ),
    ],
    bodies: Annotated[
        Path, typer.Option("--bodies", help="TOML file with the regions of interest.")
    ],
    right: Annotated[
        Path | None,
        typer.Option("--right", help="Right footage, as --left (omit for one camera)."),
    ] = None,
    calibration: opt.CalibrationOpt = None,
    out: Annotated[Path, typer.Option("--out", "-o", help="Body motion (.nc).")] = Path(
        "motion.nc"
    ),
    overwrite: Overwrite = False,
    fps: Annotated[float | None, typer.Option(help="Frame rate (1/s) (image sequences).")] = None,
    max_frames: Annotated[int | None, typer.Option(help="Process only the first N frames.")] = None,
    plot: Annotated[
        Path | None, typer.Option(help="Also write the velocity/displacement plot.")
    ] = None,
    workers: Annotated[
        int | None, typer.Option(help="Worker processes for chunks (overrides the TOML).")
    ] = None,
    chunk_size: Annotated[
        int | None, typer.Option(help="Frames per chunk (overrides the TOML).")
    ] = None,
    resume: Annotated[
        bool,
        typer.Option(
            help="Continue the partial result in --out of a run that stopped (same footage, "
            "bodies and options)."
        ),
    ] = False,
    max_epipolar_px: Annotated[
        float | None,
        typer.Option(
            help="Epipolar gate of the stereo matches (px; overrides the TOML's "
            "max_epipolar_px). Raise only for a calibration known to be that far off."
        ),
    ] = None,
    max_reinit: Annotated[
        int | None,
        typer.Option(
            help="Most SIFT re-initialisations per body after lost tracking (0: none; "
            "overrides the TOML)."
        ),
    ] = None,
    scheduler: Scheduler = None,
) -> None:
    """Track the bodies of rig footage: poses, follower velocity, journal out-of-plane motion.

    The result is written after every chunk of frames, so an interrupted run keeps what was
    computed (attribute 'status').
    """
    from jointwear import io
    from jointwear.dic.footage._files import track_files

    if right is None:
        opt.refuse_given(
            ((calibration, "--calibration"), (max_epipolar_px, "--max-epipolar-px")),
            "two cameras (--right); one camera tracks in pixels of the left image",
        )
    io.check_writable(out)
    cfg, specs = _track_config(
        bodies,
        workers=workers,
        chunk_size=chunk_size,
        max_epipolar_px=max_epipolar_px,
        max_reinit=max_reinit,
    )
    ds = track_files(
        left,
        right,
        out,
        bodies=bodies,
        config=cfg,
        specs=specs,
        calibration=calibration,
        plot=plot,
        fps=fps,
        max_frames=max_frames,
        resume=resume,
        scheduler=scheduler,
    )
    lines, errs = _track_lines(ds, cfg, out)
    for line in lines:
        typer.echo(line)
    for line in errs:
        typer.echo(line, err=True)
    if plot is not None:
        typer.echo(f"plot -> {plot}")


def plot_track_cmd(
    motion: Annotated[Path, typer.Argument(help="Output of `jointwear dic track` (.nc).")],
    out: FigureOut = Path("motion.png"),
    overwrite: Overwrite = False,
    reference: Annotated[
        Path | None,
        typer.Option("--overlay", help="File to overlay (ground truth, simulation) (.nc)."),
    ] = None,
) -> None:
    """Plot the follower velocity and the journal's out-of-plane displacement."""
    from jointwear import io
    from jointwear.dic.footage._plot import plot_body_motion

    ds = io.load(motion)
    ref = io.load(reference) if reference is not None else None
    plot_body_motion(ds, reference=ref, path=out)
    typer.echo(f"plot -> {out}")


def register(app: typer.Typer) -> None:
    """Add the stereo commands to ``jointwear dic``."""
    app.command("calibrate")(calibrate_cmd)
    app.command("import-calibration")(import_calibration_cmd)
    app.command("track")(track_cmd)
    app.command("plot-track")(plot_track_cmd)
