"""Wear-map criteria: shape, location and size of the maximum, volume, cylindricity, coverage."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import xarray as xr

import jointwear.compare.metrics as mt
import jointwear.compare.verdicts as vd
from jointwear.compare._decide import (
    Rows,
    decision,
    fmt,
    scalar_discrepancy,
    threshold_state,
    vv20_decision,
)
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


def band_label(al: xr.Dataset) -> str:
    """``"within z = -6…+6 mm"`` (and the measured share of the circumference, if partial)."""
    lo, hi = (float(v) for v in np.ravel(al.attrs["z_overlap_m"]))
    text = f"within z = {lo * 1e3:+.3g}…{hi * 1e3:+.3g} mm"
    arc = float(al.attrs.get("theta_fraction_measured", 1.0))
    if arc < 1.0:
        text += f", {arc:.0%} of the circumference"
    return text.replace("-", "−")


def validation_domain(al: xr.Dataset, rows: Rows) -> str:
    """What of the simulation lies outside the measured band: an extrapolation statement.

    Adds ``validation_domain`` rows (global simulated maximum, its location, the share of the
    simulated worn volume outside the band) and returns the sentence for the card ('' when the
    band holds the whole simulated map).
    """
    a = al.attrs
    frac = float(a.get("volume_fraction_compared", np.nan))
    gmax, gz, gth = (
        float(a.get(k, np.nan)) for k in ("sim_max_value_m", "sim_max_z_m", "sim_max_theta_deg")
    )
    q = "validation_domain"
    rows.add(q, "sim_global_max", gmax, "m", "whole simulated map")
    rows.add(q, "sim_global_max_z", gz, "m", "whole simulated map")
    rows.add(q, "sim_global_max_theta", gth, "m", "whole simulated map")
    rows.add(q, "volume_fraction_outside", 1.0 - frac, "m", "share of the simulated worn volume")
    outside = 1.0 - frac if np.isfinite(frac) else 0.0
    if int(a.get("sim_max_inside", 1)) and outside <= 1e-3:
        return ""
    where = "outside" if not int(a.get("sim_max_inside", 1)) else "inside"
    return (
        f"validation domain: the wear criteria are decided {band_label(al)} only. Outside it "
        f"the simulation is an extrapolation, not validated: its global maximum "
        f"({gmax * 1e6:.3g} µm at z = {gz * 1e3:+.2f} mm, theta {gth:.0f} degree) lies {where} "
        f"the band and {outside:.0%} of the simulated worn volume lies outside it"
    )


def _u_field(al: xr.Dataset, name: str) -> tuple[np.ndarray | None, str]:
    # an all-NaN uncertainty (e.g. a fixed-interval wear run: accuracy not assessed) is not
    # stated, the same as an absent one
    if name not in al:
        return None, ""
    u = np.asarray(al[name].values, dtype=float)
    return (u, str(al[name].attrs.get("basis", ""))) if np.isfinite(u).any() else (None, "")


def _cell_u(al: xr.Dataset, name: str, u: np.ndarray, basis: str) -> tuple[np.ndarray, str]:
    """The u of each grid value: the per-point u ``u`` split, when the map states its
    independent part (``{name}_random``), into the systematic part sqrt(u^2 - u_random^2) per
    point (correlated over the map: not reduced by the cell averaging) and the independent part
    reduced by it (:func:`jointwear.compare.align._random_on_grid`), combined in quadrature.
    Without that part (older files, simulated maps) the per-point u itself, as before."""
    rname = f"{name}_random"
    if rname not in al:
        return u, basis
    r_cell = np.asarray(al[rname].values, dtype=float)
    factor = float(al[rname].attrs.get("per_point_factor", 1.0))
    if not (np.isfinite(r_cell).any() and 0 < factor <= 1):
        return u, basis
    known = np.isfinite(r_cell)  # where the part is not stated the per-point u stays whole
    r_point = np.where(known, np.minimum(r_cell / factor, u), 0.0)
    cell = np.sqrt(u**2 - (1.0 - factor**2) * r_point**2)  # sys^2 + (factor r_point)^2
    return cell, f"{basis}; its independent part averaged over the cell: {al[rname].attrs['basis']}"


def _simulated_edge(al: xr.Dataset, side: int) -> float | None:
    """z [m] of the whole simulated map's first (``side`` -1) or last (+1) layer, or None."""
    if "z_sim" not in al.coords or al["z_sim"].size == 0:
        return None
    z_sim = np.asarray(al["z_sim"].values, dtype=float)
    return float(z_sim.min() if side < 0 else z_sim.max())


def _edge_max(f: np.ndarray) -> int:
    """-1 / +1 when the maximum of ``f`` lies on the first / last layer of the band, else 0."""
    i = int(np.unravel_index(np.nanargmax(f), f.shape)[0])
    return -1 if i == 0 else (1 if i == f.shape[0] - 1 else 0)


def _stated_volume_u(al: xr.Dataset, d_volume: float) -> tuple[float, str] | None:
    """The measurement's own worn_volume_u (converted by k) when it is of the compared band.

    It is, when the band is the map's whole width and circumference and the map's own
    ``worn_volume`` agrees with the volume of the compared map ``d_volume`` within 5 % (a map
    cut after the volume was computed keeps a stale value: then the per-point u is used).
    """
    value = al.attrs.get("worn_volume_u_meas")
    own = float(al.attrs.get("worn_volume_meas_stated", np.nan))
    if value is None or not np.isfinite(float(value)):
        return None
    if not (np.isfinite(d_volume) and abs(own - d_volume) <= 0.05 * abs(d_volume)):
        return None
    lo, hi = (float(v) for v in np.ravel(al.attrs["z_overlap_m"]))
    zlo, zhi = (float(v) for v in np.ravel(al.attrs["z_range_meas_m"]))
    whole = abs(lo - zlo) < 1e-9 and abs(hi - zhi) < 1e-9
    if not whole or float(al.attrs.get("theta_fraction_measured", 1.0)) < 1.0:
        return None
    return float(value), str(al.attrs.get("worn_volume_u_meas_basis", ""))


def _stated(al: xr.Dataset, s: np.ndarray, d: np.ndarray) -> dict[str, tuple]:
    """Per quantity: ((u_sim, note), (u_meas, note)) from the per-point and derived ``_u``."""
    z = np.asarray(al["z"].values)
    th = np.asarray(al["theta"].values)
    radius = al.attrs.get("bearing_radius_m")
    out: dict[str, tuple] = {}
    sides = {
        "sim": (_u_field(al, "wear_depth_sim_u"), s),
        "meas": (_u_field(al, "wear_depth_meas_u"), d),
    }
    for side, ((u, basis), f) in sides.items():
        if u is None:
            for name in ("max_wear_depth", "worn_volume", "cylindricity"):
                out.setdefault(name, {})[side] = (None, "")
            continue
        cell, cell_basis = _cell_u(al, f"wear_depth_{side}_u", u, basis)
        what = "per-point u" if cell is u else "u of the grid value"
        i, j = np.unravel_index(np.nanargmax(f), f.shape)
        out.setdefault("max_wear_depth", {})[side] = (
            float(cell[i, j]),
            f"{what} at the maximum ({cell_basis})",
        )
        vol = mt.worn_volume(u, z, th, float(radius)) if radius else None
        out.setdefault("worn_volume", {})[side] = (
            vol,
            f"per-point u integrated over the band as fully correlated (an upper bound; {basis})",
        )
        out.setdefault("cylindricity", {})[side] = (
            math.sqrt(2) * float(np.sqrt(np.nanmean(cell**2))),
            f"√2 · rms of the {what} (peak-to-valley of two independent points; {cell_basis})",
        )
    vol_meas = _stated_volume_u(al, mt.worn_volume(d, z, th, float(radius)) if radius else np.nan)
    if vol_meas is not None:
        out["worn_volume"]["meas"] = (
            vol_meas[0],
            f"the measurement's worn_volume_u over its whole band ({vol_meas[1]})",
        )
    return out


def _calibration(name: str, meas: float, al: xr.Dataset, d: np.ndarray, criteria) -> list:
    """The user-stated calibration terms of the instrument, ``(u, basis)``, for u_D of ``name``
    (measured value ``meas``; ``d`` the measured map on the band)."""
    out = []
    gain = criteria.gain_u_rel
    if gain is not None:
        out.append((gain * abs(meas), f"user-stated instrument gain u {gain:.3g}·|D| (gain_u_rel)"))
    probe = criteria.probe_u_m
    radius = al.attrs.get("bearing_radius_m")
    if probe is not None and name == "max_wear_depth":
        out.append((probe, f"user-stated radial offset u {fmt(probe, 'm')} (probe_u_m)"))
    elif probe is not None and name == "worn_volume" and radius:
        z, th = np.asarray(al["z"].values), np.asarray(al["theta"].values)
        area = mt.worn_volume(np.where(np.isfinite(d), 1.0, np.nan), z, th, float(radius))
        out.append(
            (
                probe * area,
                f"user-stated radial offset u {fmt(probe, 'm')} (probe_u_m) over the band's "
                f"area {area * 1e6:.3g} mm²",
            )
        )
    return out


@dataclass(frozen=True)
class WearCase:
    """What every wear criterion reads: the aligned maps on the band and what was derived.

    Attributes
    ----------
    al : Dataset
        The aligned maps (:func:`jointwear.compare.align.align_wear_maps`).
    s, d : ndarray
        Simulated and measured wear depth on the band, ``(z, theta)`` [m].
    rows, decisions, src
        The metrics table, the decision card and the uncertainty sources of the comparison.
    band : str
        The band's label (:func:`band_label`).
    peak_nc, whole_nc : str
        Why the maximum / the whole-map criteria are not comparable ('' when they are).
    sim_max, meas_max : (float, float, float)
        Value [m], z [m] and angle [degree] of each maximum (:func:`metrics.max_location`).
    """

    al: xr.Dataset
    s: np.ndarray
    d: np.ndarray
    rows: Rows
    decisions: list[dict[str, Any]]
    src: Sources
    band: str
    peak_nc: str
    whole_nc: str
    sim_max: tuple[float, float, float]
    meas_max: tuple[float, float, float]

    @property
    def z(self) -> np.ndarray:
        return np.asarray(self.al["z"].values)

    @property
    def criteria(self):
        return self.src.criteria


def angle_criterion(c: WearCase) -> None:
    """Angle of the maximum wear against ``max_angle_error_deg``."""
    ts, td = c.sim_max[2], c.meas_max[2]
    ang = float(mt.wrap_angle_deg(ts - td))
    c.decisions.append(
        decision(
            f"angle of maximum wear {c.band}",
            f"|error| <= {c.criteria.max_angle_error_deg:g} degree",
            f"{ang:+.1f} degree (sim {ts:.1f}, meas {td:.1f})",
            vd.NOT_COMPARABLE
            if c.peak_nc
            else threshold_state(abs(ang) <= c.criteria.max_angle_error_deg),
            "threshold",
            c.peak_nc,
            key="wear_depth",
        )
    )


def axial_criterion(c: WearCase) -> None:
    """Axial position of the maximum wear against ``max_z_error_m``."""
    zs, zd, z = c.sim_max[1], c.meas_max[1], c.z
    z_nc = c.peak_nc
    edge_s, edge_d = _edge_max(c.s), _edge_max(c.d)
    if not z_nc and z.size > 1 and edge_s != 0 and edge_s == edge_d:
        edge = float(z[0 if edge_s < 0 else -1])
        face = _simulated_edge(c.al, edge_s)
        # on the simulated map's own edge (the bearing face), nothing lies beyond: both maxima
        # are located there and the criterion is decided; inside it, the band cannot tell
        if face is None or abs(edge - face) > 1e-6:
            beyond = (
                f"; a measured map reaching z = {face * 1e3:+.2f} mm (the simulated map's edge, "
                "the bearing face) would decide it"
                if face is not None
                else ""
            )
            z_nc = (
                f"both maxima {c.band} lie on its edge layer z = {edge * 1e3:+.2f} mm: the wear "
                f"grows towards the edge on both sides and the band cannot show where either "
                f"maximum is{beyond}"
            )
    c.decisions.append(
        decision(
            f"axial position of maximum wear {c.band}",
            f"|error| <= {c.criteria.max_z_error_m * 1e3:g} mm",
            f"{(zs - zd) * 1e3:+.2f} mm (sim {zs * 1e3:+.2f}, meas {zd * 1e3:+.2f})",
            vd.NOT_COMPARABLE
            if z_nc
            else threshold_state(abs(zs - zd) <= c.criteria.max_z_error_m + 1e-12),
            "threshold",
            z_nc,
            key="wear_depth",
        )
    )


#: the V&V 20 band quantities: card label and units
_LABELS = {
    "max_wear_depth": ("maximum wear depth", "m"),
    "worn_volume": ("worn volume", "m3"),
    "cylindricity": ("cylindricity of the wear (LSCY)", "m"),
}


def vv20_band_criterion(name: str):
    """The V&V 20 decision of the band quantity ``name`` (a key of :func:`sim_quantities`)."""

    def decide(c: WearCase) -> None:
        sim_q = sim_quantities(c.al)
        if name not in sim_q:
            return
        meas_q = sim_quantities(c.al, "wear_depth_meas")
        value = sim_q[name] if name != "max_wear_depth" else c.sim_max[0]
        meas = meas_q[name] if name != "max_wear_depth" else c.meas_max[0]
        (us, us_note), (ud, ud_note) = (_stated(c.al, c.s, c.d)[name][k] for k in ("sim", "meas"))
        budget = c.src.budget(
            name,
            value,
            "wear",
            sim_u=us,
            meas_u=ud,
            sim_note=us_note,
            meas_note=f"stated by the measurement: {ud_note}" if ud_note else "",
            calibration=_calibration(name, meas, c.al, c.d, c.criteria),
        )
        label, units = _LABELS[name]
        vv20_decision(
            c.rows,
            c.decisions,
            name,
            f"{label} {c.band}",
            scalar_discrepancy(value, meas, units, c.criteria.relative_error_max),
            budget,
            not_comparable=c.peak_nc if name == "max_wear_depth" else c.whole_nc,
        )

    return decide


def wear_metrics(al: xr.Dataset, rows: Rows, decisions: list[dict[str, Any]], src: Sources) -> str:
    """Metric rows and decisions of the aligned wear maps ``al``; returns the domain statement.

    Every criterion is decided on the band the measurement covers and labelled so; what lies
    outside is the validation-domain statement (returned), never a verdict. With
    ``criteria.strict_coverage`` the old rule applies: a simulated maximum outside the band, or
    more than ``max_volume_outside`` of the volume, makes the criteria *not comparable*. The
    criteria decided are the wear rows of :data:`jointwear.compare.registry.CRITERIA`, in order.
    """
    from jointwear.compare.registry import criteria_of

    criteria = src.criteria
    s = np.asarray(al["wear_depth_sim"].values)
    d = np.asarray(al["wear_depth_meas"].values)
    z = np.asarray(al["z"].values)
    th = np.asarray(al["theta"].values)
    q = "wear_depth"
    if criteria.strict_coverage:
        peak_nc, whole_nc = coverage(al, criteria.max_volume_outside)
    else:
        peak_nc = whole_nc = ""
    domain = validation_domain(al, rows)
    frac = float(al.attrs.get("volume_fraction_compared", np.nan))
    rows.add(q, "volume_fraction_compared", frac, "m")
    rows.add(q, "rmse", mt.rmse(s, d), "m")
    rows.add(q, "nrmse", mt.nrmse(s, d), "m")
    rows.add(q, "pearson_r", mt.pearson_r(s, d), "m")
    rows.add(q, "mean_error", float(np.nanmean(s - d)), "m")
    rows.add(q, "max_abs_error", float(np.nanmax(np.abs(s - d))), "m")
    rows.add(q, "area_validation_metric", mt.area_validation_metric(s, d), "m")
    sim_max, meas_max = mt.max_location(s, z, th), mt.max_location(d, z, th)
    rows.add(q, "max_angle_error", float(mt.wrap_angle_deg(sim_max[2] - meas_max[2])), "m")
    rows.add(q, "max_z_error", sim_max[1] - meas_max[1], "m")
    case = WearCase(
        al, s, d, rows, decisions, src, band_label(al), peak_nc, whole_nc, sim_max, meas_max
    )
    for entry in criteria_of("wear"):
        entry.decide(case)
    cs, cd = al.attrs.get("cylindricity_stated_sim_m"), al.attrs.get("cylindricity_stated_meas_m")
    if cs is not None and cd is not None:
        rows.add("cylindricity_stated", "value_sim", float(cs), "m")
        rows.add("cylindricity_stated", "value_meas", float(cd), "m")
        rows.add("cylindricity_stated", "E", float(cs) - float(cd), "m")
    return domain
