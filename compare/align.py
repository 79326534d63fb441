"""Putting simulation and measurement on one grid: wear maps over (z, theta), motion over time.

Wear maps
    Both maps are converted to the canonical angle convention (a map that does not state its
    convention is refused), restricted to the axial range both cover, and brought onto one
    grid: ``theta`` uniform over [0, 360) with the coarser of the two angular steps, ``z`` the
    layers of the map with more layers inside the overlap (no layer of either map is skipped
    over; the other map is interpolated linearly between its layers). In theta *both* maps go
    through the same operator: the mean over each grid cell (one grid step wide, centred on
    the grid angle) of the map's periodic linear interpolant. A dense instrument trace (18000
    points per layer) is thereby box-averaged (no aliasing) and a coarse simulated map is
    averaged over the same cells, not sampled at its nodes: sampling one side and averaging
    the other read a sharp peak (and the cylindricity) low on the averaged side, by about
    slope x step / 4 (3-5 % on the reference layout). Only when both maps are sampled at the
    grid's angles are their own values compared (the identity, again for both). In z both are point values (thin measured
    layers, simulated nodes), linear between layers, never extrapolated. The method used for
    each side is stated in the ``interpolation`` attribute.

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

import numpy as np
import xarray as xr

from jointwear import conventions
from jointwear.compare._coverage import theta_covered as _theta_covered
from jointwear.compare._coverage import with_coverage as _with_coverage
from jointwear.compare.align_motion import MOTION_VARIABLES, align_time_series
from jointwear.compare.budget import to_standard
from jointwear.errors import BadInputError, ConventionError

__all__ = ["align_wear_maps", "align_time_series", "MOTION_VARIABLES", "to_metres"]

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


def _cell_mean(
    theta_src: np.ndarray, values: np.ndarray, theta_tgt: np.ndarray, width: float
) -> np.ndarray:
    """Mean over each cell ``[t - width/2, t + width/2]`` of the periodic linear interpolant.

    The one operator that puts every map on the common grid in theta [degree], along the last
    axis: the samples of a row (NaN samples dropped) are joined linearly, periodically over 360
    degree, and the resulting curve is integrated exactly over each cell. For dense samples (an
    instrument's 18000 points per layer) this is the box mean of the samples; for a map sampled
    at the grid's own angles it is ``(f[i-1] + 6 f[i] + f[i+1]) / 8``. Applying it to both
    sides gives the same number for a map and a dense measurement of that map. A cell that
    reaches into an angular gap (spacing > 1.5 median steps, e.g. a partial arc) is NaN.
    """
    order = np.argsort(theta_src)
    th = np.asarray(theta_src, dtype=float)[order]
    own = _theta_step(th)
    flat = np.asarray(values, dtype=float)[..., order].reshape(-1, th.size)
    lo, hi = theta_tgt - width / 2, theta_tgt + width / 2
    out = np.full((flat.shape[0], theta_tgt.size), np.nan)
    for r, row in enumerate(flat):
        ok = np.isfinite(row)
        if ok.sum() < 2:
            continue
        t = np.concatenate([th[ok] - 360.0, th[ok], th[ok] + 360.0])
        f = np.tile(row[ok], 3)
        seg = np.diff(t)
        cum = np.concatenate([[0.0], np.cumsum(seg * (f[1:] + f[:-1]) / 2)])

        def integral(x: np.ndarray, t=t, f=f, cum=cum) -> np.ndarray:
            k = np.clip(np.searchsorted(t, x, side="right") - 1, 0, t.size - 2)
            return cum[k] + (x - t[k]) * (f[k] + np.interp(x, t, f)) / 2

        mean = (integral(hi) - integral(lo)) / width
        gaps = np.concatenate([[0], np.cumsum(seg > 1.5 * own + 1e-9)])
        first = np.searchsorted(t, lo, side="right") - 1
        last = np.searchsorted(t, hi, side="left") - 1
        mean[gaps[last + 1] - gaps[first] > 0] = np.nan
        out[r] = mean
    return out.reshape(*np.shape(values)[:-1], theta_tgt.size)


def _prepare_map(
    obj: xr.Dataset | xr.DataArray, variable: str, cycles: float | None, what: str
) -> tuple[xr.DataArray, dict[str, xr.DataArray], float | None, str, xr.Dataset]:
    """The map [m] at the compared cycles, canonical, over (z, theta); its uncertainties
    (``{"u": ..., "u_random": ...}``, standard, same grid; the random part only with a u)."""
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
    uncs = {}
    for suffix in ("u", "u_random"):
        uname = f"{name}_{suffix}"
        if uname in ds and (suffix == "u" or "u" in uncs):
            # converted to a standard uncertainty by its declared coverage factor (sim: k = 2)
            std, u_note = to_standard(ds[uname].values, ds[uname].attrs, f"{what}: {uname}")
            tau = float(ds[uname].attrs.get("correlation_length_samples", 1.0))
            uncs[suffix] = (to_metres(ds[uname].copy(data=std), what), f"{uname}: {u_note}", tau)
    da, n_cycles, how = _pick_cycles(da, ds, cycles, what)
    flip = str(da["z"].attrs.get("z_direction", "+z")).strip() == "-z"
    for suffix, (unc, basis, tau) in uncs.items():
        unc, _, _ = _pick_cycles(unc, ds, n_cycles if "cycles" in unc.dims else None, what)
        unc = unc.assign_coords(z=-unc["z"]) if flip else unc
        unc = conventions.convert_theta(
            unc.transpose("z", "theta"), source=conventions.angle_convention_of(ds[name])
        ).sortby("z")
        unc.attrs = {"units": "m", "basis": basis, "correlation_length_samples": tau}
        uncs[suffix] = unc
    zattrs = da["z"].attrs
    if flip:
        da = da.assign_coords(z=-da["z"])
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
    return da, uncs, n_cycles, how, ds


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


def _on_grid(da: xr.DataArray, theta_tgt: np.ndarray) -> bool:
    """True when the map's own angles are the grid's angles."""
    theta = np.sort(np.asarray(da["theta"].values, dtype=float))
    return theta.size == theta_tgt.size and bool(np.allclose(theta, theta_tgt, atol=1e-9))


def _resample(
    da: xr.DataArray, z_tgt: np.ndarray, theta_tgt: np.ndarray, step: float, native: bool
) -> tuple[np.ndarray, str]:
    """The map on the common grid: its own values (``native``, both maps on the grid) or, for
    both maps alike, the cell mean of its interpolant in theta; linear between layers in z."""
    theta = np.asarray(da["theta"].values, dtype=float)
    z = np.asarray(da["z"].values, dtype=float)
    values = np.asarray(da.values, dtype=float)
    if native:
        at_theta = values[:, np.argsort(theta)]
        how_theta = "native theta grid (both maps on it)"
    else:
        at_theta = _cell_mean(theta, values, theta_tgt, step)
        how_theta = (
            f"mean over each grid cell ({step:.4g} degree) of the periodic linear interpolant "
            f"of its {int(round(360.0 / _theta_step(theta)))} samples per layer in theta"
        )
    if z.size == z_tgt.size and np.allclose(z, z_tgt, atol=1e-12):
        return at_theta, how_theta + ", native z layers"
    if z.size == 1:
        raise BadInputError("a single-layer map can only be compared at its own z")
    out = np.empty((z_tgt.size, theta_tgt.size))
    for j in range(theta_tgt.size):
        out[:, j] = np.interp(z_tgt, z, at_theta[:, j])
    return out, how_theta + ", linear interpolation in z between layers"


def _random_on_grid(
    unc: xr.DataArray,
    z_tgt: np.ndarray,
    theta_tgt: np.ndarray,
    step: float,
    native: bool,
    variable: str,
    side: str,
) -> tuple:
    """The independent (point-to-point) part of a map's u, of the values on the common grid.

    A grid value is the cell mean of the map's periodic linear interpolant: it weights the
    ``n`` samples inside the cell about equally (trapezoid weights, ``1/n`` each), so the
    variance of their independent noise drops by ``1/n``. Noise correlated over ``tau``
    samples (the map's integrated correlation length, ``correlation_length_samples``: the
    variance of a mean of ``n >> tau`` such samples is ``sigma^2 tau / n``) counts as
    ``n / tau`` independent samples: ``n_eff = max(1, n / max(1, tau))``, and the random part
    of the grid value is the per-point part / sqrt(n_eff). Between layers in z it is
    interpolated linearly (an upper bound: the interpolant's weights w, 1 - w give
    sqrt(w^2 + (1 - w)^2) <= 1); where the map is not averaged (``native``), n_eff = 1.
    """
    on_grid = native and _on_grid(unc, theta_tgt)
    vals, _ = _resample(unc, z_tgt, theta_tgt, step, on_grid)
    tau = max(1.0, float(unc.attrs.get("correlation_length_samples", 1.0)))
    per_cell = 1.0 if on_grid else max(1.0, step / _theta_step(np.asarray(unc["theta"].values)))
    n_eff = max(1.0, per_cell / tau)
    return (
        ("z", "theta"),
        vals / np.sqrt(n_eff),
        {
            "units": "m",
            "long_name": f"independent part of {variable}_{side}_u, of the grid value",
            "coverage_factor": 1.0,
            "basis": (
                f"{unc.attrs.get('basis', '')}; per-point part / sqrt(n_eff), n_eff = "
                f"{n_eff:.4g} independent samples per cell ({per_cell:.4g} samples, "
                f"correlation length {tau:.3g} samples)"
            ),
            "per_point_factor": 1.0 / float(np.sqrt(n_eff)),
        },
    )


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
        Optional ``wear_depth_u`` (standard uncertainty) is carried along, and with it its
        independent part ``wear_depth_u_random`` (reduced by the cell averaging, see
        :func:`_random_on_grid`).
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
        ``wear_depth_diff`` (sim - meas) [m], uncertainties ``*_u`` when given (the per-point
        u, cell-averaged) and ``*_u_random`` (the independent part of the grid value); attributes
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
    # one operator for both maps: their own values when both are on the grid, else the cell mean
    native = _on_grid(s_da, theta_tgt) and _on_grid(m_da, theta_tgt)
    s_vals, s_interp = _resample(s_da, z_tgt, theta_tgt, step, native)
    m_vals, m_interp = _resample(m_da, z_tgt, theta_tgt, step, native)
    # a measurement with an angular gap (a partial arc) is not interpolated across it: both
    # sides are compared only where the measurement has samples
    covered = _theta_covered(np.asarray(m_da["theta"].values, dtype=float), theta_tgt)
    # a cell reaching into the gap is not averaged over the same angles on both sides
    covered &= np.isfinite(m_vals).any(axis=0)
    if not covered.all():
        s_vals = np.where(covered[None, :], s_vals, np.nan)
        m_vals = np.where(covered[None, :], m_vals, np.nan)
        m_interp += f"; {int((~covered).sum())} of {covered.size} grid angles lie in (or reach into) an angular gap of the measurement and are not compared"

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
    for uncs, side in ((s_u, "sim"), (m_u, "meas")):
        if "u" not in uncs:
            continue
        unc = uncs["u"]
        vals, _ = _resample(unc, z_tgt, theta_tgt, step, native and _on_grid(unc, theta_tgt))
        uname = f"{variable}_{side}_u"
        out[uname] = (
            dims,
            vals,
            {
                "units": "m",
                "long_name": f"standard uncertainty of {variable}_{side}",
                "coverage_factor": 1.0,
                "basis": unc.attrs.get("basis", ""),
            },
        )
        out[f"{variable}_{side}"].attrs["ancillary_variables"] = uname
        anc.append(uname)
        if "u_random" in uncs:
            out[f"{uname}_random"] = _random_on_grid(
                uncs["u_random"], z_tgt, theta_tgt, step, native, variable, side
            )
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
    have = all(v in m_ds.data_vars and m_ds[v].ndim == 0 for v in ("worn_volume", "worn_volume_u"))
    if have:
        var = m_ds["worn_volume_u"]
        if str(var.attrs.get("units", "m3")) == "m3":
            out.attrs["worn_volume_meas_stated"] = float(m_ds["worn_volume"].values)
            value, note = to_standard(var.values, var.attrs, "measured worn_volume_u")
            out.attrs["worn_volume_u_meas"] = float(value)
            out.attrs["worn_volume_u_meas_basis"] = f"worn_volume_u: {note}"
    for side, ds in (("sim", s_ds), ("meas", m_ds)):
        if "cylindricity" in ds.data_vars or "cylindricity" in ds.attrs:
            value = _stated_scalar(ds, "cylindricity", s_cycles if side == "sim" else m_cycles)
            if value is not None and np.isfinite(value):
                out.attrs[f"cylindricity_stated_{side}_m"] = value
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
