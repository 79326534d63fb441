"""``jointwear report --sim ... --metrology ... --dic ... --out report.html``."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from jointwear._cli import Overwrite
from jointwear.compare import (
    AxisOpt,
    CriteriaOpt,
    CyclesOpt,
    EnsembleOpt,
    PeriodOpt,
    SimOpt,
    StrictOpt,
    VariableOpt,
    VerificationOpt,
)


def report_cmd(
    ctx: typer.Context,
    out: Annotated[
        Path,
        typer.Option("--out", "-o", help="HTML report to write (.pdf: the PDF version only)."),
    ] = Path("report.html"),
    overwrite: Overwrite = False,
    sim: SimOpt = None,
    metrology: Annotated[
        list[Path] | None,
        typer.Option("--metrology", help="Measured wear map (.nc from jointwear metrology)."),
    ] = None,
    dic: Annotated[
        list[Path] | None,
        typer.Option("--dic", help="Measured motion (.nc from jointwear dic)."),
    ] = None,
    reported: Annotated[
        list[Path] | None,
        typer.Option(
            "--reported",
            help="Reported measurements (.nc from jointwear import reported); repeatable.",
        ),
    ] = None,
    comparison: Annotated[
        Path | None,
        typer.Option("--comparison", help="A metrics.nc from jointwear compare instead."),
    ] = None,
    verification: VerificationOpt = None,
    criteria: CriteriaOpt = None,
    pdf: Annotated[
        Path | None, typer.Option("--pdf", help="Also write a PDF (no browser needed).")
    ] = None,
    title: Annotated[str | None, typer.Option("--title", help="Report title.")] = None,
    cycles: CyclesOpt = None,
    period: PeriodOpt = None,
    variables: VariableOpt = None,
    ensemble: EnsembleOpt = None,
    axes: AxisOpt = None,
    strict: StrictOpt = False,
) -> None:
    """Build a self-contained HTML validation report from simulation and measurement files.

    Exit code 1 when a criterion fails (the report is written first); with --strict also
    when one is not assessed or not comparable.
    """
    if ctx.invoked_subcommand is not None:
        return
    from jointwear.compare import DEFAULT_AXES
    from jointwear.compare import outcome as oc
    from jointwear.compare.verdicts import LABELS
    from jointwear.reports.builder import report_from_files

    path, result = report_from_files(
        out,
        sim=sim or [],
        metrology=metrology or [],
        dic=dic or [],
        comparison=comparison,
        verification=verification or [],
        criteria=criteria,
        title=title,
        pdf=pdf,
        cycles=cycles,
        period_s=period,
        variables=variables or None,
        ensemble=ensemble or [],
        axes=axes or DEFAULT_AXES,
        warn=oc.echo_warning,
        reported=reported or [],
    )
    typer.echo(oc.origin_line(result))
    for row in result.decisions.itertuples():
        typer.echo(f"{LABELS[row.state]:<14}  {row.quantity}: {row.value}")
    typer.echo(f"report: {path}")
    if pdf is not None:
        typer.echo(f"pdf: {pdf}")
    for line in oc.outcome_lines(result):
        typer.echo(line)
    oc.raise_for_outcome(result, strict=strict, where=str(path))


def register(app: typer.Typer) -> None:
    """Make the ``jointwear report`` group itself build the report (options only)."""
    app.callback(invoke_without_command=True)(report_cmd)
