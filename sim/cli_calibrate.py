"""``jointwear sim calibrate`` (Bayesian calibration) and ``jointwear sim predict`` (the posterior
ensemble of real simulations)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from jointwear._cli import Overwrite
from jointwear._cli_dataclass import options_from
from jointwear.sim._cli_options import Base, SweepRun, WearParams, check_lost_runs
from jointwear.sim._defaults import DEFAULT_PARAMETER_SET
from jointwear.sim.calibrate._defaults import PREDICT_SAMPLES

__all__ = ["register"]


@options_from("run", SweepRun)
def calibrate_cmd(
    spec: Annotated[Path, typer.Argument(help="Calibration spec (TOML; see docs/calibration.md).")],
    out: Annotated[Path, typer.Option("--out", help="Posterior file (netCDF).")],
    params: WearParams = None,
    base: Base = DEFAULT_PARAMETER_SET,
    *,
    run: SweepRun,
    verification: Annotated[
        Path | None,
        typer.Option(
            "--verification",
            help="A 'jointwear sim verify' study: u_num of each map quantity on its band "
            "(else the spec's u_num_rel).",
        ),
    ] = None,
    overwrite: Overwrite = False,
) -> None:
    """Calibrate uncertain inputs on measured data: emulator over the prior, posterior by MCMC.

    The training runs (a Latin hypercube over the prior) go through the sweep driver and are
    kept in OUT's folder as <out>.design-<cycles>.nc (--resume reuses them). Refused (exit 3):
    an emulator error above the spec's fraction of the data's u, an unconverged chain, a
    datum outside its posterior predictive interval.
    """
    from jointwear.sim.calibrate import calibrate

    with run.runs("training runs") as runs:
        studies = [verification] if verification else []
        ds = calibrate(spec, out=out, params=params, base=base, verification=studies, **runs)
    typer.echo(f"{out}: posterior of {', '.join(ds['parameter'].values.tolist())}")
    for line in ds.attrs["identifiability"].splitlines():
        typer.echo(f"  {line}")
    typer.echo(
        f"  sampler: {ds.attrs['sampler']}; acceptance {ds.attrs['acceptance_fraction']:.2f}"
    )
    for i, label in enumerate(ds["datum"].values):
        typer.echo(
            f"  {label}: measured {float(ds['measured'][i]):.4g}, predictive "
            f"{float(ds['ppc_lo'][i]):.4g} .. {float(ds['ppc_hi'][i]):.4g}"
        )


@options_from("run", SweepRun)
def predict_cmd(
    posterior: Annotated[Path, typer.Argument(help="Posterior file of 'jointwear sim calibrate'.")],
    cycles: Annotated[float, typer.Option("--cycles", help="Crank cycles to simulate.")],
    out: Annotated[Path, typer.Option("--out", help="Prediction ensemble (netCDF).")],
    samples: Annotated[
        int, typer.Option("--samples", min=2, help="Posterior samples simulated.")
    ] = PREDICT_SAMPLES,
    *,
    run: SweepRun,
    overwrite: Overwrite = False,
) -> None:
    """Run the simulator at posterior samples: the ensemble 'jointwear compare' takes as the
    simulation (mean map compared, spread = input uncertainty)."""
    from jointwear.sim.calibrate import predict

    with run.runs("prediction") as runs:
        ds = predict(posterior, cycles=cycles, out=out, samples=samples, **runs)
    typer.echo(
        f"{out}: {ds.attrs['n_runs']} runs at posterior samples, {cycles:g} cycles: "
        f"{ds.attrs['n_ok']} ok, {ds.attrs['n_failed']} failed, {ds.attrs['n_not_run']} not run"
    )
    check_lost_runs(ds, f" (see 'error' in {out})")


def register(app: typer.Typer) -> None:
    """Add ``jointwear sim calibrate`` and ``jointwear sim predict`` to the ``sim`` group."""
    app.command("calibrate")(calibrate_cmd)
    app.command("predict")(predict_cmd)
