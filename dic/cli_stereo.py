"""``jointwear dic calibrate | import-calibration | track | plot-track``: stereo rig commands."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Literal

import typer

from jointwear._cli import Overwrite


def _image_list(path: Path, what: str) -> list[Path]:
    """Board images of one camera: a folder, or a pattern such as 'cal/*_0.tif'."""
    from jointwear.dic._video import list_image_sequence

    return list_image_sequence(path, what=what)[0]


def _video_frames(path: Path, every: int, what: str) -> list:
    from jointwear.dic._video import open_frames

    src = open_frames(path, what=what)
    return [img for i, _, img in src.frames() if i % every == 0]


def register(app: typer.Typer) -> None:
    """Add the stereo commands to ``jointwear dic``."""

    @app.command("calibrate")
    def calibrate(
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
        out: Annotated[Path, typer.Option("--out", "-o", help="Calibration file (.nc).")] = Path(
            "calibration.nc"
        ),
        overwrite: Overwrite = False,
        board: Annotated[
            Literal["chessboard", "charuco"], typer.Option(help="chessboard or charuco.")
        ] = "chessboard",
        squares: Annotated[
            tuple[int, int], typer.Option(help="Squares along x and y (not inner corners).")
        ] = (10, 7),
        square_mm: Annotated[float, typer.Option(help="Square side (mm).")] = 10.0,
        marker_mm: Annotated[float, typer.Option(help="ChArUco marker side (mm).")] = 7.5,
        dictionary: Annotated[str, typer.Option(help="ChArUco ArUco dictionary.")] = "DICT_5X5_100",
        world_view: Annotated[
            int | None,
            typer.Option(help="Index of the view whose board pose becomes the world frame."),
        ] = None,
        min_views: Annotated[int, typer.Option(min=1, help="Fewest usable views.")] = 6,
        every: Annotated[int, typer.Option(min=1, help="Videos: use every N-th frame.")] = 10,
    ) -> None:
        """Calibrate a stereo pair from simultaneous views of a chessboard or ChArUco board."""
        from jointwear import io
        from jointwear.dic._calib_board import CalibrationBoard, calibrate_stereo
        from jointwear.dic._video import is_image_sequence

        io.check_writable(out)
        b = CalibrationBoard(
            board, squares[0], squares[1], square_mm * 1e-3, marker_mm * 1e-3, dictionary
        )
        if is_image_sequence(left):  # a folder, or a pattern like 'cal/*_0.tif'
            lefts, rights = (
                _image_list(left, "left calibration"),
                _image_list(right, "right calibration"),
            )
        else:
            lefts = _video_frames(left, every, "left calibration video")
            rights = _video_frames(right, every, "right calibration video")
        cal = calibrate_stereo(lefts, rights, b, min_views=min_views, world_view=world_view)
        cal.save(
            out, inputs=[left, right], parameters={"board": b.__dict__, "world_view": world_view}
        )
        typer.echo(
            f"calibrated from {cal.views_used} views ({cal.views_rejected} rejected): RMS "
            f"{cal.rms:.3f} px, baseline {cal.baseline * 1e3:.2f} mm, focal "
            f"{cal.left.focal[0]:.1f}/{cal.right.focal[0]:.1f} px -> {out}"
        )
        for reason in cal.rejected:
            typer.echo(f"  rejected {reason}")

    @app.command("import-calibration")
    def import_calibration(
        paths: Annotated[
            list[Path],
            typer.Argument(
                help="OpenCV YAML/XML file(s) (stereo_calib: intrinsics.yml extrinsics.yml) or "
                "one VIC-3D cal.xml / project XML / .z3d.",
                show_default=False,
            ),
        ],
        fmt: Annotated[
            Literal["opencv", "vic3d"], typer.Option("--format", help="opencv or vic3d.")
        ],
        out: Annotated[Path, typer.Option("--out", "-o", help="Calibration file (.nc).")] = Path(
            "calibration.nc"
        ),
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
            typer.Option(
                "--extrinsics", help="OpenCV: a second file with R and T (extrinsics.yml)."
            ),
        ] = None,
    ) -> None:
        """Import a calibration made elsewhere (OpenCV FileStorage, VIC-3D) as a jointwear file."""
        from jointwear.dic._calib import read_opencv_calibration, read_vic3d_calibration
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

    @app.command("track")
    def track(
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
        calibration: Annotated[
            Path | None, typer.Option("--calibration", "-c", help="Stereo calibration (.nc).")
        ] = None,
        out: Annotated[Path, typer.Option("--out", "-o", help="Body motion (.nc).")] = Path(
            "motion.nc"
        ),
        overwrite: Overwrite = False,
        fps: Annotated[
            float | None, typer.Option(help="Frame rate (1/s) (image sequences).")
        ] = None,
        max_frames: Annotated[
            int | None, typer.Option(help="Process only the first N frames.")
        ] = None,
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
    ) -> None:
        """Track the bodies of rig footage: poses, follower velocity, journal out-of-plane motion.

        The result is written after every chunk of frames, so an interrupted run keeps what was
        computed (attribute 'status').
        """
        from jointwear import io
        from jointwear.dic._calib import read_calibration
        from jointwear.dic._footage import read_bodies, track_footage

        io.check_writable(out)
        cfg, specs = read_bodies(bodies)
        if workers is not None or chunk_size is not None:
            import dataclasses

            cfg = dataclasses.replace(
                cfg,
                workers=cfg.workers if workers is None else workers,
                chunk_size=cfg.chunk_size if chunk_size is None else chunk_size,
            )
        cal = read_calibration(calibration) if calibration is not None else None
        inputs = [p for p in (left, right, bodies, calibration) if p is not None]
        ds = track_footage(
            left,
            right,
            bodies=specs,
            calibration=cal,
            config=cfg,
            fps=fps,
            max_frames=max_frames,
            out=out,
            progress=True,
            inputs=tuple(inputs),
            resume=resume,
        )
        dup = ds.attrs.get("duplicated_frames", "[]")
        typer.echo(
            f"tracked {ds.attrs['frames_processed']} frames in {ds.attrs.get('wall_time_s', 0):.1f} s; "
            f"duplicated frames: {dup}; dropped frames (time gaps): "
            f"{ds.attrs.get('dropped_frames_estimated', 0)} -> {out}"
        )
        if plot is not None:
            from jointwear.dic._footage_plot import plot_body_motion

            plot_body_motion(ds, path=plot)
            typer.echo(f"plot -> {plot}")

    @app.command("plot-track")
    def plot_track(
        motion: Annotated[Path, typer.Argument(help="Output of `jointwear dic track` (.nc).")],
        out: Annotated[Path, typer.Option("--out", "-o", help="Figure (.png/.svg/.pdf).")] = Path(
            "motion.png"
        ),
        overwrite: Overwrite = False,
        reference: Annotated[
            Path | None,
            typer.Option("--overlay", help="File to overlay (ground truth, simulation) (.nc)."),
        ] = None,
    ) -> None:
        """Plot the follower velocity and the journal's out-of-plane displacement."""
        from jointwear import io
        from jointwear.dic._footage_plot import plot_body_motion

        ds = io.load(motion)
        ref = io.load(reference) if reference is not None else None
        plot_body_motion(ds, reference=ref, path=out)
        typer.echo(f"plot -> {out}")
