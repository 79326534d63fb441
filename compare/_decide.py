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


@dataclass(frozen=True)
class Budget:
    """The uncertainties V&V 20 combines for one quantity, and the coverage factor.

    Attributes
    ----------
    u_num, u_input, u_d : Uncertainty
        Numerical, input and measurement standard uncertainty [units of the quantity].
    k : float
        Coverage factor, ``U_val = k u_val`` [1].
    """

    u_num: Uncertainty
    u_input: Uncertainty
    u_d: Uncertainty
    k: float

    def parts(self) -> tuple[tuple[str, Uncertainty], ...]:
        """The uncertainties by metric name."""
        return (("u_num", self.u_num), ("u_input", self.u_input), ("u_D", self.u_d))


@dataclass(frozen=True)
class Discrepancy:
    """What one V&V 20 criterion judges, and how the decision card words it.

    Attributes
    ----------
    s, d : float
        The simulated and measured values V&V 20 is given [units]; for an angle ``s`` is
        ``d + e``, so that V&V 20 sees the wrapped error.
    e : float
        The error ``E`` (NaN: the values are undefined, not comparable) [units].
    units : str
        Units of the quantity.
    values : tuple of (str, float)
        Metric rows written before ``E`` (``value_sim``, ``value_meas``, ...).
    shown : str
        Value of a *not comparable* decision.
    not_assessed_text : str
        Value of a *not assessed* decision; may carry a screening figure (never a pass or fail).
    result_text : callable
        Value of a pass or a fail, from the :class:`~jointwear.compare.metrics.VV20` result.
    criterion_note : str
        Added to the criterion's text (e.g. how an angle error is wrapped).
    """

    s: float
    d: float
    e: float
    units: str
    values: tuple[tuple[str, float], ...]
    shown: str
    not_assessed_text: str
    result_text: Callable[[Any], str]
    criterion_note: str = ""


def scalar_discrepancy(s: float, d: float, units: str, relative_error_max: float) -> Discrepancy:
    """``E = S - D`` of a scalar quantity; when V&V 20 is not assessed the card shows the
    relative error against the screening threshold ``relative_error_max``, labelled *screening
    only* (never counted as a pass or a fail)."""
    rel = (s - d) / abs(d) if d != 0 else float("nan")
    finite = bool(np.isfinite(s) and np.isfinite(d))
    screen = (
        f"; screening only, not a verdict: |S - D| / |D| = {abs(rel):.3g} "
        f"{'<=' if abs(rel) <= relative_error_max else '>'} {relative_error_max:g}"
        if np.isfinite(rel)
        else ""
    )
    return Discrepancy(
        s,
        d,
        (s - d) if finite else float("nan"),
        units,
        values=(("value_sim", s), ("value_meas", d), ("relative_error", rel)),
        shown=f"S = {fmt(s, units)}, D = {fmt(d, units)}",
        not_assessed_text=f"E = {fmt(s - d, units)} (S = {fmt(s, units)}, D = {fmt(d, units)}){screen}",
        result_text=lambda res: f"|E| = {fmt(abs(res.E), units)}, U_val = {fmt(res.U_val, units)}",
    )


def vv20_decision(
    rows: Rows,
    decisions: list[dict[str, Any]],
    quantity: str,
    label: str,
    error: Discrepancy,
    budget: Budget,
    not_comparable: str = "",
) -> None:
    """Metric rows and the decision of one V&V 20 criterion: its four states.

    Adds the rows of ``error.values``, ``E`` and the uncertainties, then one decision: *not
    comparable* (``not_comparable`` states why the data do not cover the quantity, or ``E`` is
    not finite), *not assessed* when an uncertainty of ``budget`` is unknown, else pass or fail.
    """
    units, e = error.units, error.e
    for metric, value in error.values:
        rows.add(quantity, metric, value, units)
    rows.add(quantity, "E", e, units)
    parts = budget.parts()
    for name, u in parts:
        rows.add(quantity, name, u.value if u.known else float("nan"), units, u.basis)
    criterion = f"|E| <= U_val = {budget.k:g} u_val (ASME V&V 20{error.criterion_note})"
    if not_comparable or not np.isfinite(e):
        reason = not_comparable or "the simulated or measured value is undefined"
        decisions.append(
            decision(
                label, criterion, error.shown, vd.NOT_COMPARABLE, "V&V 20", reason, key=quantity
            )
        )
        return
    if not all(u.known for _, u in parts):
        # V&V 20 cannot be decided; a screening figure in the text is for orientation only
        reason = "; ".join(f"{name} not assessed ({u.basis})" for name, u in parts if not u.known)
        decisions.append(
            decision(
                label,
                criterion,
                error.not_assessed_text,
                vd.NOT_ASSESSED,
                "V&V 20",
                reason,
                key=quantity,
            )
        )
        return
    res = mt.vv20(
        error.s,
        error.d,
        u_num=float(budget.u_num.value),
        u_input=float(budget.u_input.value),
        u_d=float(budget.u_d.value),
        k=budget.k,
    )
    rows.add(quantity, "u_val", res.u_val, units)
    rows.add(quantity, "U_val", res.U_val, units)
    decisions.append(
        decision(
            label,
            criterion,
            error.result_text(res),
            vd.PASS if res.passed else vd.FAIL,
            "V&V 20",
            key=quantity,
        )
    )
