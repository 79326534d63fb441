"""Options shared by ``jointwear compare`` and ``jointwear report``, declared once.

Each is an ``Annotated`` type to put on a command's parameter (``criteria: CriteriaOpt = None``),
so both commands show the same flag with the same help text.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from jointwear.compare._choices import DEFAULT_AXES, MOTION_VARIABLES

__all__ = [
    "AllowOtherRigOpt",
    "AxisOpt",
    "CriteriaOpt",
    "CyclesOpt",
    "EnsembleOpt",
    "PeriodOpt",
    "SimOpt",
    "StrictOpt",
    "VariableOpt",
    "VerificationOpt",
]

SimOpt = Annotated[
    list[Path] | None,
    typer.Option("--sim", help="Simulated wear map and/or motion record (.nc); repeatable."),
]
CriteriaOpt = Annotated[
    Path | None, typer.Option("--criteria", help="TOML file with validation criteria.")
]
CyclesOpt = Annotated[
    float | None,
    typer.Option("--cycles", help="Crank cycles at which to compare the wear maps."),
]
PeriodOpt = Annotated[
    float | None,
    typer.Option(
        "--period", help="Crank period in seconds (when neither record has a crank angle)."
    ),
]
VariableOpt = Annotated[
    list[str] | None,
    typer.Option(
        "--variable",
        help=f"Motion variable to compare (repeatable; default: {', '.join(MOTION_VARIABLES)} "
        "when both sides have them).",
    ),
]
AxisOpt = Annotated[
    list[str] | None,
    typer.Option(
        "--axis",
        help=f"Motion component to compare (repeatable; default {' and '.join(DEFAULT_AXES)}, "
        "the plane of the mechanism).",
    ),
]
EnsembleOpt = Annotated[
    list[Path] | None,
    typer.Option(
        "--ensemble",
        help="Ensemble of simulations (.nc with a 'run' dimension, from jointwear sim "
        "sweep); its spread is the V&V 20 input uncertainty. Repeatable.",
    ),
]
VerificationOpt = Annotated[
    list[Path] | None,
    typer.Option(
        "--verification",
        help="Verification study: a 'jointwear sim verify' study.nc (u_num of each wear "
        "criterion on the measured band, Eça-Hoekstra), or older 1-D refinement data "
        "(GCI, order capped at the formal order).",
    ),
]
AllowOtherRigOpt = Annotated[
    bool,
    typer.Option(
        "--allow-other-rig",
        help="Use a --verification study or an --ensemble whose recorded rig parameters "
        "differ from the simulation's (labelled in the notes); refused by default.",
    ),
]
StrictOpt = Annotated[
    bool,
    typer.Option(
        "--strict",
        help="Also exit 1 when a criterion is not assessed or not comparable, or a "
        "part was not compared (a failed criterion always exits 1).",
    ),
]
