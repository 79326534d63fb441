"""``jointwear sim verify``: the numerical uncertainty of a wear run (replicates, ΔN, grid)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from jointwear._cli import Overwrite
from jointwear._cli_dataclass import options_from
from jointwear.sim._cli_options import SweepRun, check_lost_runs
from jointwear.sim._defaults import DEFAULT_PARAMETER_SET
from jointwear.sim.sweep._verify_spec import default_study

__all__ = ["register"]


@options_from("run", SweepRun)
def verify(
    out: Annotated[Path, typer.Option("--out", help="Study file (netCDF).")],
    spec: Annotated[
        Path | None,
        typer.Argument(
            help="Study spec (TOML with a \\[verify] table; see docs/sim-wear.md). Without "
            f"it: the default study ({default_study()})."
        ),
    ] = None,
    cycles: Annotated[
        float | None,
        typer.Option("--cycles", help="Wear cycles of every run (overrides the spec)."),
    ] = None,
    params: Annotated[
        Path | None,
        typer.Option(
            "--params",
            help="The rig (TOML, as for 'sim wear', with an optional \\[wear] table); "
            f"default the {DEFAULT_PARAMETER_SET} set.",
        ),
    ] = None,
    seed: Annotated[
        int | None,
        typer.Option(
            "--seed",
            min=0,
            help="Draw the replicates' start phases from this seed (default: phases 0, 1, "
            "2, ... cycles, or the spec's phases); a second seed measures how much u_num "
            "depends on them.",
        ),
    ] = None,
    *,
    run: SweepRun,
    band_mm: Annotated[
        str | None,
        typer.Option(
            "--band-mm",
            help="Axial band LO,HI [mm] (e.g. what the measurement covers): adds the "
            "maximum depth, volume and cylindricity within it as quantities.",
        ),
    ] = None,
    overwrite: Overwrite = False,
) -> None:
    """Estimate u_num of a wear run: replicates at >= 4 update intervals dN and a grid run.

    The runs are one sweep of dask tasks (resumable with --resume); the study file holds
    every run's values and final wear map and, per quantity, the Eça-Hoekstra fit and
    u_num = sqrt(u_stat^2 + u_refinement^2 + u_grid^2) as a standard uncertainty (k = 1).
    """
    from jointwear.errors import BadInputError
    from jointwear.sim.sweep._verify import verify_wear
    from jointwear.summary import describe_study

    band = None
    if band_mm is not None:
        try:
            lo, hi = (1e-3 * float(v) for v in band_mm.split(","))
        except ValueError:
            raise BadInputError(f"--band-mm {band_mm!r}: expected LO,HI in mm, e.g. -6,6") from None
        band = (lo, hi)
    if spec is None and cycles is None:
        raise BadInputError("the default study needs --cycles N (or give a SPEC.toml)")
    with run.runs("verify") as runs:
        ds = verify_wear(params, cycles=cycles, spec=spec, seed=seed, band=band, out=out, **runs)
    typer.echo(
        f"{out}: {ds.attrs['n_runs']} runs on {ds.attrs['executor']}: {ds.attrs['n_ok']} ok, "
        f"{ds.attrs['n_failed']} failed, {ds.attrs['n_not_run']} not run"
    )
    typer.echo(describe_study(ds))
    check_lost_runs(ds)


def register(app: typer.Typer) -> None:
    """Add ``jointwear sim verify`` to the ``sim`` group."""
    app.command("verify")(verify)
