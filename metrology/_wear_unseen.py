"""Wear the unworn selection cannot see, and what it can do to a wear map (decided by consequence).

With a before-scan the change of set-up (a limaçon cylinder: radius offset, eccentricity, tilt)
is fitted to the difference of the scans on the points taken as unworn. Wear on those points
cannot be told from that change where it lies in the span of the limaçon over them: a uniform
wear c of the unworn arcs is a radius offset, and wear differing between two arcs is a first
harmonic. Such wear is not identifiable from the scans; what the data bound is the wear *level*
the selection would have seen. Where the bore is worn over most of its circumference (unworn
arcs shorter than ``UNSEEN_ARC``, in a quarter of the layers, hold more than 1 % of the points: the arcs lie between worn regions, where
the tails of both overlap; a simulated tilt-stiff rig holds 2-20 nm over all of it) or the band
test's faint tails reach around it, the map carries the consequence of wear up to that level on
every unworn point:

* the level ``A``: ``threshold`` robust standard deviations of the residual smoothed over 2
  degree (the region test of the selection flags smoothed wear above it), or the faint tail the
  band test still measures next to the worn region (mean + 2 standard errors), the larger;
* the worst case over every wear w of the unworn points with 0 <= w <= A: the reference is
  linear in the data, so each quantity's change is A times the sum of the positive weights of
  the unworn points in it (exact for the volume; for the depths on 2-degree bins);
* it enters the u as a rectangular distribution (a / sqrt(3), GUM 4.3.7) beside the other
  estimates of the reference's bias by faint wear (the larger counts), and the map is refused
  only where the bound a exceeds ``UNSEEN_LIMIT`` of the volume or of the maximum depth.
"""

from __future__ import annotations

import numpy as np

from jointwear.errors import BadInputError
from jointwear.metrology._wear_fit import _basis, _design_sum, _LayerBasis, _smooth_theta

__all__ = [
    "STRUCTURE_SHARE",
    "UNSEEN_ARC",
    "UNSEEN_LIMIT",
    "WearMapRefusal",
    "exposed",
    "unworn_arcs",
]

#: Largest bound of the unseen wear's change of the volume or the maximum depth, as a fraction
#: of it, that a map may carry in its u (above it the map is refused) [1].
UNSEEN_LIMIT = 0.3
#: Where unworn arcs (in at least a quarter of the layers) shorter than this [degree] hold more
#: than 1 % of the points, the unseen-wear term is assessed: such arcs lie within reach of the worn regions' tails on
#: both sides, and a limaçon fitted on them absorbs smooth wear (a single Gaussian groove
#: 20 degree wide leaves 150-200 degree; the simulated tilt-stiff rig 60-85 degree).
UNSEEN_ARC = 120.0
#: Smooth structure on the unworn points (correlated over >= 3 samples) above this fraction of
#: the instrument noise: wear the change of set-up absorbed (a cos^2 lobe over 92 % of the bore,
#: 0.1 um deep, leaves 10 nm against 28 nm of noise and read 12 u low) [1].
STRUCTURE_SHARE = 0.25


class WearMapRefusal(BadInputError):
    """A wear map refused with the unworn arcs that would settle it if the user knows them.

    Attributes
    ----------
    reason, fix : str
        The message without its fix (the command line adds a runnable command), and the fix.
    unworn_arcs : tuple of (float, float)
        Canonical theta arcs [degree] (start, end; may wrap through 0) that the data find least
        worn: ``unworn=`` mask / CLI ``--unworn``.
    """

    def __init__(self, reason: str, fix: str, unworn_arcs: tuple[tuple[float, float], ...] = ()):
        super().__init__(f"{reason}; {fix}")
        self.reason = reason
        self.fix = fix
        self.unworn_arcs = tuple(unworn_arcs)


def format_arcs(arcs) -> str:
    """The arcs as the CLI's ``--unworn`` value: ``a:b,c:d`` [degree]."""
    return ",".join(f"{a:g}:{b:g}" for a, b in arcs)


def exposed(mask2: np.ndarray, min_arc: float = UNSEEN_ARC) -> np.ndarray:
    """The unworn points (nz, nt) that are not on an arc of at least ``min_arc`` [degree]
    unworn in at least a quarter of the layers (periodic; the symmetric rejection of noise
    leaves holes in single layers): where the worn regions' tails can reach."""
    mask2 = np.asarray(mask2, dtype=bool)
    col = mask2.mean(axis=0) >= 0.25
    if col.all():
        return np.zeros_like(mask2)
    start = int(np.argmin(col))
    c = np.roll(col, -start)
    edges = np.flatnonzero(np.diff(np.concatenate([[0], c.astype(int), [0]])))
    safe = np.zeros(col.size, dtype=bool)
    for a, b in zip(edges[::2], edges[1::2], strict=True):
        if (b - a) * 360.0 / col.size >= min_arc:
            safe[a:b] = True
    return mask2 & ~np.roll(safe, start)[None, :]


def unworn_arcs(
    mask2: np.ndarray, theta_deg: np.ndarray, wear=None, most: int = 3, min_deg: float = 5.0
):
    """The longest runs of theta (at most ``most``, each >= ``min_deg``) where at least three
    quarters of the layers are unworn, as whole-degree arcs inside the run [degree,
    canonical]; where every column or none is, the runs where the layers' mean ``wear`` [m]
    (the map, smoothed over 5 degree) lies in its lowest quarter (the reference absorbed the
    wear: the least worn arcs read lowest); () if none."""
    col = np.asarray(mask2, dtype=bool).mean(axis=0) >= 0.75
    if (col.all() or not col.any()) and wear is not None:
        win = max(1, int(round(5.0 * col.size / 360.0)))
        mean = _smooth_theta(np.nanmean(wear, axis=0)[None, :], win)[0]
        col = mean <= np.nanpercentile(mean, 25)
    n = col.size
    if col.all() or not col.any():
        return ()
    start = int(np.argmin(col))  # a worn column: runs do not wrap past it
    c = np.roll(col, -start)
    edges = np.flatnonzero(np.diff(np.concatenate([[0], c.astype(int), [0]])))
    runs = sorted(zip(edges[::2], edges[1::2], strict=True), key=lambda r: r[0] - r[1])
    step = 360.0 / n
    out = []
    for a, b in runs[:most]:
        lo = np.ceil(float(theta_deg[(a + start) % n]))
        hi = np.floor(float(theta_deg[(b - 1 + start) % n]) + (360.0 if b - 1 + start >= n else 0))
        if (b - a) * step >= min_deg and hi - lo >= 1.0:
            out.append((float(lo % 360.0), float(hi % 360.0 if hi % 360.0 else 360.0)))
    return tuple(out)


def smooth_structure(s2: float, noise: float, tau: float) -> float:
    """RMS [m] of smooth structure on the unworn points: what their residual (variance ``s2``
    [m^2]) holds beyond the instrument ``noise`` [m], where it is correlated along theta
    (``tau`` >= 3 samples); 0 for white residuals."""
    if not (np.isfinite(noise) and np.isfinite(tau)) or tau < 3.0:
        return 0.0
    return float(np.sqrt(max(s2 - noise**2, 0.0)))


def unseen_level(
    resid2: np.ndarray, mask2: np.ndarray, theta_deg, threshold: float, tail=None, structure=0.0
):
    """The level A [m] of wear the selection cannot see on an unworn point (module docstring):
    ``threshold`` x 1.4826 MAD of the residual smoothed over 2 degree on the unworn points,
    ``tail`` (the band test's remaining tail, mean + 2 standard errors [m]) or twice the RMS
    ``structure`` [m] the unworn points hold beyond noise, the largest."""
    win = max(1, int(round(2.0 * theta_deg.size / 360.0)))
    sm = _smooth_theta(resid2, win)[mask2]
    sm = sm[np.isfinite(sm)]
    level = threshold * 1.4826 * float(np.median(np.abs(sm - np.median(sm)))) if sm.size else 0.0
    return max(level, float(tail) if tail is not None else 0.0, 2.0 * structure)


def _bin_rows(X, z, bins):
    """Design rows at the bin centres, per layer: (nz, nb, p) for a cylinder, (nz, nb, 3)
    block rows for a circle per layer."""
    if isinstance(X, _LayerBasis):
        return np.broadcast_to(_basis(z, bins, "circle").block.T, (z.size, bins.size, 3))
    return _basis(z, bins, "cylinder").reshape(z.size, bins.size, -1)


def unseen_bound(X, G, levels, z, theta_deg, wts, wear, n_bins: int = 180):
    """Worst-case change of each quantity and of every depth [m] by unseen wear 0..``levels``
    [m] on the unworn points (``levels`` (nz, nt), 0 elsewhere; reference X b fitted with
    normal matrix ``G``).

    Returns ({"worn_volume": [m^3], "max_wear_depth": [m], "wear_cylindricity": [m]},
    per-point bound (nz, nt) [m]). Wear w on the unworn points moves the fitted reference by
    H w (H the hat matrix; its rows on 2-degree bins): the worst case over 0 <= w <= levels is
    the sum of the positive weights times the levels.
    """
    nz, nt = levels.shape
    nb = min(n_bins, nt)
    bins = (np.arange(nb) + 0.5) * 360.0 / nb
    idx = np.minimum((np.mod(theta_deg, 360.0) * nb / 360.0).astype(int), nb - 1)
    cnt = np.stack([np.bincount(idx, weights=v, minlength=nb) for v in levels])  # [m]
    rows = _bin_rows(X, z, bins)  # (nz, nb, p)
    Gi = np.linalg.inv(G)
    a = _design_sum(X, wts)
    if isinstance(X, _LayerBasis):  # one block per layer: a point moves with its layer only
        ci = np.einsum("lk,lkj->lj", a.reshape(nz, 3), Gi)
        cvol = np.einsum("lj,lbj->lb", ci, rows) * cnt
        H = np.einsum("lbj,ljk,lck->lbc", rows, Gi, rows * cnt[..., None])
        pos = np.clip(H, 0, None).sum(axis=2)
        Hrow = lambda k: np.where(  # noqa: E731
            np.arange(nz)[:, None] == k[0], H[k[0], idx[k[1]]][None, :], 0.0
        )
    else:
        flat = rows.reshape(nz * nb, -1)
        right = (flat * cnt.ravel()[:, None]) @ Gi  # (nz nb, p): G^-1 x_j A_j n_j
        cvol = (right @ a).reshape(nz, nb)
        pos = np.stack([np.clip(rows[i] @ right.T, 0, None).sum(axis=1) for i in range(nz)])
        Hrow = lambda k: (right @ rows[k[0], idx[k[1]]]).reshape(nz, nb)  # noqa: E731
    w = np.nan_to_num(wear)
    hi = np.unravel_index(int(np.argmax(w)), w.shape)
    lo = np.unravel_index(int(np.argmin(w)), w.shape)
    diff = Hrow(hi) - Hrow(lo)
    bound = {
        "worn_volume": float(np.clip(cvol, 0, None).sum()),
        "max_wear_depth": float(pos[hi[0], idx[hi[1]]]),
        "wear_cylindricity": max(
            float(np.clip(diff, 0, None).sum()), float(np.clip(-diff, 0, None).sum())
        ),
    }
    return bound, pos[:, idx]


def unseen_term(bound: dict, per_point: np.ndarray):
    """(standard u of each quantity, of every depth) of the bound: rectangular, a / sqrt(3)."""
    return {k: v / np.sqrt(3.0) for k, v in bound.items()}, per_point / np.sqrt(3.0)


def refuse_by_consequence(
    q: dict, bound: dict, level: float, share: float, arcs, explicit: bool = False
) -> None:
    """Refuse a map whose unseen-wear bound exceeds ``UNSEEN_LIMIT`` of its volume or of its
    maximum depth (the message names both figures and the arcs an ``unworn`` mask could use;
    ``explicit``: the unworn points were given, and cannot rule the wear out)."""
    for name, what, unit, scale in (
        ("worn_volume", "worn volume", "mm³", 1e9),
        ("max_wear_depth", "maximum depth", "µm", 1e6),
    ):
        value, b = q[name][0], bound[name]
        if np.isfinite(b) and b > UNSEEN_LIMIT * abs(value):
            fix = (
                "the points given as unworn lie within reach of the worn regions' tails (arcs "
                f"shorter than {UNSEEN_ARC:g} degree) or hold smooth structure, so they cannot "
                "rule it out: give arcs known to be unworn over a longer span"
                if explicit
                else f"if the bore is known to be unworn at theta {format_arcs(arcs)} degree "
                f"(canonical), pass them as unworn (unworn={[tuple(a) for a in arcs]}; CLI "
                f"--unworn {format_arcs(arcs)})"
                if arcs
                else "give the theta arcs known to be unworn (Python: (start, end) pairs as "
                "unworn; CLI --unworn THETA1:THETA2) [degree, canonical]"
            )
            raise WearMapRefusal(
                f"wear_map: wear spread round the bore ({share:.0%} of the points unworn): "
                f"wear below {level * 1e9:.2g} nm on the points taken as unworn, which the "
                "selection cannot see and the change of set-up would absorb, could change the "
                f"{what} ({value * scale:.3g} {unit}) by up to {b * scale:.2g} {unit} "
                f"({b / max(abs(value), 1e-30):.0%}, more than {UNSEEN_LIMIT:.0%})",
                fix,
                arcs,
            )
