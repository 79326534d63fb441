"""IC-GN drivers (numba): many points in parallel, preloaded reference subsets for trackers,
and reliability-guided propagation from seeds.

Arguments come packed as in :mod:`jointwear.dic.icgn._solve` (``ref``, ``dfm``, ``opts``), and
the per-point outputs as ``out`` = ``(zncc, iterations, flags, sigma)``.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from jointwear.dic.icgn._flags import FLAG_LOW_CORRELATION, FLAG_NO_TEXTURE, FLAG_OK
from jointwear.dic.icgn._reference import _load_reference
from jointwear.dic.icgn._solve import _affine_system, _iterate_affine, make_work, solve_point
from jointwear.dic.icgn._warp import _extrapolate


@njit(cache=True, inline="always")
def _store_point(i, p, z, it, fl, w, zncc_min, P, out):
    """Write point ``i``'s outcome (low ZNCC flagged) and its u, v uncertainty from ``w``."""
    zncc, iters, flags, sigma = out
    if fl == FLAG_OK and not (z >= zncc_min):
        fl = FLAG_LOW_CORRELATION
    for q in range(12):
        P[i, q] = p[q]
    zncc[i] = z
    iters[i] = it
    flags[i] = fl
    sigma[i, 0] = w[3, 4]
    sigma[i, 1] = w[3, 5]


#: points of a propagation group that measure the IC-GN's contraction with the classic
#: convergence test before the group's later points may assume it
CONTRACTION_PROBES = 16
#: smallest contraction assumed (the test then stops at a step of 20 x the tolerance)
CONTRACTION_FLOOR = 0.05


@njit(cache=True, inline="always")
def _measure_contraction(probe, it, fl, w):
    """Update a propagation group's contraction probe ``probe`` = (points measured, largest
    ratio, rho in use, points to measure) with one solved point: a point that converged with
    the classic test after two iterations or more gives the ratio of its last step to the one
    before (``w[3, 0:2]``; the last steps, nearest to the solution, where the Gauss-Newton
    converges linearly). Once ``probe[3]`` points have, rho = the largest ratio (at least
    ``CONTRACTION_FLOOR``); ``probe[3] <= 0`` keeps the classic test."""
    if probe[0] < probe[3] and fl == FLAG_OK and it >= 2 and w[3, 0] > 0.0:
        probe[1] = max(probe[1], w[3, 1] / w[3, 0])
        probe[0] += 1.0
        if probe[0] == probe[3]:
            probe[2] = min(max(probe[1], CONTRACTION_FLOOR), 1.0)


@njit(cache=True)
def _refine_chunk(ch, n_chunks, ref, dfm, opts, centres, scale, P, active, out):
    """Refine the active points ``ch, ch + n_chunks, ...`` from ``P[i]`` (in place);
    ``scale[i]`` multiplies point i's Gauss-Newton steps (its kappa, see
    :func:`~jointwear.dic.icgn._solve._iterate`), with the classic convergence test: guessed
    points often share their start offset (a previous frame's field), so stopping them short
    (see :func:`rg_propagate`) would leave a common bias rather than scatter."""
    n = centres.shape[0]
    work = make_work(opts[0])
    p = np.empty(12)
    for i in range(ch, n, n_chunks):
        if not active[i]:
            continue
        for q in range(12):
            p[q] = P[i, q]
        z, it, fl = solve_point(
            ref, dfm, opts, centres[i, 0], centres[i, 1], p, work, scale[i], 1.0
        )
        _store_point(i, p, z, it, fl, work[4], opts[7], P, out)


@njit(cache=True, parallel=True)
def icgn_many(ref, dfm, opts, centres, scale, P, active, out):
    """Refine every active point from its initial parameters ``P[i]`` (in place), in parallel
    (``scale``: the points' step factors, see :func:`_refine_chunk`)."""
    n_chunks = min(centres.shape[0], 64)
    for ch in prange(n_chunks):
        _refine_chunk(ch, n_chunks, ref, dfm, opts, centres, scale, P, active, out)


@njit(cache=True)
def icgn_serial(ref, dfm, opts, centres, scale, P, active, out):
    """As :func:`icgn_many` on one thread (for a handful of points, e.g. seeds)."""
    n_chunks = min(centres.shape[0], 64)
    for ch in range(n_chunks):
        _refine_chunk(ch, n_chunks, ref, dfm, opts, centres, scale, P, active, out)


@njit(cache=True, nogil=True)
def affine_references(ref, opts, centres, F, GX, GY, HINV, JF, JS, FN, FLAG0):
    """Load every reference subset once for :func:`icgn_affine_loaded`: zero-mean values
    ``F`` (n, m), gradients ``GX``, ``GY``, norms ``FN``, inverse Hessians ``HINV`` (n, 6, 6),
    ``JF``/``JS`` (n, 6) and the loading outcome ``FLAG0`` (n,)."""
    ref_img, ref_gx, ref_gy, ref_coef, ref_invalid = ref
    half, _, _, _, min_std, _, border, _, order = opts
    w = np.empty((4, 6))
    for i in range(centres.shape[0]):
        fl, fn = _load_reference(
            ref_img, ref_gx, ref_gy, ref_coef, ref_invalid, order, centres[i, 0], centres[i, 1],
            half, min_std, border, F[i], GX[i], GY[i], w,
        )  # fmt: skip
        FN[i] = fn
        for a in range(6):
            for b in range(6):
                HINV[i, a, b] = 1.0 if a == b else 0.0
            JF[i, a] = 0.0
            JS[i, a] = 0.0
        if fl == FLAG_OK and not _affine_system(F[i], GX[i], GY[i], half, HINV[i], JF[i], JS[i]):
            fl = FLAG_NO_TEXTURE
        FLAG0[i] = fl


@njit(cache=True, nogil=True)
def icgn_affine_loaded(loaded, dfm, opts, centres, scale, P, active, out):
    """As :func:`icgn_serial` (affine shape) with the reference subsets preloaded by
    :func:`affine_references` (``loaded`` = ``(F, GX, GY, HINV, JF, JS, FN, FLAG0)``): a tracker
    matching the same subsets in many frames skips the per-frame loading and Hessian. Runs
    without the GIL (one thread per call)."""
    F, GX, GY, HINV, JF, JS, FN, FLAG0 = loaded
    def_coef, def_invalid = dfm
    half, _, max_iter, tol, _, max_shift, border, zncc_min, order = opts
    zncc, iters, flags, sigma = out
    w = np.empty((4, 6))
    p = np.empty(12)
    for i in range(centres.shape[0]):
        if not active[i]:
            continue
        if FLAG0[i] != FLAG_OK:
            zncc[i] = np.nan
            iters[i] = 0
            flags[i] = FLAG0[i]
            sigma[i, 0] = np.nan
            sigma[i, 1] = np.nan
            continue
        for q in range(12):
            p[q] = P[i, q]
        w[3, 4] = np.nan
        w[3, 5] = np.nan
        z, it, fl = _iterate_affine(
            F[i], GX[i], GY[i], FN[i], HINV[i], JF[i], JS[i], def_coef, def_invalid, order,
            centres[i, 0], centres[i, 1], half, p, max_iter, tol, max_shift, border, w, scale[i],
            1.0,
        )  # fmt: skip
        _store_point(i, p, z, it, fl, w, zncc_min, P, out)


# ---------------------------------------------------------------- reliability-guided propagation


@njit(cache=True)
def _heap_push(keys, vals, size, key, val):
    i = size
    keys[i] = key
    vals[i] = val
    while i > 0:
        parent = (i - 1) // 2
        if keys[parent] >= keys[i]:
            break
        keys[parent], keys[i] = keys[i], keys[parent]
        vals[parent], vals[i] = vals[i], vals[parent]
        i = parent
    return size + 1


@njit(cache=True)
def _heap_pop(keys, vals, size):
    val = vals[0]
    size -= 1
    keys[0] = keys[size]
    vals[0] = vals[size]
    i = 0
    while True:
        left = 2 * i + 1
        right = left + 1
        best = i
        if left < size and keys[left] > keys[best]:
            best = left
        if right < size and keys[right] > keys[best]:
            best = right
        if best == i:
            break
        keys[best], keys[i] = keys[i], keys[best]
        vals[best], vals[i] = vals[i], vals[best]
        i = best
    return val, size


@njit(cache=True)
def _propagate_group(
    g, group, ref, dfm, opts, centres, scale, nb_ptr, nb_idx, P, out, done, probes
):
    """Propagation within group ``g`` (all points when ``g < 0``), see :func:`rg_propagate`."""
    zncc, _, flags, _ = out
    n = centres.shape[0]
    keys = np.empty(n)
    vals = np.empty(n, dtype=np.int64)
    size = 0
    for i in range(n):
        if (g < 0 or group[i] == g) and done[i] and flags[i] == FLAG_OK:
            size = _heap_push(keys, vals, size, zncc[i], i)
    guess = np.empty(12)
    work = make_work(opts[0])
    w = work[4]
    # points measured, largest ratio, rho in use, points to measure
    probe = np.array([0.0, 0.0, 1.0, float(probes)])
    while size > 0:
        i, size = _heap_pop(keys, vals, size)
        for q in range(nb_ptr[i], nb_ptr[i + 1]):
            j = nb_idx[q]
            if done[j] or (g >= 0 and group[j] != g):
                continue
            _extrapolate(P[i], centres[j, 0] - centres[i, 0], centres[j, 1] - centres[i, 1], guess)
            z, it, fl = solve_point(
                ref, dfm, opts, centres[j, 0], centres[j, 1], guess, work, scale[j], probe[2]
            )
            done[j] = True
            _measure_contraction(probe, it, fl, w)
            _store_point(j, guess, z, it, fl, w, opts[7], P, out)
            if flags[j] == FLAG_OK:
                size = _heap_push(keys, vals, size, z, j)


@njit(cache=True, parallel=True)
def rg_propagate(
    n_groups, group, ref, dfm, opts, centres, scale, nb_ptr, nb_idx, P, out, done, probes
):
    """Reliability-guided propagation: from the solved (``done`` and ok) points of each group,
    always extend from the best-correlated point to its unsolved neighbours (guess = its
    parameters extrapolated). Groups run in parallel; ``n_groups = 0`` runs one global pass
    ignoring groups.

    Convergence: each group's first ``probes`` points (``CONTRACTION_PROBES`` in the
    correlator; 0 keeps the classic test throughout) that take two iterations or more run the
    classic test (step below the tolerance) and measure the contraction per iteration, the
    ratio of their last step to the one before; the group's later points may also stop on
    their first or second step when it times the largest ratio measured (at least
    ``CONTRACTION_FLOOR``) is below the tolerance (:func:`~jointwear.dic.icgn._solve._iterate`).
    From a neighbour's solution the first step is the noise of that neighbour and the
    contraction 0.02-0.05 (affine; up to 0.4 with the second-order shape on a wave, or at 5
    grey levels of noise on a low-contrast pattern), so most points stop after one iteration
    instead of two."""
    if n_groups == 0:
        _propagate_group(
            -1, group, ref, dfm, opts, centres, scale, nb_ptr, nb_idx, P, out, done, probes
        )
        return
    for g in prange(n_groups):
        _propagate_group(
            g, group, ref, dfm, opts, centres, scale, nb_ptr, nb_idx, P, out, done, probes
        )
