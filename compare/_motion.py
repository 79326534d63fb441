"""Motion criteria: Sprague-Geers of each history, V&V 20 of each component's RMS."""

from __future__ import annotations

from typing import Any

import numpy as np
import xarray as xr

import jointwear.compare.metrics as mt
from jointwear.compare._decide import (
    Rows,
    decision,
    scalar_discrepancy,
    threshold_state,
    vv20_decision,
)
from jointwear.compare.sources import Sources


def components(al: xr.Dataset) -> list[tuple[str, str | None]]:
    """(variable, component) pairs of an aligned motion dataset."""
    names = [str(v)[: -len("_sim")] for v in al.data_vars if str(v).endswith("_sim")]
    out = []
    for name in names:
        if f"{name}_meas" not in al:
            continue
        sim = al[f"{name}_sim"]
        comps = [str(c) for c in al["axis"].values] if "axis" in sim.dims else [None]
        out += [(name, c) for c in comps]
    return out


def _column(al: xr.Dataset, var: str, c: str | None) -> np.ndarray:
    da = al[var]
    return np.asarray(da.sel(axis=c).values if c else da.values, dtype=float)


def rms_quantities(al: xr.Dataset) -> dict[str, float]:
    """RMS of every simulated component over the samples where the measurement is finite."""
    out = {}
    for name, c in components(al):
        s = _column(al, f"{name}_sim", c)
        d = _column(al, f"{name}_meas", c)
        ok = np.isfinite(s) & np.isfinite(d)
        if ok.sum() >= 4:
            out[f"{name}_{c}_rms" if c else f"{name}_rms"] = float(np.sqrt(np.mean(s[ok] ** 2)))
    return out


def _sg_resolution(c_max: float, al: xr.Dataset) -> str:
    """What C <= c_max can detect, in closed form: a pure amplitude error S = a D has
    M = a - 1, P = 0; a pure phase shift of a sinusoid P = shift / pi."""
    text = (
        f"detects an amplitude error beyond ±{c_max:.0%} (M alone) or a phase error beyond "
        f"{c_max * 180:.0f} degree of the signal's own period (P alone)"
    )
    if al.attrs.get("alignment_method") != "crank_angle":
        text += "; a constant phase error was removed by the alignment first (motion_alignment)"
    return text


def _shift_rows(al: xr.Dataset, rows: Rows) -> None:
    """The alignment's time shift as a quantity with its u (a phase error removed by the
    cross-correlation is a model error: reported, never silently dropped)."""
    a = al.attrs
    if "time_shift_s" not in a:
        return
    period = float(a.get("period_s", np.nan))
    how = (
        "crank angle matched on both sides: a clock offset between the records"
        if a.get("alignment_method") == "crank_angle"
        else "removed by cross-correlation before the history criteria: a phase error of the "
        "model of this size is not judged by them"
    )
    rows.add("motion_alignment", "time_shift", float(a["time_shift_s"]), "s", how)
    u = float(a.get("time_shift_u_s", np.nan))
    rows.add("motion_alignment", "time_shift_u", u, "s", str(a.get("time_shift_u_basis", "")))
    rows.add("motion_alignment", "phase_shift", float(a["time_shift_s"]) / period * 360.0,
             "degree", how)  # fmt: skip
    rows.add("motion_alignment", "phase_shift_u", u / period * 360.0, "degree")


def motion_metrics(
    al: xr.Dataset, rows: Rows, decisions: list[dict[str, Any]], src: Sources
) -> None:
    """Metric rows and decisions of the aligned motion ``al``."""
    criteria = src.criteria
    _shift_rows(al, rows)
    for name, c in components(al):
        s = _column(al, f"{name}_sim", c)
        d = _column(al, f"{name}_meas", c)
        units = str(al[f"{name}_sim"].attrs.get("units", "1"))
        ok = np.isfinite(s) & np.isfinite(d)
        if ok.sum() < 4:
            continue
        s, d = s[ok], d[ok]
        q = f"{name}_{c}" if c else name
        label = q.replace("_", " ")
        rows.add(q, "rmse", mt.rmse(s, d), units)
        rows.add(q, "nrmse", mt.nrmse(s, d), units)
        rows.add(q, "pearson_r", mt.pearson_r(s, d), units)
        sg = mt.sprague_geers(s, d)
        rows.add(q, "sg_magnitude", sg.M, units)
        rows.add(q, "sg_phase", sg.P, units)
        rows.add(q, "sg_comprehensive", sg.C, units)
        rows.add(q, "area_validation_metric", mt.area_validation_metric(s, d), units)
        decisions.append(
            decision(
                f"{label} history",
                f"Sprague-Geers C <= {criteria.motion_sg_c_max:g}",
                f"C = {sg.C:.3g} (M = {sg.M:+.3g}, P = {sg.P:.3g})",
                threshold_state(sg.C <= criteria.motion_sg_c_max, bool(np.isfinite(sg.C))),
                "threshold",
                resolution=_sg_resolution(criteria.motion_sg_c_max, al),
            )
        )
        u = {}
        for side in ("sim", "meas"):
            uname = f"{name}_{side}_u"
            if uname in al:
                u[side] = _column(al, uname, c)[ok]
        rms_s = float(np.sqrt(np.mean(s**2)))
        rms_d = float(np.sqrt(np.mean(d**2)))
        rms_u = {k: float(np.sqrt(np.nanmean(v**2))) for k, v in u.items()}
        quantity = f"{q}_rms"
        budget = src.budget(
            quantity, rms_s, "motion", sim_u=rms_u.get("sim"), meas_u=rms_u.get("meas")
        )
        error = scalar_discrepancy(rms_s, rms_d, units, criteria.relative_error_max)
        vv20_decision(rows, decisions, quantity, f"{label} RMS", error, budget)
