"""Option types shared by the ``jointwear sim`` commands (declared once, one help text each),
and the check that closes the commands that run sweeps of dask tasks."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any

import typer

from jointwear._cli import Scheduler
from jointwear.sim._defaults import DEFAULT_PARAMETER_SET

__all__ = [
    "Base",
    "WearParams",
    "Progress",
    "Scheduler",
    "SweepRun",
    "check_executor",
    "check_lost_runs",
]

#: The parameter sets of the registered mechanisms, as ``--base`` lists them: written out, so
#: that ``jointwear --help`` need not import the mechanism registry and the parameter sets
#: (17-20 ms); ``tests/sim/test_mechanisms.py`` holds it equal to :func:`base_sets` of
#: ``jointwear.sim.mechanisms.MECHANISMS``.
BASE_SETS = "zhang2023 (four-bar), slider_crank (slider-crank)"


def base_sets(mechanisms: Any) -> str:
    """``--base``'s list of parameter sets: each mechanism's set and title, in table order."""
    return ", ".join(f"{m.parameter_set} ({m.title})" for m in mechanisms.values())


Base = Annotated[
    str,
    typer.Option(
        "--base",
        help="Named parameter set the --params overrides apply to, which chooses the "
        f"mechanism: {BASE_SETS}; default {DEFAULT_PARAMETER_SET}.",
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


def check_executor(workers: int | None, scheduler: str | None) -> None:
    """Refuse ``--workers`` (local processes) together with ``--scheduler`` (a cluster)."""
    if scheduler is not None and workers is not None:
        from jointwear.errors import BadInputError

        raise BadInputError("give --workers or --scheduler, not both")


@dataclass(frozen=True)
class SweepRun:
    """Where and how a command's sweep of dask tasks runs: the options ``--workers``,
    ``--scheduler``, ``--resume`` and ``--progress/--no-progress`` as given, declared once for
    every command that runs one (``@options_from("run", SweepRun)`` puts them where the
    command's parameter ``run: SweepRun`` stands)."""

    workers: Annotated[
        int | None,
        typer.Option(
            "--workers",
            help="Local dask worker processes, one thread each (default: one per core; "
            "0 = in this process, no dask).",
        ),
    ] = None
    scheduler: Scheduler = None  # shared with other groups' commands (jointwear._cli)
    resume: Annotated[
        bool,
        typer.Option(
            "--resume", help="Continue an interrupted run: compute only the missing runs."
        ),
    ] = False
    progress: Progress = None

    @contextmanager
    def runs(self, what: str) -> Iterator[dict[str, Any]]:
        """Refuses ``--workers`` with ``--scheduler`` (:func:`check_executor`), then, inside a
        progress bar labelled ``what`` (``--progress``), yields the keywords the library's
        sweep functions (``run_sweep``, ``calibrate``, ``predict``, ``verify_wear``) take:
        ``workers``, ``scheduler``, ``resume`` and ``on_progress`` (the bar's run counter)."""
        from jointwear.progress import progress_bar, run_counter

        check_executor(self.workers, self.scheduler)
        with progress_bar(what, total=None, enabled=self.progress) as bar:
            yield {
                "workers": self.workers,
                "scheduler": self.scheduler,
                "resume": self.resume,
                "on_progress": run_counter(bar, what),
            }


def check_lost_runs(ds: Any, where: str = "") -> None:
    """Raise a SimulationError when the cluster lost runs of ``ds`` (``n_not_run``): their
    parts are kept, and ``--resume`` computes them; ``where`` tells where to read why."""
    if ds.attrs["n_not_run"]:
        from jointwear.errors import SimulationError

        raise SimulationError(
            f"{ds.attrs['n_not_run']} run(s) were lost by the cluster{where}; their parts are "
            "kept: run the same command with --resume to compute them"
        )
