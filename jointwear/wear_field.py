"""The whole-band wear field: mean wear depth in bins of a band's grid (one definition).

compare's wear-field criterion (``compare._field``) and the calibration's ``wear_field``
quantity (``sim.calibrate``) reduce a band map ``h(z, theta)`` the same way: the layers split
into ``bins_z`` groups and the angles into ``bins_theta`` groups of consecutive samples (as
equal as the counts allow, :func:`numpy.array_split`; fewer bins than samples never), and each
bin's feature is the mean of its finite cells. Averaging cells keeps interpolation detail and a
measurement's independent noise from dominating. The root holds it so that both packages use
one definition (``sim`` may not import ``compare``).

A per-point u that states its independent part (``wear_depth_u_random``) splits into that part
and the rest, correlated over the map, ``sqrt(u² − u_random²)`` (:func:`split_u`, the one
definition the bin and the volume uncertainties use).
"""

from __future__ import annotations

import numpy as np

from jointwear.errors import BadInputError

__all__ = [
    "BINS_Z",
    "BINS_THETA",
    "RANDOM_PART_RTOL",
    "field_bins",
    "field_means",
    "field_u",
    "random_part",
    "split_u",
]

#: default bins of the band in z and theta (compare's criteria field_bins_z / field_bins_theta)
BINS_Z, BINS_THETA = 4, 12


#: relative excess of a stated independent part over its whole u taken as round-off (and capped)
RANDOM_PART_RTOL = 1e-6


def random_part(
    u: np.ndarray, u_random: np.ndarray, where: str = "the map", name: str = "wear_depth_u"
) -> np.ndarray:
    """The independent part of a per-point u, no larger than the u it is part of [units of u].

    ``u_random`` is included in ``u`` (the data contract; ``metrology wearmap`` caps it so), so
    a stated part above its whole is inconsistent: above ``u`` by round-off
    (:data:`RANDOM_PART_RTOL`) it is capped at ``u`` (the point's u all independent), by more it
    is refused, as which of the two numbers is wrong cannot be told. NaN (not stated) stays NaN,
    and so does any point whose ``u`` is not stated.

    Raises
    ------
    BadInputError
        Naming ``where``, the points and the largest excess.
    """
    u = np.asarray(u, dtype=float)
    rnd = np.asarray(u_random, dtype=float)
    with np.errstate(invalid="ignore"):
        over = rnd > u * (1.0 + RANDOM_PART_RTOL)
    if over.any():
        worst = float(np.max(rnd[over] / u[over]))
        raise BadInputError(
            f"{where}: {name}_random exceeds {name} at {int(over.sum())} of {u.size} points (up "
            f"to {worst:.4g} x); the independent part is included in the point's whole u: state "
            f"the whole u in {name} (sqrt(systematic² + random²)) or a {name}_random no larger "
            "than it"
        )
    return np.minimum(rnd, u)


def split_u(
    u: np.ndarray, u_random: np.ndarray | None, where: str = "the map"
) -> tuple[np.ndarray, np.ndarray]:
    """A per-point standard uncertainty split into its correlated and independent parts.

    Parameters
    ----------
    u : ndarray
        The whole per-point standard uncertainty (NaN: not stated).
    u_random : ndarray or None
        Its part independent from point to point (NaN or None: none stated; above ``u`` see
        :func:`random_part`: capped within round-off, else refused).
    where : str
        What the values are of, for the refusal.

    Returns
    -------
    systematic, independent : ndarray
        ``sqrt(u² − u_random²)``, correlated over the map, and ``u_random`` (0 where not
        stated: the whole u then counts as correlated); both in the units of ``u``. Where ``u``
        is not stated, ``systematic`` is NaN and ``independent`` 0.
    """
    u = np.asarray(u, dtype=float)
    rnd = np.zeros_like(u) if u_random is None else np.nan_to_num(random_part(u, u_random, where))
    return np.sqrt(np.maximum(u**2 - rnd**2, 0.0)), rnd


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
    map, :func:`split_u`) is taken fully correlated within a bin (its mean, an upper bound).
    A bin's points whose u is not stated are left out of it (NaN: none stated).
    """
    sys_part, rnd = split_u(u, u_random)
    out = np.full(len(bins), np.nan)
    for k, (i, j) in enumerate(bins):
        s, r = sys_part[np.ix_(i, j)], rnd[np.ix_(i, j)]
        ok = np.isfinite(s)
        if ok.any():
            n = int(ok.sum())
            out[k] = float(np.hypot(s[ok].mean(), np.sqrt(np.sum(r[ok] ** 2)) / n))
    return out
