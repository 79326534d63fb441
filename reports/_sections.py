"""The report's sections as plain data: verdict line, coverage, alignment, metrics, budget.

Pure functions of a :class:`~jointwear.compare.Comparison` used by the HTML and the PDF report.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from jointwear.compare import Comparison, Criteria

__all__ = ["format_value"]


def format_value(value: float, units: str, *, digits: int = 4) -> tuple[str, str]:
    """A number and its unit for display: lengths in µm, volumes in mm³, others as given."""
    if value is None or not np.isfinite(value):
        return "n/a", units
    scale = {"m": (1e6, "µm"), "m3": (1e9, "mm³"), "m s-1": (1.0, "m/s"), "1": (1.0, "")}
    factor, shown = scale.get(units, (1.0, units))
    v = value * factor
    if v == 0:
        return "0", shown
    if abs(v) >= 1e-3 and abs(v) < 1e5:
        return f"{v:.{digits}g}", shown
    return f"{v:.{digits - 1}e}", shown


def _cycles(value: Any) -> str:
    try:
        v = float(value)
    except (TypeError, ValueError):
        return "(not stated)"
    return f"{v:.4g}" if np.isfinite(v) else "(not stated)"


def _alignment(c: Comparison) -> list[tuple[str, str]]:
    out: list[tuple[str, str]] = []
    if c.wear is not None:
        a = c.wear.attrs
        out.append(("wear maps", str(a.get("interpolation", ""))))
        if "z_overlap_m" in a:
            lo, hi = (float(v) for v in np.ravel(a["z_overlap_m"]))
            out.append(("axial range compared", f"z from {lo * 1e3:+.2f} mm to {hi * 1e3:+.2f} mm"))
        for key, label in (
            ("angle_convention_sim", "simulation"),
            ("angle_convention_meas", "measurement"),
        ):
            if key in a:
                out.append(
                    (
                        f"angle convention of the {label}",
                        f"{a[key]}; converted to the canonical convention (0 along −x, clockwise)",
                    )
                )
        if "cycles_selection" in a:
            cs, cm = _cycles(a.get("cycles_sim")), _cycles(a.get("cycles_meas"))
            out.append(
                (
                    "crank cycles",
                    f"simulation {cs}, measurement {cm} ({a['cycles_selection']})",
                )
            )
    if c.motion is not None:
        a = c.motion.attrs
        out.append(("motion time base", str(a.get("interpolation", ""))))
        out.append(("phase alignment", str(a.get("alignment", a.get("alignment_method", "")))))
        if "time_shift_s" in a:
            out.append(
                (
                    "time shift",
                    f"{float(a['time_shift_s']) * 1e3:+.2f} ms = {float(a.get('time_shift_deg', np.nan)):+.1f}"
                    f" degree of crank angle (simulation time = measurement time − shift, "
                    f"period {float(a.get('period_s', np.nan)):.4g} s)",
                )
            )
    return out


def _metrics_rows(c: Comparison) -> list[dict[str, str]]:
    rows = []
    budget_only = {"u_num", "u_input", "u_D", "u_val", "U_val"}
    for r in c.metrics.itertuples():
        if r.metric in budget_only:  # shown in the uncertainty budget
            continue
        value, units = format_value(float(r.value), str(r.units))
        rows.append(
            {
                "quantity": str(r.quantity),
                "long_name": str(r.long_name),
                "value": value,
                "units": units,
                "definition": str(r.definition),
            }
        )
    return rows


_BUDGET_KEYS = ("value_sim", "value_meas", "E", "u_num", "u_input", "u_D", "u_val", "U_val")


def _budget(c: Comparison) -> tuple[list[dict[str, Any]], list[str]]:
    """Rows of the V&V 20 budget (every compared scalar) and the sources of each uncertainty."""
    import jointwear.compare.verdicts as vd

    m = c.metrics
    budget, sources = [], []
    vv = {
        str(r.key): (str(r.quantity), str(r.state))
        for r in c.decisions.itertuples()
        if r.basis == "V&V 20"
    }
    for q in [q for q in dict.fromkeys(m.quantity) if str(q) in vv]:
        label, state = vv[str(q)]
        sub = m[m.quantity == q].set_index("metric")
        units = str(sub.loc["value_sim", "units"])
        cells = []
        for key in _BUDGET_KEYS:
            if key not in sub.index or not np.isfinite(float(sub.loc[key, "value"])):
                cells.append("not assessed" if key.startswith("u_") else "–")
                continue
            v, u = format_value(float(sub.loc[key, "value"]), units, digits=3)
            cells.append(f"{v} {u}".strip())
        budget.append(
            {"quantity": label, "cells": cells, "state": state, "label": vd.LABELS[state]}
        )
        for key in ("u_num", "u_input", "u_D"):
            if key in sub.index:
                sources.append(
                    {"quantity": label, "component": key, "basis": str(sub.loc[key, "basis"])}
                )
    return budget, sources


def _uncertainty_sources(crit: Criteria) -> list[tuple[str, str]]:
    def stated(name: str) -> str:
        v = getattr(crit, name)
        return "not stated" if v is None else f"user-stated {v:.3g}·|S|"

    return [
        (
            "u_D (measurement)",
            "the measurement's stated standard uncertainty (<name>_u): at the location of the "
            "maximum for the maximum wear depth; its surface integral for the worn volume (fully "
            "correlated, conservative); √2·RMS for the cylindricity (peak-to-valley of two "
            "points); its RMS for the RMS motion. None stated: not assessed.",
        ),
        (
            "u_num (numerical)",
            "the simulation's stated standard uncertainty (<name>_u), else a verification study "
            "(GCI, Roache; only for monotone convergence), else a fraction stated in the criteria "
            f"(wear: {stated('wear_u_num_rel')}; motion: {stated('motion_u_num_rel')}); "
            "otherwise not assessed.",
        ),
        (
            "u_input (model inputs)",
            "the standard deviation of the quantity over an ensemble of simulations (--ensemble), "
            "else a fraction stated in the criteria (wear: "
            f"{stated('wear_u_input_rel')}; motion: {stated('motion_u_input_rel')}); otherwise "
            "not assessed - never zero.",
        ),
    ]


def _verdict(c: Comparison, counts: dict[str, int]) -> tuple[str, str]:
    """Headline of the decision card and its CSS class."""
    import jointwear.compare.verdicts as vd

    n = sum(counts.values())
    synthetic = (
        " (against SYNTHETIC measurement data)"
        if c.data_origin.get("measurement") == "synthetic"
        else ""
    )
    if n == 0:
        return "NO DECISION: nothing was compared", "undecided"
    if c.wear is not None and any(str(t).startswith("validation domain") for t in c.notes):
        from jointwear.compare import band_label

        # the wear is judged on the measured band only; the rest of the simulation is not
        synthetic += f"; wear judged {band_label(c.wear)}, outside it extrapolated"
    if counts[vd.FAIL]:
        return f"NOT VALIDATED: {counts[vd.FAIL]} of {n} criteria failed{synthetic}", "fail"
    undecided = counts[vd.NOT_ASSESSED] + counts[vd.NOT_COMPARABLE]
    if undecided or c.partial:
        what = []
        if counts[vd.NOT_ASSESSED]:
            what.append(f"{counts[vd.NOT_ASSESSED]} not assessed")
        if counts[vd.NOT_COMPARABLE]:
            what.append(f"{counts[vd.NOT_COMPARABLE]} not comparable")
        if c.partial:
            what.append("parts not compared")
        return (
            f"INCOMPLETE: no criterion failed, but {', '.join(what)}{synthetic}",
            "undecided",
        )
    return f"VALIDATED: every criterion is met{synthetic}", "pass"


def _coverage(c: Comparison) -> list[str]:
    """What the wear comparison covers (the compared fraction of the simulated volume)."""
    if c.wear is None or "volume_fraction_compared" not in c.wear.attrs:
        return []
    a = c.wear.attrs
    lo, hi = (float(v) for v in np.ravel(a["z_overlap_m"]))
    zs = [float(v) for v in np.ravel(a.get("z_range_sim_m", [np.nan, np.nan]))]
    frac = float(a["volume_fraction_compared"])
    arc = float(a.get("theta_fraction_measured", 1.0))
    out = []
    if arc < 1.0:
        out.append(
            f"The measurement covers {arc:.0%} of the circumference; the rest is not compared "
            "(blank on the maps), never interpolated across."
        )
    out += [
        f"Compared axial range z = {lo * 1e3:+.2f} to {hi * 1e3:+.2f} mm of the simulated "
        f"{zs[0] * 1e3:+.2f} to {zs[1] * 1e3:+.2f} mm: {frac:.0%} of the simulated worn volume "
        "is compared (uncompared region hatched on the wear maps); every wear criterion is "
        "decided within this range."
    ]
    if not int(a.get("sim_max_inside", 1)):
        out.append(
            f"The simulated maximum ({float(a['sim_max_value_m']) * 1e6:.3g} µm at z = "
            f"{float(a['sim_max_z_m']) * 1e3:+.2f} mm) lies outside the measured range: there "
            "the simulation is an extrapolation, not validated (validation domain)."
        )
    return out


def _sensitivity_rows(c: Comparison) -> list[dict[str, str]]:
    rows = []
    for r in c.sensitivity.itertuples():
        rows.append(
            {
                "quantity": str(r.quantity),
                "parameter": str(r.parameter),
                "S1": f"{float(r.S1):.2f}" if np.isfinite(float(r.S1)) else "–",
                "ST": f"{float(r.ST):.2f}" if np.isfinite(float(r.ST)) else "–",
                "method": str(r.method),
                "estimator": str(getattr(r, "estimator", "S1")),
            }
        )
    return rows
