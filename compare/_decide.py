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
DECISION_COLUMNS = [
    "quantity", "criterion", "value", "state", "basis", "reason", "passed", "key", "resolution",
]  # fmt: skip


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
    relative : float
        Share of the variance ``value**2`` that is applied relative to the simulated value
        ``S`` (a user-stated ``rel·|S|``, a verification study's relative u_num, a reduced
        ensemble's relative spread): it scales with ``S**2`` when the model predicts another
        value, the rest is fixed [1, in 0..1]. The resolution of a criterion
        (:func:`jointwear.compare.metrics.detectable_error`) uses it.
    """

    value: float | None
    basis: str
    relative: float = 0.0

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
    resolution: str = "",
) -> dict[str, Any]:
    """One row of the decision card (``key``: the metrics-table quantity it judges;
    ``resolution``: the errors the criterion detects, :func:`resolution_text`)."""
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
        "resolution": resolution,
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
    relative : bool
        True (a magnitude): the resolution is stated as relative errors ``(S - D) / |D|``;
        False (an angle): as the absolute error ``|E| > U_val``.
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
    relative: bool = True


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


def _percent(e: float) -> str:
    return f"{e * 100:+.0f} %".replace("-", "−")


def resolution_text(low: float, high: float) -> str:
    """``"detects errors outside −24 %…+40 %"``: what a V&V 20 criterion can detect."""
    if not (np.isfinite(low) or np.isfinite(high)):
        return "detects no error of S (U_val grows with S faster than |E|, and exceeds |D|)"
    if not np.isfinite(high):
        return f"detects under-predictions below {_percent(low)}, no over-prediction"
    if not np.isfinite(low):
        return f"detects over-predictions above {_percent(high)}, no under-prediction to S = 0"
    return f"detects errors outside {_percent(low)}…{_percent(high)}"


def _resolution(rows: Rows, quantity: str, error: Discrepancy, budget: Budget, res: Any) -> str:
    """The detectable errors of a decided criterion: metric rows and the card's text."""
    if not error.relative:
        return f"detects |E| > {fmt(res.U_val, error.units)}"
    known = [u for _, u in budget.parts()]
    u_rel = float(np.sqrt(sum(float(u.value) ** 2 * u.relative for u in known)))
    u_fix = float(np.sqrt(sum(float(u.value) ** 2 * (1.0 - u.relative) for u in known)))
    low, high = mt.detectable_error(error.d, error.s, u_fixed=u_fix, u_relative=u_rel, k=budget.k)
    how = (
        f"|E| = U_val solved for S = D (1 + e); {u_rel / res.u_val:.0%} of u_val applied relative "
        "to S"
        if res.u_val > 0
        else ""
    )
    rows.add(quantity, "detectable_error_low", low, error.units, how)
    rows.add(quantity, "detectable_error_high", high, error.units, how)
    return resolution_text(low, high)


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
            resolution=_resolution(rows, quantity, error, budget, res),
        )
    )
