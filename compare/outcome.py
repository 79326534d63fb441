"""What a comparison means for the command line: card lines, summary and exit code.

Exit code 1 (:class:`~jointwear.errors.ValidationFailed`) when any criterion fails; with
``strict`` also when a criterion is not assessed or not comparable or a part was not compared.
Otherwise 0 - with a distinct summary line saying what was left undecided.
"""

from __future__ import annotations

import jointwear.compare.verdicts as vd
from jointwear.compare.comparison import Comparison
from jointwear.errors import ValidationFailed

__all__ = [
    "alignment_lines",
    "card_lines",
    "echo_warning",
    "origin_line",
    "outcome_lines",
    "raise_for_outcome",
]


def echo_warning(text: str) -> None:
    """Print ``warning: TEXT`` as one plain line on stderr (the ``warn`` of
    :func:`jointwear.external.load_for_comparison` for ``compare`` and ``report``)."""
    import typer

    typer.echo(f"warning: {text}", err=True)


def origin_line(c: Comparison) -> str:
    """``data origin: simulation simulated, measurement SYNTHETIC (...)``."""
    sim = c.data_origin.get("simulation", "not stated")
    meas = c.data_origin.get("measurement", "not stated")
    line = f"data origin: simulation {sim}, measurement {meas}"
    if meas == "synthetic":
        line += " - SYNTHETIC measurement: generated data with a known truth, not a real test"
    elif meas == "not stated":
        line += " - the measured files do not state data_origin"
    return line


def card_lines(c: Comparison) -> list[str]:
    """One line per decision: ``STATE  quantity: value  [criterion]`` plus the reason."""
    out = []
    width = max(len(v) for v in vd.LABELS.values())
    for row in c.decisions.itertuples():
        out.append(
            f"{vd.LABELS[row.state]:<{width}}  {row.quantity}: {row.value}  [{row.criterion}]"
        )
        if row.reason:
            out.append(f"{'':<{width}}    why: {row.reason}")
        if row.resolution and row.state in (vd.PASS, vd.FAIL):
            out.append(f"{'':<{width}}    resolution: {row.resolution}")
    return out


def alignment_lines(c: Comparison) -> list[str]:
    """How the wear maps were interpolated and the motion aligned, and the notes: one line each."""
    lines = []
    if c.wear is not None:
        lines.append(f"wear maps: {c.wear.attrs['interpolation']}")
    if c.motion is not None:
        a = c.motion.attrs
        lines.append(
            f"motion aligned by {a['alignment_method'].replace('_', ' ')}: shift "
            f"{a['time_shift_s'] * 1e3:+.2f} ± {a.get('time_shift_u_s', float('nan')) * 1e3:.2g}"
            f" ms ({a['time_shift_deg']:+.1f} degree of crank angle) over {a['n_cycles']:g} "
            "cycle(s)"
        )
    return lines + [f"note: {note}" for note in c.notes]


def outcome_lines(c: Comparison) -> list[str]:
    """The summary line and, when something is undecided, what and why in one line each."""
    lines = [c.summary(), *([c.resolution()] if c.resolution() else [])]
    na, nc = c.quantities(vd.NOT_ASSESSED), c.quantities(vd.NOT_COMPARABLE)
    if na:
        lines.append(
            "not assessed (an uncertainty is unknown - give --ensemble / --verification or "
            f"state it in --criteria): {', '.join(dict.fromkeys(na))}"
        )
    if nc:
        lines.append(f"not comparable (the data do not cover it): {', '.join(dict.fromkeys(nc))}")
    for p in c.partial:
        lines.append(f"partial: {p}")
    return lines


def raise_for_outcome(c: Comparison, *, strict: bool = False, where: str = "") -> None:
    """Raise :class:`ValidationFailed` (exit 1) when a criterion failed, or with ``strict`` when
    anything is undecided."""
    tail = f" (details in {where})" if where else ""
    if c.any_failed:
        raise ValidationFailed(
            f"validation failed for: {', '.join(dict.fromkeys(c.failed()))}{tail}"
        )
    if strict and not c.complete:
        raise ValidationFailed(
            "--strict: not every criterion was decided: "
            + c.summary()
            + ("; partial" if c.partial else "")
            + tail
        )
