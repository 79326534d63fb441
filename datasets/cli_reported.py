"""``jointwear datasets reported``: the reference study's reported measurements as a TOML file."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from jointwear._cli import Overwrite
from jointwear.datasets._study_size import REDUCED


def reported_cmd(
    out: Annotated[Path, typer.Argument(help="TOML file to write.")],
    overwrite: Overwrite = False,
) -> None:
    """Write the reference study's reported values (Zhang et al. 2023) as a reported-measurement file."""
    from jointwear import io
    from jointwear.datasets.reference_study import reference_file

    text = reference_file().read_text(encoding="utf-8")
    with io.atomic_path(out) as tmp:
        tmp.write_text(text, encoding="utf-8")
    typer.echo(f"wrote {out}: edit it or pass it to 'jointwear import reported'")


def reference_study_cmd(
    out: Annotated[Path, typer.Argument(help="Output folder.")],
    overwrite: Overwrite = False,
    reduced: Annotated[
        bool,
        typer.Option(
            "--reduced",
            help=f"Coarse grid, {REDUCED.ensemble_runs} ensemble members, "
            f"{REDUCED.training_runs} calibration runs and {REDUCED.prediction_runs} predictions "
            "(about two minutes).",
        ),
    ] = False,
    verbose: Annotated[
        bool,
        typer.Option("--verbose", help="Every reading of each undecided verdict, and all notes."),
    ] = False,
) -> None:
    """Decide the reference study's reported values against the default rig (with u_num, u_input),
    then calibrate on the 4e5 growth and validate at 1.2e6.

    Writes reported.nc, sim_wear.nc, verification.nc, ensemble.nc and metrics.nc to OUT and
    prints the verdict per reported quantity; then the calibration (posterior.nc,
    prediction.nc, verification_calibrated.nc, metrics_calibrated.nc): kw and the tilt
    stiffness calibrated on the 4e5 cylindricity growth, the 1.2e6 growth decided with the
    posterior prediction. Exit code 1 when a criterion fails.
    """
    from jointwear.compare.outcome import card_lines, outcome_lines, raise_for_outcome
    from jointwear.datasets._study_card import (
        baseline_quantities,
        study_card_lines,
        unstated_fields,
    )
    from jointwear.datasets.reference_study import (
        FULL,
        REDUCED,
        reference_file,
        run_reference_study,
    )
    from jointwear.params import read_toml

    result = run_reference_study(
        out, REDUCED if reduced else FULL, say=lambda s: typer.echo(s, err=True)
    )
    if verbose:
        lines = [*card_lines(result), *(f"note: {n}" for n in result.notes), *outcome_lines(result)]
    else:
        reported = read_toml(reference_file())
        unstated = unstated_fields(reported)
        notes = [n for n in result.notes if not (unstated and "does not state" in n)]
        lines = [
            *study_card_lines(result, baseline_quantities(reported), unstated),
            *(f"note: {n}" for n in notes),
        ]
    for line in lines:
        typer.echo(line)
    from jointwear.datasets.reference_calibration import calibrate_reference, reference_lines

    cal = calibrate_reference(
        out, REDUCED if reduced else FULL, result, say=lambda s: typer.echo(s, err=True)
    )
    for line in reference_lines(cal):
        typer.echo(line)
    raise_for_outcome(result, where=str(Path(out) / "metrics.nc"))
    raise_for_outcome(cal.validation, where=str(Path(out) / "metrics_calibrated.nc"))


def register(app: typer.Typer) -> None:
    """Add ``reported`` to the ``jointwear datasets`` group."""
    app.command("reported")(reported_cmd)
    app.command("reference-study")(reference_study_cmd)
