"""What ``jointwear datasets reference-study`` prints: the decision card for a reader of the paper.

At most three lines per criterion (the verdict, why, and what it detects); the verdicts that
depend on what the paper leaves unstated are counted per state instead of listing every reading
(``--verbose`` lists them); the new bore's cylindricity is shown as the baseline of the growth
quantities, not counted as a criterion; an undecided angle whose screening disagrees says so; the
fields the paper does not state are explained in its own terms.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from typing import Any

__all__ = ["UNSTATED_WORDS", "baseline_quantities", "study_card_lines", "unstated_fields"]

#: The reported file's unstated fields, in words a reader of the paper can check against it.
UNSTATED_WORDS: dict[str, str] = {
    "angle.direction": (
        "which way the angles of Figs. 13-14 grow from 0 degree (parallel to the ground, towards "
        "the crank): clockwise or counter-clockwise seen from the crank side; the paper does "
        "not say (its simulation grid runs clockwise from there, Section 2, which suggests, "
        "but does not state, clockwise)"
    ),
    "layers.first": (
        "which end of the bore the figures' 'first layer' is at (the crank side or the other); "
        "the paper does not say"
    ),
    "layers.z_centre": (
        "where the 13 scanned layers (a 12 mm span, 1 mm apart) sit in the 15 mm bore: centred, "
        "or shifted up to 1.5 mm towards a face; the paper does not say (centred is the "
        "natural reading)"
    ),
}

_UNDER = re.compile(r"(PASS|FAIL|NOT ASSESSED|NOT COMPARABLE) under (\d+) of (\d+)")
_SETTLE = re.compile(r"state (.+?) in the reported file")
_SCREEN_E = re.compile(r"E = ([-+]?[\d.]+) degree")


def unstated_fields(reported: Mapping[str, Any]) -> list[str]:
    """Dotted names of the reported file's fields marked ``"unstated"`` (``layers.first``...)."""
    out = []
    for section, table in reported.items():
        if isinstance(table, Mapping):
            out += [f"{section}.{k}" for k, v in table.items() if v == "unstated"]
    return [name for name in out if name in UNSTATED_WORDS]


def baseline_quantities(reported: Mapping[str, Any]) -> set[str]:
    """Names of the reported quantities at 0 cycles (the new bore): a baseline, not a
    prediction of the simulation."""
    quantities = reported.get("quantity", {})
    return {name for name, q in quantities.items() if float(q.get("cycles", -1)) == 0.0}


def _short_reason(reason: str) -> str:
    """A reading-dependent verdict as counts per state (the readings are in --verbose)."""
    counts = _UNDER.findall(reason)
    if not counts:
        return reason
    settle = _SETTLE.search(reason)
    total = counts[0][2]
    per = ", ".join(f"{state} under {n}" for state, n, _ in counts)
    what = settle.group(1) if settle else "what the paper leaves unstated"
    return f"depends on {what}, which the paper does not state: {per} of {total} readings"


def _errors(value: str) -> list[float]:
    """The errors ``E = ... degree`` of an angle's value (one per reading)."""
    return [float(e) for e in _SCREEN_E.findall(value) if math.isfinite(float(e))]


def _short_value(value: str) -> str:
    """One reading's value as it is; several readings' as the range of their errors."""
    if " | " not in value:
        return value
    errors = _errors(value)
    n = value.count(" | ") + 1
    if not errors:
        return f"{n} readings (--verbose lists them)"
    lo, hi = min(errors), max(errors)
    return f"E = {lo:+.0f}…{hi:+.0f} degree over {n} readings (--verbose lists them)"


def _screening(row: Any, comparison: Any) -> str:
    """For an undecided angle: whether its screening agrees with the threshold (under every
    reading: the smallest |E| decides)."""
    errors = _errors(str(row.value))
    if row.state != "not_assessed" or not errors:
        return ""
    e = min(abs(x) for x in errors)
    limit = float(comparison.criteria.max_angle_error_deg)
    verdict = "disagrees" if e > limit else "agrees"
    return (
        f"screening {verdict}, not a verdict: |E| >= {e:.0f} degree "
        f"{'>' if e > limit else '<='} {limit:g}"
    )


def study_card_lines(comparison: Any, baseline: set[str], unstated: list[str]) -> list[str]:
    """The default output of the reference study (``comparison``: its Comparison; ``baseline``:
    keys of the quantities that are a baseline, not a prediction; ``unstated``:
    :func:`unstated_fields`)."""
    from jointwear.compare import verdicts as vd

    width = max(len(v) for v in vd.LABELS.values())
    lines: list[str] = []
    counted = []
    for row in comparison.decisions.itertuples():
        if row.key in baseline:
            lines.append(
                f"{'BASELINE':<{width}}  {row.quantity}: {row.value} (the new bore: the growth "
                "quantities are measured from it; not a criterion)"
            )
            continue
        counted.append(row.state)
        screen = _screening(row, comparison)
        label = vd.LABELS[row.state] + (" (screening disagrees)" if "disagrees" in screen else "")
        value = _short_value(str(row.value))
        lines.append(f"{label:<{width}}  {row.quantity}: {value}  [{row.criterion}]")
        why = "; ".join(
            p for p in (_short_reason(str(row.reason)) if row.reason else "", screen) if p
        )
        if why:
            lines.append(f"{'':<{width}}    why: {why}")
        if row.resolution and row.state in (vd.PASS, vd.FAIL):
            lines.append(f"{'':<{width}}    resolution: {row.resolution}")
    for name in unstated:
        lines.append(f"unstated: {name} = {UNSTATED_WORDS[name]}")
    if unstated:
        lines.append(
            "to decide them: 'jointwear datasets reported zhang.toml', state these fields in it, "
            "'jointwear import reported' and 'jointwear compare' (docs/compare-report.md)"
        )
    summary = vd.summary_line(counted)
    lines.append(
        summary + (f" (and {len(baseline)} baseline, not a criterion)" if baseline else "")
    )
    return lines
