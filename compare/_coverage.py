"""How much of the simulated wear map a measurement covers (axial range and arc).

Used by :func:`jointwear.compare.align.align_wear_maps`: the whole simulated map is kept next to
the common grid, with the location of its maximum and the share of its worn volume inside the
measured range, so that criteria on what is not covered are *not comparable*.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

__all__ = ["theta_covered", "with_coverage"]


def _median_step(theta: np.ndarray) -> float:
    return float(np.median(np.diff(np.sort(theta))))


def _volume_between(z: np.ndarray, per_layer: np.ndarray, lo: float, hi: float) -> float:
    """Trapezoid integral of a piecewise-linear per-layer profile over [lo, hi]."""
    lo, hi = max(lo, float(z.min())), min(hi, float(z.max()))
    if hi <= lo:
        return 0.0
    grid = np.unique(np.concatenate([[lo, hi], z[(z > lo) & (z < hi)]]))
    return float(np.trapezoid(np.interp(grid, z, per_layer), grid))


def theta_covered(theta_src: np.ndarray, theta_tgt: np.ndarray) -> np.ndarray:
    """Target angles [degree] within reach of the source samples (no angular gap), periodic.

    A target angle is covered when a source sample lies within 1.5 source steps (the median
    spacing) of it: a full circle covers everything, a partial arc only itself.
    """
    th = np.sort(np.mod(theta_src, 360.0))
    own = _median_step(th)
    ext = np.concatenate([th - 360.0, th, th + 360.0])
    idx = np.clip(np.searchsorted(ext, theta_tgt), 1, ext.size - 1)
    dist = np.minimum(np.abs(ext[idx] - theta_tgt), np.abs(ext[idx - 1] - theta_tgt))
    return dist <= 1.5 * own + 1e-9


def with_coverage(
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
