"""``jointwear report --sim ... --metrology ... --dic ... --out report.html``."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from jointwear._cli import Overwrite


def register(app: typer.Typer) -> None:
    """Make the ``jointwear report`` group itself build the report (options only)."""

    @app.callback(invoke_without_command=True)
    def report(
        ctx: typer.Context,
        out: Annotated[
            Path,
            typer.Option("--out", "-o", help="HTML report to write (.pdf: the PDF version only)."),
        ] = Path("report.html"),
        overwrite: Overwrite = False,
        sim: Annotated[
            list[Path] | None,
            typer.Option("--sim", help="Simulated wear map and/or motion (.nc); repeatable."),
        ] = None,
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
        verification: Annotated[
            list[Path] | None,
            typer.Option("--verification", help="Verification (convergence) data (.nc)."),
        ] = None,
        criteria: Annotated[
            Path | None, typer.Option("--criteria", help="TOML file with validation criteria.")
        ] = None,
        pdf: Annotated[
            Path | None, typer.Option("--pdf", help="Also write a PDF (no browser needed).")
        ] = None,
        title: Annotated[str | None, typer.Option("--title", help="Report title.")] = None,
        cycles: Annotated[
            float | None, typer.Option("--cycles", help="Crank cycles at which to compare wear.")
        ] = None,
        period: Annotated[
            float | None,
            typer.Option("--period", help="Crank period in seconds (if no crank angle)."),
        ] = None,
        variables: Annotated[
            list[str] | None,
            typer.Option("--variable", help="Motion variable to compare (repeatable)."),
        ] = None,
        ensemble: Annotated[
            list[Path] | None,
            typer.Option(
                "--ensemble",
                help="Ensemble of simulations (.nc with a 'run' dimension, from jointwear sim "
                "sweep): its spread is the V&V 20 input uncertainty. Repeatable.",
            ),
        ] = None,
        axes: Annotated[
            list[str] | None,
            typer.Option("--axis", help="Motion component to compare (default x and y)."),
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
        """Build a self-contained HTML validation report from simulation and measurement files.

        Exit code 1 when a criterion fails (the report is written first); with --strict also
        when one is not assessed or not comparable.
        """
        if ctx.invoked_subcommand is not None:
            return
        from jointwear import io
        from jointwear.compare import load_criteria
        from jointwear.compare.outcome import (
            echo_warning,
            origin_line,
            outcome_lines,
            raise_for_outcome,
        )
        from jointwear.compare.verdicts import LABELS
        from jointwear.reports.builder import DEFAULT_TITLE, report_from_files

        io.check_writable(out, what="report")
        path, result = report_from_files(
            out,
            sim=sim or [],
            metrology=metrology or [],
            dic=dic or [],
            comparison=comparison,
            verification=verification or [],
            criteria=load_criteria(criteria),
            title=title or DEFAULT_TITLE,
            pdf=pdf,
            cycles=cycles,
            period_s=period,
            variables=variables or None,
            ensemble=ensemble or [],
            axes=axes or ("x", "y"),
            warn=echo_warning,
            reported=reported or [],
        )
        typer.echo(origin_line(result))
        for row in result.decisions.itertuples():
            typer.echo(f"{LABELS[row.state]:<14}  {row.quantity}: {row.value}")
        typer.echo(f"report: {path}")
        if pdf is not None:
            typer.echo(f"pdf: {pdf}")
        for line in outcome_lines(result):
            typer.echo(line)
        raise_for_outcome(result, strict=strict, where=str(path))
