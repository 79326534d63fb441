"""``jointwear sim cycle``: simulate crank cycles of the four-bar and write the record to netCDF."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from jointwear._cli import NetcdfOut, Overwrite
from jointwear.sim._cli_options import Base, Progress
from jointwear.sim._cycle_file import DEFAULT_CRANK_CYCLES
from jointwear.sim._defaults import DEFAULT_PARAMETER_SET

__all__ = ["register"]


def cycle(
    out: NetcdfOut = Path("cycle.nc"),
    overwrite: Overwrite = False,
    cycles: Annotated[
        float, typer.Option("--cycles", help="Crank cycles to simulate (fractions allowed).")
    ] = DEFAULT_CRANK_CYCLES,
    params: Annotated[
        Path | None,
        typer.Option("--params", help="TOML file overriding the parameter set (SI units)."),
    ] = None,
    base: Base = DEFAULT_PARAMETER_SET,
    wear: Annotated[
        Path | None,
        typer.Option(
            "--wear",
            help="netCDF file with a wear_depth map (z, theta) to simulate the worn bearing.",
        ),
    ] = None,
    wear_cycles: Annotated[
        float | None,
        typer.Option("--wear-cycles", help="Snapshot of the wear map (default: the last)."),
    ] = None,
    progress: Progress = None,
) -> None:
    """Simulate the four-bar with the 3D clearance joint C and write the time record.

    The file holds crank angle, body motions, the journal's offset and tilt in the bearing,
    contact forces, contact mode and penetration over time, with the resolved parameters
    in its provenance. If the run fails, what was computed is written next to --out as
    <name>.partial.nc.
    """
    from jointwear.errors import ParameterError
    from jointwear.progress import progress_bar
    from jointwear.sim._cycle_file import cycle_parameters, simulate_cycles_to_file

    if not cycles > 0:
        raise ParameterError(f"--cycles must be positive, got {cycles}")
    p = cycle_parameters(params, base)
    with progress_bar(f"crank cycles ({p.name})", total=cycles, enabled=progress) as bar:
        task = bar.tasks[0].id
        ds = simulate_cycles_to_file(
            out,
            p,
            cycles=cycles,
            params_file=params,
            wear=wear,
            wear_cycles=wear_cycles,
            progress=lambda fraction: bar.update(task, completed=fraction * cycles),
        )
    if "contact_validity_warning" in ds.attrs:
        typer.echo(f"warning: {ds.attrs['contact_validity_warning']}", err=True)
    typer.echo(
        f"{out}: {cycles:g} cycle(s), {ds.sizes['time']} samples, "
        f"mean contact force {float(ds.contact_force.mean()):.1f} N, "
        f"max penetration {float(ds.penetration.max()) * 1e6:.2f} um"
    )


def register(app: typer.Typer) -> None:
    """Add ``jointwear sim cycle`` to the ``sim`` group."""
    app.command("cycle")(cycle)
