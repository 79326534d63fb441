"""``jointwear compare SIM.nc [SIM2.nc] MEAS.nc [...] --out metrics.nc``."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from jointwear._cli import Overwrite
from jointwear.compare import _cli_options as opt
from jointwear.compare._choices import ALIGN_METHOD, ALIGN_METHODS


def compare_cmd(
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
    sim_extra: opt.SimOpt = None,
    meas_extra: Annotated[
        list[Path] | None,
        typer.Option("--meas", help="Further measured file (e.g. the DIC motion record)."),
    ] = None,
    table: Annotated[
        Path | None, typer.Option("--table", help="Also write the metrics table as CSV.")
    ] = None,
    criteria: opt.CriteriaOpt = None,
    cycles: opt.CyclesOpt = None,
    period: opt.PeriodOpt = None,
    method: Annotated[
        str,
        typer.Option("--method", help=f"Motion alignment: {', '.join(ALIGN_METHODS)}."),
    ] = ALIGN_METHOD,
    variables: opt.VariableOpt = None,
    axes: opt.AxisOpt = None,
    ensemble: opt.EnsembleOpt = None,
    verification: opt.VerificationOpt = None,
    allow_other_rig: opt.AllowOtherRigOpt = False,
    strict: opt.StrictOpt = False,
    calibration_check: Annotated[
        bool,
        typer.Option(
            "--calibration-check",
            help="Compare with the data a posterior prediction was calibrated on: every row "
            "labelled 'calibration check, not validation', a pass never counted as validation "
            "(without it such data are refused).",
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
    from jointwear.compare import DEFAULT_AXES
    from jointwear.compare import outcome as oc
    from jointwear.compare.storage import compare_files

    result = compare_files(
        [sim, *(sim_extra or [])],
        [meas, *(meas_extra or [])],
        out,
        table=table,
        criteria=criteria,
        cycles=cycles,
        period_s=period,
        motion_method=method,
        variables=variables,
        axes=axes or DEFAULT_AXES,
        ensemble=ensemble or [],
        verification=verification or [],
        allow_other_rig=allow_other_rig,
        warn=oc.echo_warning,
        calibration_check=calibration_check,
    )
    lines = [oc.origin_line(result), *oc.card_lines(result), *oc.alignment_lines(result)]
    lines += [f"metrics: {out}", *oc.outcome_lines(result)]
    for line in lines:
        typer.echo(line)
    oc.raise_for_outcome(result, strict=strict, where=str(out))


def register(app: typer.Typer) -> None:
    """Make the ``jointwear compare`` group itself the command (no sub-command needed)."""
    app.callback(
        invoke_without_command=True,
        context_settings={"allow_interspersed_args": True},
    )(compare_cmd)
