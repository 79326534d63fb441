"""Options shared by the ``jointwear dic`` commands, declared once; their defaults are the
library's (:class:`jointwear.dic.CorrelationParams`), so the CLI and the library agree."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from jointwear._cli import NetcdfOut
from jointwear.dic.subset._params import MIN_STEP, MIN_SUBSET, CorrelationParams

__all__ = [
    "AllowEmptyOpt",
    "CalibrationOpt",
    "CalibrationOutOpt",
    "DEFAULTS",
    "FpsOpt",
    "OriginOpt",
    "OutOpt",
    "PlotOpt",
    "PointsOpt",
    "SearchRadiusOpt",
    "StepOpt",
    "SubsetOpt",
    "ThreadsOpt",
    "ZnccMinOpt",
    "correlation_keywords",
    "refuse_given",
]

#: the library's correlation defaults (the options below show them)
DEFAULTS = CorrelationParams()

# the limits are the library's (a value below them is a usage error naming the flag; an even
# subset is refused by CorrelationParams with the odd size to use)
SubsetOpt = Annotated[
    int, typer.Option("--subset", min=MIN_SUBSET, help="Subset size (pixels), odd.")
]
StepOpt = Annotated[int, typer.Option("--step", min=MIN_STEP, help="Grid step (pixels).")]
ZnccMinOpt = Annotated[float, typer.Option("--zncc-min", help="Flag matches below this ZNCC.")]
SearchRadiusOpt = Annotated[
    int, typer.Option("--search-radius", help="Seed search half-width (pixels).")
]
ThreadsOpt = Annotated[int, typer.Option("--threads", min=0, help="numba threads (0: auto).")]
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


def correlation_keywords(
    subset: int, step: int, zncc_min: float, search_radius: int, threads: int
) -> dict[str, int | float]:
    """The options every subset-DIC command shares, as the library's keywords: the one place
    that maps the CLI's names onto :class:`~jointwear.dic.CorrelationParams` fields (``--subset``
    is ``subset_size``)."""
    return {
        "subset_size": subset,
        "step": step,
        "zncc_min": zncc_min,
        "search_radius": search_radius,
        "threads": threads,
    }
