"""Options shared by the ``jointwear dic`` commands, declared once; the correlation options'
defaults are the library's (:class:`jointwear.dic.CorrelationParams`), so the CLI and the
library agree."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from jointwear._cli import NetcdfOut
from jointwear._cli_dataclass import Opt
from jointwear.dic.subset._params import MIN_STEP, MIN_SUBSET

__all__ = [
    "CORRELATION",
    "AllowEmptyOpt",
    "CalibrationOpt",
    "CalibrationOutOpt",
    "FpsOpt",
    "OriginOpt",
    "OutOpt",
    "PlotOpt",
    "PointsOpt",
    "refuse_given",
]

#: The subset-correlation options of every dic command, as fields of
#: :class:`~jointwear.dic.CorrelationParams` or :class:`~jointwear.dic.FieldParams` (which name
#: them alike): their defaults are the dataclass's, and a value below a limit is a usage error
#: naming the flag (an even subset is refused by the library with the odd size to use).
CORRELATION = (
    Opt("subset_size", "--subset", help="Subset size (pixels), odd.", min=MIN_SUBSET),
    Opt("step", help="Grid step (pixels).", min=MIN_STEP),
    Opt("zncc_min", help="Flag matches below this ZNCC."),
    Opt("search_radius", help="Seed search half-width (pixels)."),
    Opt("threads", help="numba threads (0: auto).", min=0),
    Opt(
        "u_outlier_factor",
        help="Flag matches whose uncertainty exceeds this multiple of the image's median (0: off).",
        min=0,
    ),
    Opt(
        "neighbour_outlier_factor",
        help="Flag matches further from their grid neighbours than this multiple of the "
        "image's median uncertainty (0: off).",
        min=0,
    ),
)
OutOpt = NetcdfOut
CalibrationOpt = Annotated[
    Path | None, typer.Option("--calibration", "-c", help="Stereo calibration (.nc).")
]
CalibrationOutOpt = Annotated[Path, typer.Option("--out", "-o", help="Calibration file (.nc).")]
PointsOpt = Annotated[
    Path | None,
    typer.Option(
        "--points",
        help="Text file of subset centres 'x, y' (pixels, reference image, one per line) "
        "instead of a grid over --roi.",
    ),
]
PlotOpt = Annotated[
    Path | None,
    typer.Option("--plot", help="Also write a quick-look figure of the last image (png)."),
]
AllowEmptyOpt = Annotated[
    bool,
    typer.Option(
        "--allow-empty",
        help="Exit 0 even when an image has no valid point (otherwise exit 1).",
    ),
]
OriginOpt = Annotated[
    str, typer.Option("--origin", help="What the images are: measured or synthetic.")
]
FpsOpt = Annotated[
    float | None, typer.Option("--fps", help="Frames per second (omit for still images).")
]


def refuse_given(given, applies_to: str) -> None:
    """Usage error (exit 2) naming the first option of ``given`` (``(value, flag)`` pairs)
    that was given (not None): it applies to ``applies_to`` only."""
    for value, flag in given:
        if value is not None:
            raise typer.BadParameter(f"{flag} applies to {applies_to}")
