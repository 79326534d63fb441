"""``jointwear compare SIM.nc [SIM2.nc] MEAS.nc [...] --out metrics.nc``."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from jointwear._cli import Overwrite


def register(app: typer.Typer) -> None:
    """Make the ``jointwear compare`` group itself the command (no sub-command needed)."""

    @app.callback(
        invoke_without_command=True,
        context_settings={"allow_interspersed_args": True},
    )
    def compare_files(
        ctx: typer.Context,
        sim: Annotated[
            Path, typer.Argument(help="Simulated data (.nc): wear map and/or motion record.")
        ],
        meas: Annotated[
            Path, typer.Argument(help="Measured data (.nc): wear map (metrology) or motion (DIC).")
        ],
        out: Annotated[
            Path,
            typer.Option("--out", "-o", help="netCDF of aligned fields, differences, metrics."),
        ] = Path("metrics.nc"),
        overwrite: Overwrite = False,
        sim_extra: Annotated[
            list[Path] | None,
            typer.Option("--sim", help="Further simulated file (e.g. the motion record)."),
        ] = None,
        meas_extra: Annotated[
            list[Path] | None,
            typer.Option("--meas", help="Further measured file (e.g. the DIC motion record)."),
        ] = None,
        table: Annotated[
            Path | None, typer.Option("--table", help="Also write the metrics table as CSV.")
        ] = None,
        criteria: Annotated[
            Path | None, typer.Option("--criteria", help="TOML file with validation criteria.")
        ] = None,
        cycles: Annotated[
            float | None,
            typer.Option("--cycles", help="Crank cycles at which to compare the wear maps."),
        ] = None,
        period: Annotated[
            float | None,
            typer.Option(
                "--period", help="Crank period in seconds (when neither record has a crank angle)."
            ),
        ] = None,
        method: Annotated[
            str,
            typer.Option(
                "--method", help="Motion alignment: auto, crank_angle, cross_correlation."
            ),
        ] = "auto",
        variables: Annotated[
            list[str] | None,
            typer.Option(
                "--variable",
                help="Motion variable to compare (repeatable; default: follower_velocity, "
                "journal_offset, journal_displacement, contact_force when both sides have them).",
            ),
        ] = None,
        axes: Annotated[
            list[str] | None,
            typer.Option(
                "--axis",
                help="Motion component to compare (repeatable; default x and y, the plane of "
                "the mechanism).",
            ),
        ] = None,
        ensemble: Annotated[
            list[Path] | None,
            typer.Option(
                "--ensemble",
                help="Ensemble of simulations (.nc with a 'run' dimension, from jointwear sim "
                "sweep); its spread is the V&V 20 input uncertainty. Repeatable.",
            ),
        ] = None,
        verification: Annotated[
            list[Path] | None,
            typer.Option(
                "--verification",
                help="Verification study: a 'jointwear sim verify' study.nc (u_num of each wear "
                "criterion on the measured band, Eça-Hoekstra), or older 1-D refinement data "
                "(GCI, order capped at the formal order).",
            ),
        ] = None,
        strict: Annotated[
            bool,
            typer.Option(
                "--strict",
                help="Also exit 1 when a criterion is not assessed or not comparable, or a "
                "part was not compared (a failed criterion always exits 1).",
            ),
        ] = False,
    ) -> None:
        """Compare simulation and measurement (wear maps and/or motion, detected from variables).

        Writes the aligned fields, their differences and every metric (units and definition in
        the attributes) to OUT and prints the decision card. Each criterion is PASS, FAIL, NOT
        ASSESSED (an uncertainty it needs is unknown) or NOT COMPARABLE (the data do not cover
        it). Exit code 1 when a criterion fails; with --strict also when one is undecided.
        """
        if ctx.invoked_subcommand is not None:
            return
        from jointwear import io
        from jointwear.compare import compare, load_criteria, save_comparison
        from jointwear.compare.outcome import (
            card_lines,
            origin_line,
            outcome_lines,
            raise_for_outcome,
        )

        io.check_writable(out)
        crit = load_criteria(criteria)
        sim_paths = [sim, *(sim_extra or [])]
        meas_paths = [meas, *(meas_extra or [])]
        from jointwear.compare.outcome import echo_warning
        from jointwear.external import load_for_comparison

        sims = [load_for_comparison(p, role="simulated", warn=echo_warning) for p in sim_paths]
        meass = [load_for_comparison(p, role="measured", warn=echo_warning) for p in meas_paths]
        ens = [io.load(p) for p in ensemble or []]
        vers = [io.load(p, validate=False) for p in verification or []]
        from jointwear.compare.ensemble import as_ensemble

        result = compare(
            sims,
            meass,
            criteria=crit,
            cycles=cycles,
            period_s=period,
            motion_method=method,
            variables=variables or None,
            axes=axes or ("x", "y"),
            ensemble=as_ensemble(ens, [p.name for p in ensemble or []]) if ens else None,
            verification=vers or None,
        )
        save_comparison(
            result,
            out,
            inputs=[*sim_paths, *meas_paths, *(ensemble or []), *(verification or [])],
            parents=[*sims, *meass],
        )
        if table is not None:
            with io.atomic_path(table) as tmp:
                result.metrics.to_csv(tmp, index=False, float_format="%.6g")
        typer.echo(origin_line(result))
        for line in card_lines(result):
            typer.echo(line)
        if result.wear is not None:
            typer.echo(f"wear maps: {result.wear.attrs['interpolation']}")
        if result.motion is not None:
            a = result.motion.attrs
            typer.echo(
                f"motion aligned by {a['alignment_method'].replace('_', ' ')}: shift "
                f"{a['time_shift_s'] * 1e3:+.2f} ms ({a['time_shift_deg']:+.1f} degree of crank "
                f"angle) over {a['n_cycles']:g} cycle(s)"
            )
        for note in result.notes:
            typer.echo(f"note: {note}")
        typer.echo(f"metrics: {out}")
        for line in outcome_lines(result):
            typer.echo(line)
        raise_for_outcome(result, strict=strict, where=str(out))
