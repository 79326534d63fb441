"""A "true" wear of a tested bearing built from a simulated wear map, for generated scans.

A generated instrument scan needs a wear field ``h(theta, z)``. To try the measurement chain
against a simulation without a rig, the wear of the virtual tested bearing can be taken from a
simulated wear map — scaled and turned, so that the comparison has a known, non-zero answer. The
scan generator (:func:`jointwear.datasets.instruments.generate`) takes the returned function as
its ``wear`` argument; ``jointwear datasets instruments --wear-from wear.nc`` does the same from
the command line.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import xarray as xr

from jointwear.errors import BadInputError

__all__ = ["wear_from_simulation"]


def wear_from_simulation(
    sim_wear: xr.Dataset,
    *,
    scale: float = 1.0,
    rotation_deg: float = 0.0,
    cycles: float | None = None,
) -> Callable[[np.ndarray, np.ndarray], np.ndarray]:
    """The wear depth of a simulated map as a function of canonical angle and axial position.

    ``h(theta, z) = scale * h_sim(theta - rotation_deg, z)``, bilinear between the simulated
    grid points (periodic in ``theta``); ``z`` outside the simulated width is clamped to its edge.

    Parameters
    ----------
    sim_wear : xarray.Dataset
        A ``jointwear sim wear`` result: ``wear_depth`` [m] over (``cycles``, ``z``, ``theta``),
        ``theta`` in the canonical convention [degree], ``z`` [m].
    scale : float
        Factor on the depth [1] (1.1: the tested bearing wore 10 % more than simulated).
    rotation_deg : float
        Turn of the wear pattern in the canonical sense [degree].
    cycles : float, optional
        Snapshot to use [cycles]; the last one by default. Must be a stored snapshot.

    Returns
    -------
    callable
        ``h(theta_deg, z)`` [m] for arrays of canonical angles [degree] and positions [m].
    """
    if "wear_depth" not in sim_wear:
        raise BadInputError(
            "the simulated wear file has no 'wear_depth' variable; give the output of "
            "'jointwear sim wear' (--wear-from)"
        )
    if not np.isfinite(scale) or scale < 0:
        raise BadInputError(f"wear scale must be a finite number >= 0, got {scale} (--wear-scale)")
    da = sim_wear["wear_depth"]
    if "cycles" in da.dims:
        if cycles is None:
            da = da.isel(cycles=-1)
        else:
            stored = np.asarray(da["cycles"].values, dtype=float)
            hit = np.flatnonzero(np.isclose(stored, cycles, rtol=1e-9, atol=0.5))
            if hit.size == 0:
                raise BadInputError(
                    f"the simulated wear file has no snapshot at {cycles:g} cycles "
                    f"(stored: {', '.join(f'{c:g}' for c in stored)}); pick one of them"
                )
            da = da.isel(cycles=int(hit[0]))
    da = da.transpose("z", "theta")
    z_s = np.asarray(da["z"].values, dtype=float)
    th_s = np.asarray(da["theta"].values, dtype=float)
    h = np.asarray(da.values, dtype=float)
    if z_s.size < 2 or th_s.size < 2 or not np.all(np.isfinite(h)):
        raise BadInputError("the simulated wear map needs >= 2 finite points in z and theta")
    th_ext = np.concatenate([th_s - 360.0, th_s, th_s + 360.0])
    h_ext = np.concatenate([h, h, h], axis=1)

    def truth(theta_deg: np.ndarray, z: np.ndarray) -> np.ndarray:
        th = np.mod(np.asarray(theta_deg, dtype=float) - rotation_deg, 360.0)
        zz = np.clip(np.asarray(z, dtype=float), z_s.min(), z_s.max())
        th_b, z_b = np.broadcast_arrays(th, zz)
        out = np.empty(th_b.shape)
        flat_t, flat_z, flat_o = th_b.ravel(), z_b.ravel(), out.ravel()
        # bilinear: linear in z between layers, periodic linear in theta
        k = np.clip(np.searchsorted(z_s, flat_z) - 1, 0, z_s.size - 2)
        w = (flat_z - z_s[k]) / (z_s[k + 1] - z_s[k])
        for i in np.unique(k):
            sel = k == i
            lo = np.interp(flat_t[sel], th_ext, h_ext[i])
            hi = np.interp(flat_t[sel], th_ext, h_ext[i + 1])
            flat_o[sel] = (1 - w[sel]) * lo + w[sel] * hi
        return scale * flat_o.reshape(th_b.shape)

    return truth
