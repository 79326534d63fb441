"""``jointwear sim sweep``: parameter sweeps, ensembles and sensitivity analysis on dask."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from jointwear._cli import Overwrite
from jointwear._cli_dataclass import options_from
from jointwear.sim._cli_options import Base, SweepRun, WearParams, check_lost_runs
from jointwear.sim._defaults import DEFAULT_PARAMETER_SET

__all__ = ["register"]


@options_from("run", SweepRun)
def sweep(
    spec: Annotated[Path, typer.Argument(help="Sweep spec (TOML; see docs/sweeps.md).")],
    out: Annotated[Path, typer.Option("--out", help="Result file (netCDF).")],
    run: SweepRun,
    params: WearParams = None,
    base: Base = DEFAULT_PARAMETER_SET,
    overwrite: Overwrite = False,
) -> None:
    """Run a parameter sweep or ensemble of simulations; each run is one dask task.

    Each finished run is written at once to <out>.parts/, so an interrupted sweep continues
    with --resume; a failing run is recorded with its error and the sweep goes on. For
    method = "sobol" or "morris" the result holds SALib's sensitivity indices.
    """
    import logging

    import numpy as np

    from jointwear.sim.sweep._driver import run_sweep

    # printed below, once (the runs keep their warnings in the record)
    logging.getLogger("jointwear.sim.sweep").addHandler(logging.NullHandler())
    with run.runs("sweep") as runs:
        try:
            ds = run_sweep(spec, out=out, params=params, base=base, **runs)
        except KeyboardInterrupt:
            from jointwear.sim.sweep._store import parts_dir

            n = len(list(parts_dir(out).glob("run-*.npz")))
            typer.echo(
                f"interrupted: {n} finished run(s) are kept in {parts_dir(out)}; "
                "run the same command with --resume to compute the rest",
                err=True,
            )
            raise
    status = np.asarray(ds["status"].values)
    typer.echo(
        f"{out}: {ds.attrs['n_runs']} runs ({ds.attrs['sweep_method']}, "
        f"{ds.attrs['sweep_run']}) on {ds.attrs['executor']}: {ds.attrs['n_ok']} ok, "
        f"{ds.attrs['n_failed']} failed, {ds.attrs['n_not_run']} not run; "
        f"{ds.attrs['runs_computed_now']} computed now, {ds.attrs['runs_resumed']} resumed"
    )
    for i in np.flatnonzero(status == 1)[:5]:
        typer.echo(f"  run {int(i)} failed: {ds['error'].values[i]}", err=True)
    from jointwear.sim import warning_summary

    for line in warning_summary(ds):
        typer.echo(f"warning: {line}", err=True)
    if "sensitivity_sample_warning" in ds.attrs:
        typer.echo(f"warning: {ds.attrs['sensitivity_sample_warning']}", err=True)
    if "sensitivity_not_assessed" in ds.attrs:
        typer.echo(
            f"sensitivity not assessed for: {ds.attrs['sensitivity_not_assessed']}", err=True
        )
    check_lost_runs(ds, f" (see 'error' in {out})")


def register(app: typer.Typer) -> None:
    """Add ``jointwear sim sweep`` to the ``sim`` group."""
    app.command("sweep")(sweep)
