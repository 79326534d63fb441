"""``jointwear sim cycle``: simulate crank cycles of the four-bar and write the record to netCDF."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from jointwear._cli import Overwrite
from jointwear.sim._cli_options import Base, Progress
from jointwear.sim.parameters import DEFAULT_PARAMETER_SET

__all__ = ["register"]


def register(app: typer.Typer) -> None:
    """Add ``jointwear sim cycle`` to the ``sim`` group."""

    @app.command("cycle")
    def cycle(
        out: Annotated[Path, typer.Option("--out", help="Output netCDF file.")] = Path("cycle.nc"),
        overwrite: Overwrite = False,
        cycles: Annotated[
            float, typer.Option("--cycles", help="Crank cycles to simulate (fractions allowed).")
        ] = 1.0,
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
        from jointwear import io
        from jointwear._version import source_attribute
        from jointwear.errors import BadInputError, ParameterError, SimulationError
        from jointwear.progress import progress_bar
        from jointwear.sim.dynamics import run_cycles
        from jointwear.sim.parameters import PARAMETER_SETS, load_parameters

        if not cycles > 0:
            raise ParameterError(f"--cycles must be positive, got {cycles}")
        try:
            p = load_parameters(params, base=base) if params is not None else PARAMETER_SETS[base]
        except KeyError as exc:
            if isinstance(exc, ParameterError):
                raise
            raise BadInputError(f"--base: {exc.args[0]}") from None
        io.check_writable(out)
        source = source_attribute("sim.dynamics")
        inputs = [params] if params is not None else []
        depth = None
        if wear is not None:
            from jointwear.sim.dynamics import wear_depth_on_grid

            worn = io.load(wear, validate=False)
            if "wear_depth" not in worn:
                raise BadInputError(f"--wear '{wear}' has no 'wear_depth' variable")
            try:
                depth = wear_depth_on_grid(worn["wear_depth"], p, cycles=wear_cycles)
            except BadInputError as exc:
                raise BadInputError(f"--wear '{wear}': {exc}") from None
            inputs.append(wear)
        with progress_bar(f"crank cycles ({p.name})", total=cycles, enabled=progress) as bar:
            task = bar.tasks[0].id

            def report(fraction: float) -> None:
                bar.update(task, completed=fraction * cycles)

            try:
                result = run_cycles(p, cycles=cycles, wear_depth=depth, progress=report)
            except SimulationError as exc:
                if exc.partial is not None:
                    partial = out.with_name(out.stem + ".partial.nc")
                    io.save(exc.partial, partial, inputs=inputs, parameters=p, source=source)
                    raise SimulationError(
                        f"{exc} (partial record written to '{partial}')", partial=exc.partial
                    ) from None
                raise
        io.save(result.dataset, out, inputs=inputs, parameters=p, source=source)
        if "contact_validity_warning" in result.dataset.attrs:
            typer.echo(f"warning: {result.dataset.attrs['contact_validity_warning']}", err=True)
        ds = result.dataset
        typer.echo(
            f"{out}: {cycles:g} cycle(s), {ds.sizes['time']} samples, "
            f"mean contact force {float(ds.contact_force.mean()):.1f} N, "
            f"max penetration {float(ds.penetration.max()) * 1e6:.2f} um"
        )
