"""``jointwear datasets rig --out DIR``: render the virtual stereo rig with ground truth."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Literal

import typer

from jointwear._cli import Overwrite
from jointwear._cli_dataclass import Opt, options_from
from jointwear.datasets._rig_config import DEFAULT_CODEC, RigConfig

#: the library's defaults (every option's default is read from them)
_C = RigConfig
_BOARD = (
    f"{_C.board_squares[0]} x {_C.board_squares[1]} squares of {_C.board_square_size * 1e3:g} mm, "
    f"{_C.board_marker_size * 1e3:g} mm {_C.board_dictionary} markers"
)


@options_from(
    "cfg",
    RigConfig,
    "duration",
    "fps",
    "width",
    "height",
    Opt("z_amplitude", unit="mm"),
    Opt("noise_sigma", "--noise"),
    Opt("blur_sigma_px", "--blur"),
    "exposure",
    Opt("drop_frames", "--drop"),
    Opt("duplicate_frames", "--duplicate"),
    "seed",
    Opt("board_kind", "--board", help=f"Calibration board: chessboard, or charuco ({_BOARD})."),
    "board_legacy",
)
def rig(
    out: Annotated[Path, typer.Option("--out", "-o", help="Output folder.")],
    overwrite: Overwrite = False,
    cfg: RigConfig = _C(),
    codec: Annotated[
        Literal["ffv1", "png", "grey", "mjpg", "mp4v"],
        typer.Option(help="ffv1, png or grey (lossless), mjpg or mp4v (lossy)."),
    ] = DEFAULT_CODEC,
    video: Annotated[bool, typer.Option(help="Write videos.")] = True,
    images: Annotated[bool, typer.Option(help="Write image folders.")] = True,
    motion: Annotated[
        Path | None,
        typer.Option(
            help="Motion from data (.nc, e.g. simulator output with crank_angle and "
            "follower_position) instead of the analytic one."
        ),
    ] = None,
) -> None:
    """Render what the rig's two cameras would record, board images and the ground truth."""
    from jointwear.datasets.rig import generate_rig

    motion_ds = None
    if motion is not None:
        from jointwear import io

        motion_ds = io.load(motion)
    from jointwear.progress import progress_bar

    # frames of both cameras; the calibration views join the total when they start
    offsets = {"left": 0, "right": cfg.n_frames, "calibration": 2 * cfg.n_frames}
    with progress_bar("rendering the rig", total=2 * cfg.n_frames) as bar:
        task = bar.tasks[0].id

        def advance(stage: str, done: int, of: int) -> None:
            bar.update(
                task,
                completed=offsets[stage] + done,
                total=offsets[stage] + of if stage == "calibration" else None,
                description=f"rendering {stage}",
            )

        written = generate_rig(
            out,
            cfg,
            video=video,
            images=images,
            codec=codec,
            motion=motion_ds,
            progress=advance,
        )
    for key, path in written.items():
        typer.echo(f"{key}: {path}")


def register(app: typer.Typer) -> None:
    """Add ``rig`` to ``jointwear datasets``."""
    app.command("rig")(rig)
