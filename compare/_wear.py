"""Wear-map criteria: shape, location and size of the maximum, volume, cylindricity, coverage."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import xarray as xr

import jointwear.compare.metrics as mt
import jointwear.compare.verdicts as vd
from jointwear.compare._decide import Rows, decision, scalar_decision, threshold_state
from jointwear.compare.sources import Sources


def sim_quantities(al: xr.Dataset, variable: str = "wear_depth_sim") -> dict[str, float]:
    """The compared scalar quantities of the simulated map of an aligned dataset."""
    s = np.asarray(al[variable].values, dtype=float)
    z = np.asarray(al["z"].values, dtype=float)
    th = np.asarray(al["theta"].values, dtype=float)
    out = {"max_wear_depth": mt.max_location(s, z, th)[0]}
    radius = al.attrs.get("bearing_radius_m")
    if radius is not None and len(z) > 1:
        out["worn_volume"] = mt.worn_volume(s, z, th, float(radius))
    if len(z) > 1:
        out["cylindricity"] = mt.lsq_cylindricity(s, z, th)
    return out


def coverage(al: xr.Dataset, max_outside: float) -> tuple[str, str]:
    """Why the maximum / the whole-map criteria are not comparable ('' when they are)."""
    a = al.attrs
    lo, hi = (float(v) for v in np.ravel(a["z_overlap_m"]))
    window = f"the measurement covers z = {lo * 1e3:+.2f} to {hi * 1e3:+.2f} mm"
    arc = float(a.get("theta_fraction_measured", 1.0))
    if arc < 1.0:
        window += f" and {arc:.0%} of the circumference"
    peak = ""
    if not int(a.get("sim_max_inside", 1)):
        peak = (
            f"the simulated maximum ({float(a['sim_max_value_m']) * 1e6:.3g} µm at z = "
            f"{float(a['sim_max_z_m']) * 1e3:+.2f} mm, theta {float(a['sim_max_theta_deg']):.0f} "
            f"degree) lies outside the compared range: {window}"
        )
    whole = ""
    frac = float(a.get("volume_fraction_compared", 1.0))
    if np.isfinite(frac) and 1.0 - frac > max_outside:
        whole = (
            f"{1 - frac:.0%} of the simulated worn volume lies outside the compared range "
            f"({window}; at most {max_outside:.0%} may, criteria max_volume_outside)"
        )
    return peak, whole


def wear_metrics(al: xr.Dataset, rows: Rows, decisions: list[dict[str, Any]], src: Sources) -> None:
    """Metric rows and decisions of the aligned wear maps ``al``."""
    criteria = src.criteria
    s = np.asarray(al["wear_depth_sim"].values)
    d = np.asarray(al["wear_depth_meas"].values)
    z = np.asarray(al["z"].values)
    th = np.asarray(al["theta"].values)
    q = "wear_depth"
    peak_nc, whole_nc = coverage(al, criteria.max_volume_outside)
    frac = float(al.attrs.get("volume_fraction_compared", np.nan))
    rows.add(q, "volume_fraction_compared", frac, "m")
    rows.add(q, "rmse", mt.rmse(s, d), "m")
    nr = mt.nrmse(s, d)
    rows.add(q, "nrmse", nr, "m")
    r = mt.pearson_r(s, d)
    rows.add(q, "pearson_r", r, "m")
    rows.add(q, "mean_error", float(np.nanmean(s - d)), "m")
    rows.add(q, "max_abs_error", float(np.nanmax(np.abs(s - d))), "m")
    rows.add(q, "area_validation_metric", mt.area_validation_metric(s, d), "m")
    vs, zs, ts = mt.max_location(s, z, th)
    vd_, zd, td = mt.max_location(d, z, th)
    ang = float(mt.wrap_angle_deg(ts - td))
    rows.add(q, "max_angle_error", ang, "m")
    rows.add(q, "max_z_error", zs - zd, "m")
    ok_shape = bool(nr <= criteria.wear_nrmse_max and r >= criteria.wear_r_min)
    decisions.append(
        decision(
            "wear map shape",
            f"NRMSE <= {criteria.wear_nrmse_max:g} and r >= {criteria.wear_r_min:g}",
            f"NRMSE = {nr:.3g}, r = {r:.3g}",
            vd.NOT_COMPARABLE
            if whole_nc
            else threshold_state(ok_shape, bool(np.isfinite(nr) and np.isfinite(r))),
            "threshold",
            whole_nc,
        )
    )
    decisions.append(
        decision(
            "angle of maximum wear",
            f"|error| <= {criteria.max_angle_error_deg:g} degree",
            f"{ang:+.1f} degree (sim {ts:.1f}, meas {td:.1f})",
            vd.NOT_COMPARABLE
            if peak_nc
            else threshold_state(abs(ang) <= criteria.max_angle_error_deg),
            "threshold",
            peak_nc,
        )
    )
    decisions.append(
        decision(
            "axial position of maximum wear",
            f"|error| <= {criteria.max_z_error_m * 1e3:g} mm",
            f"{(zs - zd) * 1e3:+.2f} mm (sim {zs * 1e3:+.2f}, meas {zd * 1e3:+.2f})",
            vd.NOT_COMPARABLE
            if peak_nc
            else threshold_state(abs(zs - zd) <= criteria.max_z_error_m + 1e-12),
            "threshold",
            peak_nc,
        )
    )

    def stated_u(name: str) -> np.ndarray | None:
        # an all-NaN uncertainty (e.g. a fixed-interval wear run: accuracy not assessed) is
        # not stated, the same as an absent one
        if name not in al:
            return None
        u = np.asarray(al[name].values, dtype=float)
        return u if np.isfinite(u).any() else None

    us = stated_u("wear_depth_sim_u")
    ud = stated_u("wear_depth_meas_u")

    def at_max(u: np.ndarray | None, f: np.ndarray) -> float | None:
        if u is None:
            return None
        i, j = np.unravel_index(np.nanargmax(f), f.shape)
        return float(u[i, j])

    sim_q = sim_quantities(al)
    meas_q = sim_quantities(al, "wear_depth_meas")
    radius = al.attrs.get("bearing_radius_m")
    rms_u = (  # noqa: E731
        lambda u: math.sqrt(2) * float(np.sqrt(np.nanmean(u**2))) if u is not None else None
    )
    stated = {
        "max_wear_depth": (at_max(us, s), at_max(ud, d)),
        "worn_volume": (
            mt.worn_volume(us, z, th, float(radius)) if us is not None and radius else None,
            mt.worn_volume(ud, z, th, float(radius)) if ud is not None and radius else None,
        ),
        "cylindricity": (rms_u(us), rms_u(ud)),
    }
    labels = {
        "max_wear_depth": "maximum wear depth",
        "worn_volume": "worn volume (compared width)",
        "cylindricity": "cylindricity of the wear (LSCY, common grid)",
    }
    units = {"max_wear_depth": "m", "worn_volume": "m3", "cylindricity": "m"}
    for name in ("max_wear_depth", "worn_volume", "cylindricity"):
        if name not in sim_q:
            continue
        value = sim_q[name] if name != "max_wear_depth" else vs
        meas = meas_q[name] if name != "max_wear_depth" else vd_
        scalar_decision(
            rows,
            decisions,
            name,
            labels[name],
            value,
            meas,
            units[name],
            u_num=src.u_num(name, value, stated[name][0], "wear"),
            u_input=src.u_input(name, value, "wear"),
            u_d=src.u_d(stated[name][1]),
            k=criteria.k,
            relative_error_max=criteria.relative_error_max,
            not_comparable=peak_nc if name == "max_wear_depth" else whole_nc,
        )
    cs, cd = al.attrs.get("cylindricity_stated_sim_m"), al.attrs.get("cylindricity_stated_meas_m")
    if cs is not None and cd is not None:
        rows.add("cylindricity_stated", "value_sim", float(cs), "m")
        rows.add("cylindricity_stated", "value_meas", float(cd), "m")
        rows.add("cylindricity_stated", "E", float(cs) - float(cd), "m")
