"""The whole-band wear field: mean wear depth in bins of a band's grid (one definition).

compare's wear-field criterion (``compare._field``) and the calibration's ``wear_field``
quantity (``sim.calibrate``) reduce a band map ``h(z, theta)`` the same way: the layers split
into ``bins_z`` groups and the angles into ``bins_theta`` groups of consecutive samples (as
equal as the counts allow, :func:`numpy.array_split`; fewer bins than samples never), and each
bin's feature is the mean of its finite cells. Averaging cells keeps interpolation detail and a
measurement's independent noise from dominating. The root holds it so that both packages use
one definition (``sim`` may not import ``compare``).
"""

from __future__ import annotations

import numpy as np

__all__ = ["BINS_Z", "BINS_THETA", "field_bins", "field_means", "field_u"]

#: default bins of the band in z and theta (compare's criteria field_bins_z / field_bins_theta)
BINS_Z, BINS_THETA = 4, 12


def _split(n: int, k: int) -> list[np.ndarray]:
    return [b for b in np.array_split(np.arange(n), min(k, n)) if b.size]


def field_bins(
    n_z: int, n_theta: int, bins_z: int = BINS_Z, bins_theta: int = BINS_THETA
) -> list[tuple[np.ndarray, np.ndarray]]:
    """Row (z) and column (theta) indices of each bin of an ``n_z`` × ``n_theta`` grid, z-major."""
    return [(i, j) for i in _split(n_z, bins_z) for j in _split(n_theta, bins_theta)]


def field_means(h: np.ndarray, bins: list[tuple[np.ndarray, np.ndarray]]) -> np.ndarray:
    """Mean of the finite cells of ``h`` (z, theta) in each bin [units of h] (NaN: none)."""
    h = np.asarray(h, dtype=float)
    out = np.full(len(bins), np.nan)
    for k, (i, j) in enumerate(bins):
        cells = h[np.ix_(i, j)]
        ok = np.isfinite(cells)
        if ok.any():
            out[k] = float(cells[ok].mean())
    return out


def field_u(
    u: np.ndarray, u_random: np.ndarray | None, bins: list[tuple[np.ndarray, np.ndarray]]
) -> np.ndarray:
    """Standard uncertainty of each bin mean from a per-point u (z, theta).

    The part independent from point to point (``u_random``; NaN or None: none stated) averages
    down as ``sqrt(Σ u_random²) / n``; the rest (``sqrt(u² - u_random²)``, correlated over the
    map) is taken fully correlated within a bin (its mean, an upper bound).
    """
    u = np.asarray(u, dtype=float)
    rnd = np.zeros_like(u) if u_random is None else np.nan_to_num(np.minimum(u_random, u))
    sys_part = np.sqrt(np.maximum(u**2 - rnd**2, 0.0))
    out = np.full(len(bins), np.nan)
    for k, (i, j) in enumerate(bins):
        s, r = sys_part[np.ix_(i, j)], rnd[np.ix_(i, j)]
        ok = np.isfinite(s)
        if ok.any():
            n = int(ok.sum())
            out[k] = float(np.hypot(s[ok].mean(), np.sqrt(np.sum(r[ok] ** 2)) / n))
    return out
