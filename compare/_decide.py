"""Building blocks of the decision card: metric rows, uncertainty statements, scalar decisions."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

import jointwear.compare.metrics as mt
import jointwear.compare.verdicts as vd

METRIC_COLUMNS = ["quantity", "metric", "value", "units", "long_name", "definition", "basis"]
DECISION_COLUMNS = ["quantity", "criterion", "value", "state", "basis", "reason", "passed", "key"]


@dataclass(frozen=True)
class Uncertainty:
    """A standard uncertainty and where it comes from; ``value`` None = not assessed.

    Attributes
    ----------
    value : float or None
        Standard uncertainty [units of the quantity]; None when unknown.
    basis : str
        How it was obtained ("stated by the simulation file", "ensemble of 16 runs", "GCI ...",
        "user-stated 15 % of |S|"), or why it is unknown.
    """

    value: float | None
    basis: str

    @property
    def known(self) -> bool:
        """True when a value is available."""
        return self.value is not None and bool(np.isfinite(self.value))


def unknown(reason: str) -> Uncertainty:
    """An uncertainty that is not assessed, with the reason."""
    return Uncertainty(None, reason)


class Rows:
    """Collects metric rows with units and definitions."""

    def __init__(self) -> None:
        self.rows: list[dict[str, Any]] = []

    def add(self, quantity: str, metric: str, value: float, units: str, basis: str = "") -> None:
        long, definition, rule = mt.DEFINITIONS[metric]
        unit = units if rule == "same" else rule
        self.rows.append(
            {
                "quantity": quantity,
                "metric": metric,
                "value": float(value),
                "units": unit,
                "long_name": long,
                "definition": definition,
                "basis": basis,
            }
        )

    def frame(self) -> pd.DataFrame:
        return pd.DataFrame(self.rows, columns=METRIC_COLUMNS)


def fmt(value: float, units: str) -> str:
    """A value for the decision card: lengths in µm, volumes in mm³."""
    if not np.isfinite(value):
        return "n/a"
    if units == "m" and abs(value) < 1e-2:
        return f"{value * 1e6:.3g} µm"
    if units == "m3":
        return f"{value * 1e9:.3g} mm³"
    if units == "1":
        return f"{value:.3g}"
    shown = {"m s-1": "m/s", "m s-2": "m/s²"}.get(units, units)  # as in the report's tables
    return f"{value:.4g} {shown}"


def decision(
    quantity: str,
    criterion: str,
    value: str,
    state: str,
    basis: str,
    reason: str = "",
    key: str = "",
) -> dict[str, Any]:
    """One row of the decision card (``key``: the metrics-table quantity it judges)."""
    vd.state_code(state)  # refuse unknown states
    return {
        "quantity": quantity,
        "criterion": criterion,
        "value": value,
        "state": state,
        "basis": basis,
        "reason": reason,
        "passed": state == vd.PASS,
        "key": key or quantity,
    }


def threshold_state(ok: bool, finite: bool = True) -> str:
    """pass/fail of a threshold criterion; not comparable when its value is undefined."""
    if not finite:
        return vd.NOT_COMPARABLE
    return vd.PASS if ok else vd.FAIL


def scalar_decision(
    rows: Rows,
    decisions: list[dict[str, Any]],
    quantity: str,
    label: str,
    s: float,
    d: float,
    units: str,
    *,
    u_num: Uncertainty,
    u_input: Uncertainty,
    u_d: Uncertainty,
    k: float,
    relative_error_max: float,
    not_comparable: str = "",
) -> None:
    """Metric rows and decisions of one scalar quantity: V&V 20, or why it cannot be decided.

    The V&V 20 criterion is always on the card: *not comparable* when ``not_comparable``
    states why the data do not cover the quantity, *not assessed* when one of its
    uncertainties is unknown (the relative error against the screening threshold
    ``relative_error_max`` is then shown in its value, labelled *screening only*: it is never
    counted as a pass or a fail), else pass/fail.
    """
    rows.add(quantity, "value_sim", s, units)
    rows.add(quantity, "value_meas", d, units)
    rel = (s - d) / abs(d) if d != 0 else float("nan")
    rows.add(quantity, "relative_error", rel, units)
    finite = bool(np.isfinite(s) and np.isfinite(d))
    screen = (
        f"; screening only, not a verdict: |S - D| / |D| = {abs(rel):.3g} "
        f"{'<=' if abs(rel) <= relative_error_max else '>'} {relative_error_max:g}"
        if np.isfinite(rel)
        else ""
    )
    vv20_decision(
        rows,
        decisions,
        quantity,
        label,
        s,
        d,
        (s - d) if finite else float("nan"),
        units,
        u_num=u_num,
        u_input=u_input,
        u_d=u_d,
        k=k,
        criterion=f"|E| <= U_val = {k:g} u_val (ASME V&V 20)",
        shown=f"S = {fmt(s, units)}, D = {fmt(d, units)}",
        not_assessed_text=f"E = {fmt(s - d, units)} (S = {fmt(s, units)}, D = {fmt(d, units)}){screen}",
        result_text=lambda res: f"|E| = {fmt(abs(res.E), units)}, U_val = {fmt(res.U_val, units)}",
        not_comparable=not_comparable,
    )


def vv20_decision(
    rows: Rows,
    decisions: list[dict[str, Any]],
    quantity: str,
    label: str,
    s: float,
    d: float,
    e: float,
    units: str,
    *,
    u_num: Uncertainty,
    u_input: Uncertainty,
    u_d: Uncertainty,
    k: float,
    criterion: str,
    shown: str,
    not_assessed_text: str,
    result_text: Callable[[Any], str],
    not_comparable: str = "",
) -> None:
    """The four states of one V&V 20 criterion of ``s`` against ``d`` with the error ``e``.

    ``e`` is ``s - d`` for a scalar and the wrapped difference for an angle (then ``s`` is
    ``d + e``, so that V&V 20 sees the same error).

    Adds the ``E`` and uncertainty rows, then one decision: *not comparable* (``not_comparable``
    or a non-finite ``e``; value ``shown``), *not assessed* when an uncertainty is unknown (value
    ``not_assessed_text``, which may carry a screening figure: never a pass or a fail), else pass
    or fail with ``result_text(vv20 result)``. Shared by :func:`scalar_decision` and the
    circular (angle) decision of reported measurements.
    """
    rows.add(quantity, "E", e, units)
    parts = (("u_num", u_num), ("u_input", u_input), ("u_D", u_d))
    for name, u in parts:
        rows.add(quantity, name, u.value if u.known else float("nan"), units, u.basis)
    if not_comparable or not np.isfinite(e):
        reason = not_comparable or "the simulated or measured value is undefined"
        decisions.append(
            decision(label, criterion, shown, vd.NOT_COMPARABLE, "V&V 20", reason, key=quantity)
        )
        return
    if not all(u.known for _, u in parts):
        # V&V 20 cannot be decided; a screening figure in the text is for orientation only
        reason = "; ".join(f"{name} not assessed ({u.basis})" for name, u in parts if not u.known)
        decisions.append(
            decision(
                label,
                criterion,
                not_assessed_text,
                vd.NOT_ASSESSED,
                "V&V 20",
                reason,
                key=quantity,
            )
        )
        return
    res = mt.vv20(
        s, d, u_num=float(u_num.value), u_input=float(u_input.value), u_d=float(u_d.value), k=k
    )
    rows.add(quantity, "u_val", res.u_val, units)
    rows.add(quantity, "U_val", res.U_val, units)
    decisions.append(
        decision(
            label,
            criterion,
            result_text(res),
            vd.PASS if res.passed else vd.FAIL,
            "V&V 20",
            key=quantity,
        )
    )
