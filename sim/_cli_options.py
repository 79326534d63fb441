"""Option types shared by the ``jointwear sim`` commands (declared once, one help text each)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from jointwear.sim.parameters import DEFAULT_PARAMETER_SET

__all__ = ["Base", "WearParams", "Progress", "Workers", "Scheduler", "Resume"]

Base = Annotated[
    str,
    typer.Option(
        "--base",
        help="Named parameter set the --params overrides apply to: the four-bar's "
        f"{DEFAULT_PARAMETER_SET} or slider_crank.",
    ),
]
"""``--base``: the named parameter set under ``--params`` (default ``DEFAULT_PARAMETER_SET``)."""

WearParams = Annotated[
    Path | None,
    typer.Option(
        "--params",
        help="The rig: TOML file of simulator parameters (SI units) and an optional \\[wear] "
        "table (kw, scheme, dn, tol, ...).",
    ),
]
"""``--params`` of the commands that run wear simulations."""

Progress = Annotated[
    bool | None,
    typer.Option("--progress/--no-progress", help="Progress bar (default: on a terminal)."),
]
"""``--progress/--no-progress``: None shows the bar on a terminal only."""

#: Options of the commands that run sweeps of dask tasks (sim sweep, sim verify).
Workers = Annotated[
    int | None,
    typer.Option(
        "--workers",
        help="Local dask worker processes, one thread each (default: one per core; "
        "0 = in this process, no dask).",
    ),
]
Scheduler = Annotated[
    str | None,
    typer.Option("--scheduler", help="Address of a running dask scheduler, e.g. tcp://host:8786."),
]
Resume = Annotated[
    bool,
    typer.Option("--resume", help="Continue an interrupted run: compute only the missing runs."),
]
