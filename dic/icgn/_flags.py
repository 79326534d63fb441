"""Quality flags of the 2D DIC engine (CF ``flag_values`` / ``flag_meanings``), numba-free."""

from __future__ import annotations

import numpy as np

FLAG_OK = 0
FLAG_NOT_CONVERGED = 1
FLAG_LOW_CORRELATION = 2
FLAG_OUTSIDE = 3
FLAG_NO_TEXTURE = 4
FLAG_INVALID_PIXELS = 5
FLAG_NOT_REACHED = 6
FLAG_DIVERGED = 7

FLAG_MEANINGS = (
    "ok not_converged low_correlation subset_outside_image no_texture invalid_pixels "
    "not_reached diverged"
)
FLAG_VALUES = np.arange(8, dtype=np.int8)

#: a match whose own standard uncertainty is far above its image's (set after the matching,
#: by :func:`flag_uncertainty_outliers`; 11, after the full field's flags 8-10, so that a value
#: means one thing in every file)
FLAG_U_OUTLIER = 11
#: a match that disagrees with its grid neighbours by far more than the image's typical
#: uncertainty (13: 12 is an imported field's ``failed_in_source``)
FLAG_NEIGHBOUR_OUTLIER = 13
#: the flags of a 2D result file (the engine's and the two outlier tests')
OUTPUT_FLAG_VALUES = np.array([*range(8), FLAG_U_OUTLIER, FLAG_NEIGHBOUR_OUTLIER], dtype=np.int8)
OUTPUT_FLAG_MEANINGS = FLAG_MEANINGS + " uncertainty_outlier neighbour_outlier"
#: fewer ok points than this in an image: no robust median, no outlier test
MIN_POINTS_OUTLIER_TEST = 10
#: a point with fewer usable grid neighbours than this (of its 8: ok, not on faint texture) is
#: tested on its own u only
MIN_NEIGHBOURS = 3
#: no outlier below this [pixel], neither a u nor a disagreement with the neighbours: on
#: (nearly) noise-free images every u is tiny (1e-6-1e-3 px) and ratios to the median say
#: nothing about the match; on GT4 with 1 grey level of noise (benchmarks/bench_dic_outliers.py)
#: matches with u of 0.01-0.02 px are within 0.05 px of the truth but for a few in ten thousand.
U_OUTLIER_FLOOR_PX = 0.02

#: positions of the affine parameters (u, du/dx, du/dy, v, dv/dx, dv/dy) in the 12-vector
AFFINE_INDEX = np.array([0, 1, 2, 6, 7, 8])
#: the 8 grid neighbours (row, column offsets)
_OFFSETS = np.array([(dr, dc) for dr in (-1, 0, 1) for dc in (-1, 0, 1) if dr or dc])


def neighbour_reach(subset_size: int, step: int) -> int:
    """Grid steps between a point and the neighbours it is compared with: the fewest that put
    them half a subset apart or more, so that two compared subsets share at most about half
    their pixels (and of their errors: at step 6 with 21-pixel subsets, next neighbours share
    71 % and a faint patch's points are off together, unseen by the test)."""
    return max(1, -(-(subset_size // 2) // step))


def grid_neighbours(index: np.ndarray, reach: int = 1) -> np.ndarray:
    """The 8 grid neighbours ``reach`` grid steps away of every point (N, 8), -1 where there
    is none.

    ``index`` (N, 2) int: ``(row, column)`` of each point in a regular grid (-1: a point off
    the grid, e.g. given by its coordinates; it has no neighbours and is no one's).
    """
    index = np.asarray(index, np.int64).reshape(-1, 2)
    n = len(index)
    nb = np.full((n, len(_OFFSETS)), -1, np.int64)
    on = (index >= 0).all(axis=1)
    if not on.any():
        return nb
    r, c = index[on].T
    lookup = np.full((r.max() + 1 + 2 * reach, c.max() + 1 + 2 * reach), -1, np.int64)
    lookup[r + reach, c + reach] = np.flatnonzero(on)
    for j, (dr, dc) in enumerate(_OFFSETS * reach):
        nb[on, j] = lookup[r + reach + dr, c + reach + dc]
    return nb


def _median_of_neighbours(A: np.ndarray) -> np.ndarray:
    """Median over axis 1 ignoring NaN, every row holding at least one finite value: what
    ``np.nanmedian(A, axis=1)`` gives, by one sort (NaN sorts last), several times faster."""
    B = np.sort(np.moveaxis(A, 1, -1), axis=-1)
    c = np.count_nonzero(~np.isnan(B), axis=-1)[..., None]
    lo = np.take_along_axis(B, (c - 1) // 2, axis=-1)
    hi = np.take_along_axis(B, c // 2, axis=-1)
    return ((lo + hi) / 2)[..., 0]


def neighbour_residuals(
    ok, P, centres, nb, usable=None, threshold=0.0
) -> tuple[np.ndarray, np.ndarray]:
    """How far each ok point's displacement lies from what its usable grid neighbours
    (``usable``, default ``ok``; ``nb`` from :func:`grid_neighbours`) say [pixel].

    The neighbours' displacements ``d_j`` are carried to the point (offset ``x_j - x``) in
    four ways, and the distance of the point's (u, v) from each set's median is returned:

    0. as they are (the median test of Westerweel 1994; exact for a field linear across a
       full, symmetric neighbourhood);
    1. along the image's median gradient ``G``, ``d_j - G (x_j - x)`` (exact for a
       homogeneous strain at a grid edge too; ``G`` is a median over the image: noise-free);
    2. trapezoidally along the point's own and each neighbour's measured gradients,
       ``d_j - (g_j + g) (x_j - x) / 2`` (exact for a quadratic field: a real strain
       gradient is not a disagreement; only as good as the point's gradients), with the
       Euler-Maclaurin term ``+ (x_j - x)^T (H_j - H) (x_j - x) / 12`` where the shape
       function measures second derivatives ``H`` (exact to the fourth order);
    3. the same with the neighbours' median gradient (and second derivatives) in place of
       the point's own.

    Returns
    -------
    res : ndarray (N, 4)
        The four distances; NaN where a point has fewer than :data:`MIN_NEIGHBOURS` usable
        neighbours, and 1-3 NaN where the first is ``threshold`` [pixel] or less (they are
        allowances: they only matter where the plain median test fails).
    count : ndarray (N,) int
        How many usable neighbours each ok point has.
    """
    n = len(ok)
    res = np.full((n, 4), np.nan)
    usable = ok if usable is None else usable
    has = (nb >= 0) & usable[np.where(nb >= 0, nb, 0)] & ok[:, None]
    count = np.count_nonzero(has, axis=1)
    test = count >= MIN_NEIGHBOURS
    if not test.any():
        return res, count
    A = np.asarray(P, float)[:, AFFINE_INDEX]
    d = A[:, [0, 3]]  # (u, v)
    g = A[:, [1, 2, 4, 5]].reshape(-1, 2, 2)  # [[du/dx, du/dy], [dv/dx, dv/dy]]
    # second derivatives [component, a, b] (zero for the affine shape function)
    Pf = np.asarray(P, float)
    h = Pf[:, [3, 4, 4, 5, 9, 10, 10, 11]].reshape(-1, 2, 2, 2) if Pf.shape[1] >= 12 else None
    idx = np.flatnonzero(test)
    # the median test first; the allowances only where it fails (they can only excuse)
    j = np.where(has[idx], nb[idx], 0)
    D = np.where(has[idx][..., None], d[j], np.nan)  # (M, 8, 2)
    res[idx, 0] = np.hypot(*(d[idx] - _median_of_neighbours(D)).T)
    keep = res[idx, 0] > threshold
    idx, j, D = idx[keep], j[keep], D[keep]
    if not idx.size:
        return res, count
    G = np.where(has[idx][..., None, None], g[j], np.nan)  # (M, 8, 2, 2)
    delta = centres[j] - centres[idx][:, None, :]  # (M, 8, 2) [pixel]
    uniform = np.median(g[ok], axis=0)
    gm = _median_of_neighbours(G)
    preds = [
        D - np.einsum("ab,mjb->mja", uniform, delta),
        D - np.einsum("mjab,mjb->mja", G + g[idx][:, None], delta) / 2,
        D - np.einsum("mjab,mjb->mja", G + gm[:, None], delta) / 2,
    ]
    if h is not None and np.any(h[ok]):  # Euler-Maclaurin: + dx^T (H_j - H) dx / 12
        H = np.where(has[idx][..., None, None, None], h[j], np.nan)  # (M, 8, 2, 2, 2)
        for k, h0 in ((1, h[idx]), (2, _median_of_neighbours(H))):
            preds[k] = (
                preds[k] + np.einsum("mjcab,mja,mjb->mjc", H - h0[:, None], delta, delta) / 12
            )
    for k, pred in enumerate(preds, start=1):
        res[idx, k] = np.hypot(*(d[idx] - _median_of_neighbours(pred)).T)
    return res, count


def flag_uncertainty_outliers(
    flag: np.ndarray,
    sigma: np.ndarray,
    factor: float,
    *,
    P: np.ndarray | None = None,
    centres: np.ndarray | None = None,
    index: np.ndarray | None = None,
    neighbour_factor: float = 0.0,
    reach: int = 1,
    neighbour_images: np.ndarray | None = None,
) -> np.ndarray:
    """``flag`` with ``neighbour_outlier`` where a match disagrees with its grid neighbours by
    far more than its image's typical uncertainty, and ``uncertainty_outlier`` where a match
    that cannot be compared with neighbours has an uncertainty far above its image's.

    Per image, with ``m`` the median of u (the larger of a point's two components) over the
    ok points, ``T = max(neighbour_factor * m, U_OUTLIER_FLOOR_PX)``, and a point "faint"
    when its u exceeds ``factor * m`` (its subset's texture is faint; its value and gradients
    are imprecise):

    * the usable neighbours of a point are its ok, not faint grid neighbours ``reach`` grid
      steps away (:func:`grid_neighbours`); a point with at least :data:`MIN_NEIGHBOURS` of
      them is ``neighbour_outlier`` when its displacement lies more than ``T`` from every
      prediction of :func:`neighbour_residuals` (for a faint point, from every one but that
      along its own gradients, which are too noisy to explain a disagreement away): the
      median test (Westerweel 1994, Exp. Fluids 16:236) with a threshold in units of the
      image's typical uncertainty, made exact for smooth (quadratic) deformation;
    * any other ok point (too few usable neighbours, points off a grid, ``neighbour_factor``
      0) is ``uncertainty_outlier`` when it is faint and its u exceeds ``U_OUTLIER_FLOOR_PX``.

    Why: on GT4 with 1-2 grey levels of noise (benchmarks/bench_dic_outliers.py) the points
    off by more than 0.05 pixel are not told apart by their residual or ZNCC, and a threshold
    on u alone cannot both keep 98 % of the good points and leave <= 0.2 % of the ok points
    off: good points on faint texture have legitimately large u. Their neighbours tell them
    apart. The normalised median test of Westerweel & Scarano (2005, Exp. Fluids 39:1096),
    which scales the threshold by the neighbours' own scatter, lets them through: on faint
    texture the neighbours scatter as much.

    Parameters
    ----------
    flag : ndarray (..., N) int
        Flags of the N points of every image (leading dims: images).
    sigma : ndarray (..., N, 2)
        Standard uncertainties of (u, v) [pixel] from the match residual.
    factor : float
        The multiple of the median u above which a point is faint (0: none is).
    P : ndarray (..., N, 12), optional
        The matches' warp parameters (u and v, and their gradients, at ``AFFINE_INDEX``).
    centres : ndarray (N, 2), optional
        Subset centres ``(x, y)`` [pixel] in the reference image.
    index : ndarray (N, 2) int, optional
        ``(row, column)`` of each point in the regular grid (-1: off the grid).
    neighbour_factor : float
        ``T`` in multiples of the median u (0, or without ``P``/``centres``/``index``: no
        neighbour test). Images with fewer than ``MIN_POINTS_OUTLIER_TEST`` ok points are not
        tested.
    reach : int
        Grid steps to the compared neighbours (:func:`neighbour_reach`).
    neighbour_images : ndarray of bool, optional
        Per image (leading dims flattened): whether the neighbour test applies (default:
        all). An incremental sequence's later images hold displacements composed over several
        references, whose errors their u does not describe (RMS 0.33 pixel against a median u
        of 0.055 after 3 updates in tests/dic/test_dic_fixes.py): a threshold in units of u
        means nothing there, and only the u test applies.

    Returns
    -------
    ndarray
        A new flag array (the input is not changed).
    """
    out = np.array(flag, dtype=np.int8, copy=True)
    if not factor and not neighbour_factor:
        return out
    n = out.shape[-1]
    u = np.max(np.asarray(sigma, float), axis=-1).reshape(-1, n)
    rows = out.reshape(-1, n)
    use_nb = bool(neighbour_factor) and P is not None and centres is not None and index is not None
    if use_nb:
        nb = grid_neighbours(index, reach)
        P = np.asarray(P, float)
        Ps = P.reshape(-1, n, P.shape[-1])
        centres = np.asarray(centres, float)
    for k, (f, s) in enumerate(zip(rows, u, strict=True)):
        ok = (f == FLAG_OK) & np.isfinite(s)
        if ok.sum() < MIN_POINTS_OUTLIER_TEST:
            continue
        med = np.median(s[ok])
        high_u = (s > factor * med) if factor else np.zeros(n, bool)
        tested = np.zeros(n, bool)
        if use_nb and (neighbour_images is None or np.ravel(neighbour_images)[k]):
            # neighbours on faint texture (high u) are not a reference for others
            T = max(neighbour_factor * med, U_OUTLIER_FLOOR_PX)
            res, count = neighbour_residuals(ok, Ps[k], centres, nb, ok & ~high_u, T)
            tested = ok & (count >= MIN_NEIGHBOURS)
            # a point on faint texture (high u) is not excused by its own noisy gradients
            res[high_u, 2] = np.inf
            off = tested & (np.nanmin(res, axis=1, initial=np.inf) > T)
            f[off] = FLAG_NEIGHBOUR_OUTLIER
        if factor:
            lone = ok & ~tested & high_u & (s > U_OUTLIER_FLOOR_PX)
            f[lone] = FLAG_U_OUTLIER
    return out
