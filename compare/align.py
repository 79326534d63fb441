"""Putting simulation and measurement on one grid: wear maps over (z, theta), motion over time.

Wear maps
    Both maps are converted to the canonical angle convention (a map that does not state its
    convention is refused), restricted to the axial range both cover, and brought onto one
    grid: ``theta`` uniform over [0, 360) with the coarser of the two angular steps, ``z`` the
    layers of the map with more layers inside the overlap (no layer of either map is skipped
    over; the other map is interpolated linearly between its layers). A map sampled much more finely than
    the common grid (an instrument's 18000 points per layer) is first averaged over each grid
    cell (periodic box mean of one grid step), so the comparison is not aliased; otherwise
    values are interpolated linearly (periodically in theta, linearly in z, never
    extrapolated). The method used for each side is stated in the ``interpolation`` attribute.

Time series
    The measurement's time stamps (e.g. 50 frames/s of the DIC footage, restricted to whole
    crank cycles) are the common time base; the simulation (variable step) is interpolated
    linearly onto them. The two records are put in phase by the crank angle when the
    measurement has one (each frame is compared with the simulated instant at the same crank
    angle, taken from the simulation's last whole cycle: steady periodic motion is assumed),
    else by maximising the cross-correlation of the (normalised) signals over whole cycles.
    The time shift is reported in ``time_shift_s`` (simulation time = measurement time -
    shift, modulo the period).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import xarray as xr

from jointwear import conventions
from jointwear.errors import BadInputError, ConventionError

__all__ = ["align_wear_maps", "align_time_series", "MOTION_VARIABLES", "to_metres"]

#: time-series variables compared by default when both sides have them (contract names).
#: Positions (``follower_position``) are left out: they depend on where each record puts its
#: origin (a DIC calibration's world frame is the board's); ask for them explicitly.
MOTION_VARIABLES = (
    "follower_velocity",
    "journal_offset",
    "journal_displacement",
    "contact_force",
)

_LENGTH_FACTORS = {
    "m": 1.0,
    "metre": 1.0,
    "meter": 1.0,
    "mm": 1e-3,
    "um": 1e-6,
    "µm": 1e-6,
    "μm": 1e-6,
    "micrometre": 1e-6,
    "micrometer": 1e-6,
    "micron": 1e-6,
}


def to_metres(da: xr.DataArray, what: str) -> xr.DataArray:
    """Return a length variable in metres (converting mm/µm), or refuse an unknown unit."""
    units = str(da.attrs.get("units", "")).strip()
    if units not in _LENGTH_FACTORS:
        raise ConventionError(
            f"{what}: units {units!r} of '{da.name}' are not a length jointwear understands; "
            "expected 'm' (the contract), 'mm' or 'um'"
        )
    factor = _LENGTH_FACTORS[units]
    if factor == 1.0:
        return da
    out = da * factor
    out.attrs = {**da.attrs, "units": "m", "comment": f"converted from {units}"}
    return out


# --------------------------------------------------------------------------- wear maps


def _pick_cycles(
    da: xr.DataArray, ds: xr.Dataset, cycles: float | None, what: str
) -> tuple[xr.DataArray, float | None, str]:
    """Select one wear snapshot; return it, its cycle count and how it was chosen."""
    if "cycles" in da.dims:
        values = np.asarray(da["cycles"].values, dtype=float)
        if cycles is None:
            return da.isel(cycles=-1), float(values[-1]), "last snapshot"
        exact = np.isclose(values, cycles, rtol=1e-9, atol=0)
        if np.any(exact):
            idx = int(np.argmax(exact))
            return da.isel(cycles=idx), float(values[idx]), "snapshot at the requested cycles"
        if values.size >= 2 and values.min() <= cycles <= values.max():
            out = da.interp(cycles=cycles, method="linear")
            return out, float(cycles), "linear interpolation between the two nearest snapshots"
        raise BadInputError(
            f"{what}: no wear snapshot at {cycles:g} cycles; it has snapshots at "
            f"{', '.join(f'{v:g}' for v in values)} - run the simulation up to that number of "
            "cycles or pass cycles= / --cycles with one of these values"
        )
    stated = None
    if "cycles" in da.coords and da["cycles"].ndim == 0:
        stated = float(da["cycles"].values)
    elif "cycles" in ds.attrs:
        try:
            stated = float(ds.attrs["cycles"])
        except (TypeError, ValueError):
            stated = None
    return da, stated, "single map"


def _theta_step(theta: np.ndarray) -> float:
    if theta.size < 2:
        raise BadInputError("a wear map needs at least 2 angles per layer")
    return float(np.median(np.diff(np.sort(theta))))


def _periodic_interp(
    theta_src: np.ndarray, values: np.ndarray, theta_tgt: np.ndarray
) -> np.ndarray:
    """Linear interpolation in theta [degree], periodic over 360, along the last axis."""
    order = np.argsort(theta_src)
    th = theta_src[order]
    v = values[..., order]
    th_ext = np.concatenate([[th[-1] - 360.0], th, [th[0] + 360.0]])
    v_ext = np.concatenate([v[..., -1:], v, v[..., :1]], axis=-1)
    flat = v_ext.reshape(-1, v_ext.shape[-1])
    out = np.stack([np.interp(theta_tgt, th_ext, row) for row in flat])
    return out.reshape(*values.shape[:-1], theta_tgt.size)


def _periodic_box_mean(
    theta_src: np.ndarray, values: np.ndarray, theta_tgt: np.ndarray, width: float
) -> np.ndarray:
    """Mean of the samples within +-width/2 of each target angle (periodic), NaN-aware."""
    order = np.argsort(theta_src)
    th = theta_src[order]
    v = values[..., order]
    th_ext = np.concatenate([th - 360.0, th, th + 360.0])
    v_ext = np.concatenate([v, v, v], axis=-1)
    finite = np.isfinite(v_ext)
    cs = np.concatenate(
        [np.zeros(v_ext.shape[:-1] + (1,)), np.cumsum(np.where(finite, v_ext, 0.0), axis=-1)],
        axis=-1,
    )
    cn = np.concatenate([np.zeros(v_ext.shape[:-1] + (1,)), np.cumsum(finite, axis=-1)], axis=-1)
    lo = np.searchsorted(th_ext, theta_tgt - width / 2, side="left")
    hi = np.searchsorted(th_ext, theta_tgt + width / 2, side="left")
    total = cs[..., hi] - cs[..., lo]
    count = cn[..., hi] - cn[..., lo]
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(count > 0, total / np.maximum(count, 1), np.nan)


def _prepare_map(
    obj: xr.Dataset | xr.DataArray, variable: str, cycles: float | None, what: str
) -> tuple[xr.DataArray, xr.DataArray | None, float | None, str, xr.Dataset]:
    ds = obj.to_dataset(name=obj.name or variable) if isinstance(obj, xr.DataArray) else obj
    name = variable if variable in ds else (obj.name if isinstance(obj, xr.DataArray) else None)
    if name is None or name not in ds:
        raise BadInputError(
            f"{what} has no '{variable}' variable (found: {', '.join(map(str, ds.data_vars)) or 'none'})"
        )
    da = ds[name]
    for dim in ("z", "theta"):
        if dim not in da.dims:
            raise BadInputError(
                f"{what}: '{name}' has dims {da.dims}, expected ('cycles',) 'z', 'theta'"
            )
    try:
        conventions.angle_convention_of(da, what=what)
    except ConventionError as exc:
        raise ConventionError(
            f"{exc}. Refusing to compare a wear map whose angle convention is not stated."
        ) from None
    da = to_metres(da, what)
    unc = None
    uname = f"{name}_u"
    if uname in ds:
        unc = to_metres(ds[uname], what)
    da, n_cycles, how = _pick_cycles(da, ds, cycles, what)
    if unc is not None:
        unc, _, _ = _pick_cycles(unc, ds, n_cycles if "cycles" in unc.dims else None, what)
    zattrs = da["z"].attrs
    if str(zattrs.get("z_direction", "+z")).strip() == "-z":
        da = da.assign_coords(z=-da["z"])
        if unc is not None:
            unc = unc.assign_coords(z=-unc["z"])
    elif str(zattrs.get("z_direction", "+z")).strip() not in ("+z", "z"):
        raise ConventionError(
            f"{what}: z_direction {zattrs.get('z_direction')!r} not understood; use '+z' or '-z'"
        )
    zero = str(zattrs.get("z_zero", "bearing mid-width")).strip().lower()
    if zero not in ("bearing mid-width", "mid-width", "bearing midwidth"):
        raise ConventionError(
            f"{what}: z is measured from {zattrs.get('z_zero')!r}; the contract puts z = 0 at the "
            "bearing mid-width - shift the z coordinate and set z_zero='bearing mid-width'"
        )
    da = conventions.to_canonical(da.transpose("z", "theta")).sortby("z")
    if unc is not None:
        unc = conventions.convert_theta(
            unc.transpose("z", "theta"), source=conventions.angle_convention_of(ds[name])
        ).sortby("z")
    return da, unc, n_cycles, how, ds


def _bearing_radius(*datasets: xr.Dataset) -> float | None:
    for ds in datasets:
        for key in ("bearing_radius_m", "bearing_radius", "nominal_radius_m"):
            if key in ds.attrs:
                try:
                    value = float(ds.attrs[key])
                except (TypeError, ValueError):
                    continue
                if np.isfinite(value) and value > 0:
                    return value
    return None


def _resample(
    da: xr.DataArray, z_tgt: np.ndarray, theta_tgt: np.ndarray, step: float
) -> tuple[np.ndarray, str]:
    theta = np.asarray(da["theta"].values, dtype=float)
    z = np.asarray(da["z"].values, dtype=float)
    values = np.asarray(da.values, dtype=float)
    own = _theta_step(theta)
    if own < step / 1.5:
        at_theta = _periodic_box_mean(theta, values, theta_tgt, step)
        how_theta = (
            f"periodic box mean over one grid step ({step:.4g} degree, {int(round(step / own))} "
            "samples) in theta"
        )
    elif theta.size == theta_tgt.size and np.allclose(np.sort(theta), theta_tgt, atol=1e-9):
        at_theta = values[:, np.argsort(theta)]
        how_theta = "native theta grid"
    else:
        at_theta = _periodic_interp(theta, values, theta_tgt)
        how_theta = "periodic linear interpolation in theta"
    if z.size == z_tgt.size and np.allclose(z, z_tgt, atol=1e-12):
        return at_theta, how_theta + ", native z layers"
    if z.size == 1:
        raise BadInputError("a single-layer map can only be compared at its own z")
    out = np.empty((z_tgt.size, theta_tgt.size))
    for j in range(theta_tgt.size):
        out[:, j] = np.interp(z_tgt, z, at_theta[:, j])
    return out, how_theta + ", linear interpolation in z between layers"


def align_wear_maps(
    sim: xr.Dataset | xr.DataArray,
    meas: xr.Dataset | xr.DataArray,
    *,
    variable: str = "wear_depth",
    cycles: float | None = None,
    theta_step_deg: float | None = None,
) -> xr.Dataset:
    """Put a simulated and a measured wear map on one canonical ``(z, theta)`` grid.

    Parameters
    ----------
    sim, meas : Dataset or DataArray
        Wear maps with ``wear_depth`` over ``(cycles,) z, theta`` [m] (``mm``/``um`` are
        converted); theta must state its angle convention (``angle_zero``,
        ``angle_direction``) - a map without one is refused with :class:`ConventionError`.
        Optional ``wear_depth_u`` (standard uncertainty) is carried along.
    variable : str
        Name of the compared variable.
    cycles : float, optional
        Crank cycles at which to compare. Default: the measurement's (its single snapshot, a
        scalar ``cycles`` coordinate or a ``cycles`` attribute; else its last snapshot); the
        simulation snapshot is taken at that count (linear interpolation between snapshots).
    theta_step_deg : float, optional
        Angular step of the common grid [degree]; default the coarser of the two.

    Returns
    -------
    Dataset
        Over ``(z, theta)`` (canonical): ``wear_depth_sim``, ``wear_depth_meas``,
        ``wear_depth_diff`` (sim - meas) [m], uncertainties ``*_u`` when given; attributes
        ``interpolation``, ``z_overlap_m``, ``cycles_sim``, ``cycles_meas``,
        ``bearing_radius_m`` (if either input states it).
    """
    m_da, m_u, m_cycles, m_how, m_ds = _prepare_map(meas, variable, cycles, "measured wear map")
    target_cycles = cycles if cycles is not None else m_cycles
    s_da, s_u, s_cycles, s_how, s_ds = _prepare_map(
        sim, variable, target_cycles, "simulated wear map"
    )
    zs = np.asarray(s_da["z"].values, dtype=float)
    zm = np.asarray(m_da["z"].values, dtype=float)
    lo, hi = max(zs.min(), zm.min()), min(zs.max(), zm.max())
    tol = 1e-9
    if hi < lo - tol:
        raise BadInputError(
            f"the wear maps do not overlap axially: simulation z in [{zs.min() * 1e3:.3g}, "
            f"{zs.max() * 1e3:.3g}] mm, measurement z in [{zm.min() * 1e3:.3g}, {zm.max() * 1e3:.3g}] mm;"
            " both must measure z from the bearing mid-width (z_zero)"
        )
    in_s = zs[(zs >= lo - tol) & (zs <= hi + tol)]
    in_m = zm[(zm >= lo - tol) & (zm <= hi + tol)]
    z_src = "measurement" if in_m.size >= in_s.size else "simulation"
    z_tgt = in_m if z_src == "measurement" else in_s
    if z_tgt.size == 0:
        raise BadInputError("no layer of either map lies in the overlapping axial range")
    step_s = _theta_step(np.asarray(s_da["theta"].values))
    step_m = _theta_step(np.asarray(m_da["theta"].values))
    step = float(theta_step_deg) if theta_step_deg is not None else max(step_s, step_m)
    if not (np.isfinite(step) and 0 < step <= 90):
        raise BadInputError(f"theta_step_deg must lie in (0, 90] degree, got {step!r}")
    n = max(4, int(round(360.0 / step)))
    step = 360.0 / n
    theta_tgt = np.arange(n) * step
    s_vals, s_interp = _resample(s_da, z_tgt, theta_tgt, step)
    m_vals, m_interp = _resample(m_da, z_tgt, theta_tgt, step)
    # a measurement with an angular gap (a partial arc) is not interpolated across it: both
    # sides are compared only where the measurement has samples
    covered = _theta_covered(np.asarray(m_da["theta"].values, dtype=float), theta_tgt)
    if not covered.all():
        s_vals = np.where(covered[None, :], s_vals, np.nan)
        m_vals = np.where(covered[None, :], m_vals, np.nan)
        m_interp += f"; {int((~covered).sum())} of {covered.size} grid angles lie in an angular gap of the measurement and are not compared"

    z = conventions.z_coord(z_tgt, note=f"layers of the {z_src} inside the overlapping range")
    theta = conventions.theta_coord(theta_tgt)
    out = xr.Dataset(coords={"z": z, "theta": theta})
    dims = ("z", "theta")
    out[f"{variable}_sim"] = (dims, s_vals, {"units": "m", "long_name": "simulated wear depth"})
    out[f"{variable}_meas"] = (dims, m_vals, {"units": "m", "long_name": "measured wear depth"})
    out[f"{variable}_diff"] = (
        dims,
        s_vals - m_vals,
        {"units": "m", "long_name": "wear depth difference, simulation minus measurement"},
    )
    anc = []
    for unc, side in ((s_u, "sim"), (m_u, "meas")):
        if unc is None:
            continue
        vals, _ = _resample(unc, z_tgt, theta_tgt, step)
        uname = f"{variable}_{side}_u"
        out[uname] = (
            dims,
            vals,
            {"units": "m", "long_name": f"standard uncertainty of {variable}_{side}"},
        )
        out[f"{variable}_{side}"].attrs["ancillary_variables"] = uname
        anc.append(uname)
    radius = _bearing_radius(s_ds, m_ds)
    out = _with_coverage(out, s_da, lo, hi, variable, theta_tgt, covered)
    out.attrs.update(
        {
            "title": "simulated and measured wear maps on a common grid",
            "interpolation": (
                f"common grid: theta uniform, step {step:.6g} degree (canonical convention), "
                f"z = {z_tgt.size} layers of the {z_src} within the overlap; simulation: "
                f"{s_interp}; measurement: {m_interp}; no extrapolation"
            ),
            "z_overlap_m": [float(lo), float(hi)],
            "z_range_sim_m": [float(zs.min()), float(zs.max())],
            "z_range_meas_m": [float(zm.min()), float(zm.max())],
            "cycles_sim": float("nan") if s_cycles is None else float(s_cycles),
            "cycles_meas": float("nan") if m_cycles is None else float(m_cycles),
            "cycles_selection": f"simulation: {s_how}; measurement: {m_how}",
            "angle_convention_sim": _describe(
                conventions.angle_convention_of(
                    sim if isinstance(sim, xr.DataArray) else sim[variable]
                )
            ),
            "angle_convention_meas": _describe(
                conventions.angle_convention_of(
                    meas if isinstance(meas, xr.DataArray) else meas[variable]
                )
            ),
        }
    )
    if radius is not None:
        out.attrs["bearing_radius_m"] = radius
    for side, ds in (("sim", s_ds), ("meas", m_ds)):
        if "cylindricity" in ds.data_vars or "cylindricity" in ds.attrs:
            value = _stated_scalar(ds, "cylindricity", s_cycles if side == "sim" else m_cycles)
            if value is not None and np.isfinite(value):
                out.attrs[f"cylindricity_stated_{side}_m"] = value
    return out


def _volume_between(z: np.ndarray, per_layer: np.ndarray, lo: float, hi: float) -> float:
    """Trapezoid integral of a piecewise-linear per-layer profile over [lo, hi]."""
    lo, hi = max(lo, float(z.min())), min(hi, float(z.max()))
    if hi <= lo:
        return 0.0
    grid = np.unique(np.concatenate([[lo, hi], z[(z > lo) & (z < hi)]]))
    return float(np.trapezoid(np.interp(grid, z, per_layer), grid))


def _theta_covered(theta_src: np.ndarray, theta_tgt: np.ndarray) -> np.ndarray:
    """Target angles [degree] within reach of the source samples (no angular gap), periodic.

    A target angle is covered when a source sample lies within 1.5 source steps (the median
    spacing) of it: a full circle covers everything, a partial arc only itself.
    """
    th = np.sort(np.mod(theta_src, 360.0))
    own = _theta_step(th)
    ext = np.concatenate([th - 360.0, th, th + 360.0])
    idx = np.clip(np.searchsorted(ext, theta_tgt), 1, ext.size - 1)
    dist = np.minimum(np.abs(ext[idx] - theta_tgt), np.abs(ext[idx - 1] - theta_tgt))
    return dist <= 1.5 * own + 1e-9


def _with_coverage(
    out: xr.Dataset,
    s_da: xr.DataArray,
    lo: float,
    hi: float,
    variable: str,
    theta_tgt: np.ndarray,
    covered: np.ndarray,
) -> xr.Dataset:
    """Add the whole simulated map and how much of it the common grid covers.

    ``<variable>_sim_full`` over ``(z_sim, theta_sim)`` (canonical); attributes
    ``sim_max_value_m``, ``sim_max_z_m``, ``sim_max_theta_deg`` (maximum of the whole simulated
    map), ``sim_max_inside`` (1 if it lies in the compared axial range) and
    ``volume_fraction_compared`` (share of the simulated worn volume inside that range).
    """
    z = np.asarray(s_da["z"].values, dtype=float)
    th = np.asarray(s_da["theta"].values, dtype=float)
    h = np.asarray(s_da.values, dtype=float)
    out = out.assign_coords(
        z_sim=xr.DataArray(
            z,
            dims="z_sim",
            attrs={**s_da["z"].attrs, "long_name": "axial position of the simulated map's layers"},
        ),
        theta_sim=xr.DataArray(th, dims="theta_sim", attrs={**s_da["theta"].attrs}),
    )
    out[f"{variable}_sim_full"] = (
        ("z_sim", "theta_sim"),
        h,
        {"units": "m", "long_name": "simulated wear depth over the whole simulated width"},
    )
    tol = 1e-9
    if np.any(np.isfinite(h)):
        i, j = np.unravel_index(np.nanargmax(h), h.shape)
        zmax, tmax, vmax = float(z[i]), float(th[j]), float(h[i, j])
    else:
        zmax = tmax = vmax = float("nan")
    # simulated angles in the measured arc (nearest common-grid angle, periodic)
    step = 360.0 / theta_tgt.size
    in_arc = covered[np.mod(np.rint(np.mod(th, 360.0) / step).astype(int), theta_tgt.size)]
    inside = bool(lo - tol <= zmax <= hi + tol) and (
        not np.isfinite(tmax) or bool(in_arc[int(np.argmin(np.abs(th - tmax)))])
    )
    pos = np.clip(np.nan_to_num(h), 0.0, None)
    per_layer = np.nansum(pos, axis=1)
    per_layer_arc = np.nansum(np.where(in_arc[None, :], pos, 0.0), axis=1)
    total = float(np.trapezoid(per_layer, z)) if z.size > 1 else float(per_layer.sum())
    if z.size > 1 and total > 0:
        fraction = _volume_between(z, per_layer_arc, lo, hi) / total
    elif z.size == 1:
        fraction = 1.0 if inside else 0.0
    else:
        fraction = float("nan")
    out.attrs.update(
        {
            "sim_max_value_m": vmax,
            "sim_max_z_m": zmax,
            "sim_max_theta_deg": tmax,
            "sim_max_inside": int(inside),
            "theta_fraction_measured": float(np.mean(covered)),
            "volume_fraction_compared": float(min(1.0, fraction))
            if np.isfinite(fraction)
            else fraction,
        }
    )
    return out


def _describe(conv: conventions.AngleConvention) -> str:
    return f"theta = 0 along {conv.zero}, increasing {conv.direction} seen from +z"


def _stated_scalar(ds: xr.Dataset, name: str, cycles: float | None) -> float | None:
    """A scalar quantity an input states itself (variable, possibly per snapshot, or attribute)."""
    if name in ds.data_vars:
        var = ds[name]
        if str(var.attrs.get("units", "m")) not in ("m",):
            return None
        if var.ndim == 0:
            return float(var.values)
        if var.dims == ("cycles",):
            vals = np.asarray(var["cycles"].values, dtype=float)
            if cycles is None:
                return float(var.values[-1])
            hit = np.isclose(vals, cycles, rtol=1e-9, atol=0)
            if np.any(hit):
                return float(var.values[int(np.argmax(hit))])
        return None
    try:
        return float(ds.attrs[name])
    except (KeyError, TypeError, ValueError):
        return None


# --------------------------------------------------------------------------- time series


def _time(ds: xr.Dataset, what: str) -> np.ndarray:
    if "time" not in ds.coords:
        raise BadInputError(f"{what} has no 'time' coordinate")
    t = np.asarray(ds["time"].values, dtype=float)
    if t.size < 4:
        raise BadInputError(f"{what} has only {t.size} time samples; at least 4 are needed")
    if np.any(np.diff(t) <= 0):
        raise BadInputError(f"{what}: time is not strictly increasing")
    units = ds["time"].attrs.get("units", "s")
    if units != "s":
        raise ConventionError(f"{what}: time has units {units!r}, the contract says 's'")
    return t


def _period_from_crank(ds: xr.Dataset) -> float | None:
    if "crank_angle" not in ds:
        return None
    t = np.asarray(ds["time"].values, dtype=float)
    phi = np.unwrap(np.asarray(ds["crank_angle"].values, dtype=float))
    if t.size < 2 or not np.all(np.isfinite(phi)):
        return None
    slope = np.polyfit(t - t[0], phi, 1)[0]
    if abs(slope) < 1e-12:
        return None
    return float(2 * math.pi / abs(slope))


def _common_variables(
    sim: xr.Dataset, meas: xr.Dataset, variables: Sequence[str] | None
) -> list[str]:
    if variables is not None:
        missing = [v for v in variables if v not in sim or v not in meas]
        if missing:
            raise BadInputError(
                f"variable(s) {', '.join(missing)} are not in both the simulation and the "
                f"measurement (simulation has {', '.join(map(str, sim.data_vars))}; measurement "
                f"has {', '.join(map(str, meas.data_vars))})"
            )
        return list(variables)
    found = [
        v
        for v in MOTION_VARIABLES
        if v in sim and v in meas and "time" in sim[v].dims and "time" in meas[v].dims
    ]
    if not found:
        raise BadInputError(
            "the simulation and the measurement have no motion variable in common (looked for "
            f"{', '.join(MOTION_VARIABLES)}); simulation has {', '.join(map(str, sim.data_vars))}, "
            f"measurement has {', '.join(map(str, meas.data_vars))}"
        )
    return found


def _components(sim_da: xr.DataArray, meas_da: xr.DataArray, name: str) -> list[str] | None:
    if "axis" not in sim_da.dims and "axis" not in meas_da.dims:
        return None
    if "axis" not in sim_da.dims or "axis" not in meas_da.dims:
        raise BadInputError(f"'{name}' has an 'axis' dimension on one side only")
    common = [
        str(a) for a in meas_da["axis"].values if str(a) in set(map(str, sim_da["axis"].values))
    ]
    if not common:
        raise BadInputError(f"'{name}': the two sides have no vector component in common")
    return common


def _unit_check(sim_da: xr.DataArray, meas_da: xr.DataArray, name: str) -> str:
    us, um = sim_da.attrs.get("units"), meas_da.attrs.get("units")
    if us != um:
        raise ConventionError(
            f"'{name}' has units {us!r} in the simulation and {um!r} in the measurement; convert "
            "one of them to the contract units before comparing"
        )
    return str(us)


def align_time_series(
    sim: xr.Dataset,
    meas: xr.Dataset,
    *,
    variables: Sequence[str] | None = None,
    method: str = "auto",
    period_s: float | None = None,
    whole_cycles: bool = True,
) -> xr.Dataset:
    """Put a simulated and a measured motion record on one time base, in phase.

    Parameters
    ----------
    sim : Dataset
        Simulated motion over ``time`` [s] (any, e.g. variable, step), with ``crank_angle``
        [rad] when available; must cover at least one whole crank cycle.
    meas : Dataset
        Measured motion over ``time`` [s] (e.g. DIC at 50 frames/s).
    variables : sequence of str, optional
        Variables to compare (default: those of :data:`MOTION_VARIABLES` present in both).
    method : {"auto", "crank_angle", "cross_correlation"}
        Phase alignment. ``"auto"``: by crank angle when both sides have ``crank_angle``,
        else by cross-correlation.
    period_s : float, optional
        Crank period [s]; default from the simulation's crank angle rate.
    whole_cycles : bool
        Keep only an integer number of crank cycles of the measurement (default True).

    Returns
    -------
    Dataset
        Over the measurement's ``time`` (and ``axis``): ``<var>_sim``, ``<var>_meas``,
        ``<var>_diff`` (sim - meas), ``<var>_meas_u`` / ``<var>_sim_u`` when given, and
        ``sim_time`` (the simulated instant each sample was taken from). Attributes:
        ``alignment_method``, ``time_shift_s``, ``time_shift_deg`` (crank degrees),
        ``period_s``, ``n_cycles``, ``interpolation``.
    """
    ts = _time(sim, "simulated motion")
    tm = _time(meas, "measured motion")
    names = _common_variables(sim, meas, variables)
    period = period_s if period_s is not None else _period_from_crank(sim)
    if period is None:
        period = _period_from_crank(meas)
    if period is None or not (np.isfinite(period) and period > 0):
        raise BadInputError(
            "cannot tell the crank period: neither record has a usable 'crank_angle'; pass "
            "period_s= (or --period) [s]"
        )
    if ts[-1] - ts[0] < period * (1 - 1e-9):
        raise BadInputError(
            f"the simulated motion covers {ts[-1] - ts[0]:.4g} s, less than one crank cycle "
            f"({period:.4g} s); simulate at least one whole cycle"
        )
    if method not in ("auto", "crank_angle", "cross_correlation"):
        raise BadInputError(
            f"method must be 'auto', 'crank_angle' or 'cross_correlation', got {method!r}"
        )
    has_crank = "crank_angle" in sim and "crank_angle" in meas
    if method == "auto":
        method = "crank_angle" if has_crank else "cross_correlation"
    if method == "crank_angle" and not has_crank:
        raise BadInputError("method='crank_angle' needs 'crank_angle' in both records")

    # measurement window: whole cycles from its start
    n_cycles = (tm[-1] - tm[0] + np.median(np.diff(tm))) / period
    if whole_cycles and n_cycles >= 1:
        n_keep = int(math.floor(n_cycles + 1e-9))
        keep = tm < tm[0] + n_keep * period - 1e-12
        cycles_note = f"{n_keep} whole crank cycle(s) of the measurement"
    else:
        keep = np.ones_like(tm, dtype=bool)
        n_keep = float(n_cycles)
        cycles_note = f"the whole measurement ({n_cycles:.3g} cycles; less than one whole cycle)"
    tm_k = tm[keep]
    t0 = ts[-1] - period  # start of the simulation's last whole cycle

    def sim_at(t_sim: np.ndarray, values: np.ndarray) -> np.ndarray:
        phase = t0 + np.mod(t_sim - t0, period)
        return np.interp(phase, ts, values)

    if method == "crank_angle":
        phi_s = np.unwrap(np.asarray(sim["crank_angle"].values, dtype=float))
        phi_m = np.asarray(meas["crank_angle"].values, dtype=float)[keep]
        sign = 1.0 if phi_s[-1] >= phi_s[0] else -1.0
        ps = sign * phi_s
        if np.any(np.diff(ps) <= 0):
            raise BadInputError(
                "the simulated crank angle is not monotonic in time; cannot align by crank angle "
                "(use method='cross_correlation')"
            )
        start = ps[-1] - 2 * math.pi
        target = start + np.mod(sign * phi_m - start, 2 * math.pi)
        t_sim = np.interp(target, ps, ts)
        # shift = measurement time - simulation time, modulo the period (circular mean)
        ang = 2 * math.pi * (tm_k - t_sim) / period
        shift = math.atan2(np.mean(np.sin(ang)), np.mean(np.cos(ang))) * period / (2 * math.pi)
        how = "by crank angle (each frame matched to the simulated instant at the same crank angle)"
    else:
        # normalised signals of every common component, simulation on a fine periodic grid
        pairs = []
        for name in names:
            comps = _components(sim[name], meas[name], name)
            for c in comps or [None]:
                s = sim[name] if c is None else sim[name].sel(axis=c)
                m = meas[name] if c is None else meas[name].sel(axis=c)
                sv = np.asarray(s.transpose("time").values, dtype=float)
                mv = np.asarray(m.transpose("time").values, dtype=float)[keep]
                ok = np.isfinite(mv)
                if ok.sum() < 4 or np.nanstd(mv) == 0:
                    continue
                pairs.append((sv, (mv - np.nanmean(mv)) / np.nanstd(mv), ok))
        if not pairs:
            raise BadInputError("no usable signal for the cross-correlation (all constant or NaN)")

        def score(tau: float) -> float:
            total = 0.0
            for sv, mz, ok in pairs:
                x = sim_at(tm_k[ok] - tau, sv)
                sd = x.std()
                if sd == 0:
                    continue
                total += float(np.mean((x - x.mean()) / sd * mz[ok]))
            return total

        from scipy.optimize import minimize_scalar

        grid = np.linspace(0.0, period, 720, endpoint=False)
        scores = np.array([score(t) for t in grid])
        best = grid[int(np.argmax(scores))]
        step = period / 720
        res = minimize_scalar(
            lambda t: -score(t),
            bounds=(best - step, best + step),
            method="bounded",
            options={"xatol": period * 1e-7},
        )
        tau = float(res.x) if -res.fun >= scores.max() else float(best)
        shift = (tau + period / 2) % period - period / 2
        t_sim = t0 + np.mod(tm_k - shift - t0, period)
        how = (
            "by cross-correlation of the normalised signals over whole cycles (the simulation's "
            "last whole cycle repeated periodically)"
        )

    time = xr.DataArray(tm_k, dims="time", attrs=dict(meas["time"].attrs))
    time.attrs.setdefault("units", "s")
    time.attrs.setdefault("long_name", conventions.COORDINATES["time"][1])
    out = xr.Dataset(coords={"time": time})
    comps_of = {name: _components(sim[name], meas[name], name) for name in names}
    union = [c for c in ("x", "y", "z") if any(c in (v or []) for v in comps_of.values())]
    union += sorted({c for v in comps_of.values() for c in (v or []) if c not in union})
    if union:
        out = out.assign_coords(
            axis=xr.DataArray(
                np.array(union, dtype=str), dims="axis", attrs={"long_name": "vector component"}
            )
        )

    def columns(da: xr.DataArray, comps: list[str] | None, times: np.ndarray | None) -> np.ndarray:
        """Values on the output grid: sampled at ``times`` in the simulation (None: kept rows)."""
        if comps is None or "axis" not in da.dims:
            v = np.asarray(da.transpose("time", ...).values, dtype=float).reshape(da.sizes["time"])
            v = v[keep] if times is None else np.interp(times, ts, v)
            return v if comps is None else np.repeat(v[:, None], len(union), axis=1)
        result = np.full((tm_k.size, len(union)), np.nan)
        for c in comps:
            v = np.asarray(da.sel(axis=c).transpose("time").values, dtype=float)
            result[:, union.index(c)] = v[keep] if times is None else np.interp(times, ts, v)
        return result

    for name in names:
        comps = comps_of[name]
        units = _unit_check(sim[name], meas[name], name)
        long = meas[name].attrs.get("long_name", sim[name].attrs.get("long_name", name))
        dims = ("time", "axis") if comps is not None else ("time",)
        svals = columns(sim[name], comps, t_sim)
        mv = columns(meas[name], comps, None)
        out[f"{name}_sim"] = (dims, svals, {"units": units, "long_name": f"simulated {long}"})
        out[f"{name}_meas"] = (dims, mv, {"units": units, "long_name": f"measured {long}"})
        out[f"{name}_diff"] = (
            dims,
            svals - mv,
            {"units": units, "long_name": f"{long}: simulation minus measurement"},
        )
        for side, src in (("meas", meas), ("sim", sim)):
            uname = f"{name}_u"
            if uname not in src:
                continue
            uv = columns(src[uname], comps, None if side == "meas" else t_sim)
            out[f"{name}_{side}_u"] = (
                dims,
                uv,
                {"units": units, "long_name": f"standard uncertainty of {name}_{side}"},
            )
            out[f"{name}_{side}"].attrs["ancillary_variables"] = f"{name}_{side}_u"
    out["sim_time"] = (
        "time",
        t_sim,
        {"units": "s", "long_name": "time in the simulated record each sample is taken from"},
    )
    if "crank_angle" in meas:
        out["crank_angle_meas"] = (
            "time",
            np.asarray(meas["crank_angle"].values, dtype=float)[keep],
            {"units": "rad", "long_name": "measured crank angle"},
        )
    fps = 1.0 / float(np.median(np.diff(tm)))
    out.attrs.update(
        {
            "title": "simulated and measured motion on a common time base",
            "alignment_method": method,
            "alignment": how,
            "time_shift_s": float(shift),
            "time_shift_deg": float(shift / period * 360.0),
            "period_s": float(period),
            "n_cycles": float(n_keep),
            "interpolation": (
                f"common time base: the measurement's samples ({fps:.4g} per s), {cycles_note}; "
                "simulation interpolated linearly onto them after the phase alignment"
            ),
        }
    )
    return out
