"""One IC-GN subset match (numba): Gauss-Newton systems and iterations, affine and second
order, from one reference loading (:func:`solve_point`).

Criterion: zero-normalised sum of squared differences (ZNSSD), minimised by the
inverse-compositional Gauss-Newton (Baker & Matthews 2004; Pan, Li & Tong 2013): the Hessian is
built once per subset from the reference gradients (central differences, see
:mod:`jointwear.dic.icgn._interp`), each iteration samples the deformed image once at the warped
subset and updates ``W(p) <- W(p) o W(dp)^-1``. Kernel arguments come packed: ``ref`` =
``(image, gx, gy, coef, invalid)`` of the reference, ``dfm`` = ``(coef, invalid)`` of the
deformed image, ``opts`` = ``(half, quadratic, max_iter, tol, min_std, max_shift, border,
zncc_min, order)``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from jointwear.dic.icgn._flags import (
    AFFINE_INDEX,
    FLAG_DIVERGED,
    FLAG_INVALID_PIXELS,
    FLAG_NO_TEXTURE,
    FLAG_NOT_CONVERGED,
    FLAG_OK,
    FLAG_OUTSIDE,
)
from jointwear.dic.icgn._interp import PAD
from jointwear.dic.icgn._reference import _box_has_invalid, _load_reference, _store_sigma
from jointwear.dic.icgn._sample import add_row_sums, row_scratch, sample_affine, sample_row
from jointwear.dic.icgn._warp import _compose_inverse, _solve_spd

# a subset still below this ZNCC after this many iterations is not going to match
_HOPELESS_AFTER = 10
_HOPELESS_ZNCC = 0.5

_FM = {"nsz", "arcp", "contract", "reassoc"}  # fastmath without no-NaN/no-inf assumptions


#: position in a block's six moments (1, c, r, cc, cr, rr) of the products of (1, c, r)
_MOMENT = (0, 1, 2, 1, 3, 4, 2, 4, 5)


@njit(cache=True, fastmath=_FM)
def _hessian_affine(f, gx, gy, half, Hm, jf, js):
    """Affine Gauss-Newton Hessian ``sum J J^T``, ``sum J f`` and ``sum J`` (row-wise sums)."""
    m = np.zeros(18)  # aa, ab, bb moments: 1, c, r, cc, cr, rr
    size = 2 * half + 1
    k0 = 0
    for r in range(-half, half + 1):
        rr = float(r)
        raa = raac = raacc = rab = rabc = rabcc = rbb = rbbc = rbbcc = 0.0
        rfa = rfac = rfb = rfbc = rsa = rsac = rsb = rsbc = 0.0
        # the row's pixels by a count from 0 (a form the compiler vectorises: twice as fast
        # as the loop over c = -half..half), the column offset c as a float
        for j in range(size):
            k = k0 + j
            c = float(j - half)
            a = gx[k]
            b = gy[k]
            fk = f[k]
            q = a * a
            raa += q
            raac += q * c
            raacc += q * c * c
            q = a * b
            rab += q
            rabc += q * c
            rabcc += q * c * c
            q = b * b
            rbb += q
            rbbc += q * c
            rbbcc += q * c * c
            rfa += a * fk
            rfac += a * fk * c
            rfb += b * fk
            rfbc += b * fk * c
            rsa += a
            rsac += a * c
            rsb += b
            rsbc += b * c
        k0 += size
        for o, s1, sc, scc in (
            (0, raa, raac, raacc),
            (6, rab, rabc, rabcc),
            (12, rbb, rbbc, rbbcc),
        ):
            m[o] += s1
            m[o + 1] += sc
            m[o + 2] += s1 * rr
            m[o + 3] += scc
            m[o + 4] += sc * rr
            m[o + 5] += s1 * rr * rr
        add_row_sums(jf, 0, rfa, rfac, rr)
        add_row_sums(jf, 3, rfb, rfbc, rr)
        add_row_sums(js, 0, rsa, rsac, rr)
        add_row_sums(js, 3, rsb, rsbc, rr)
    # J = [a, a c, a r, b, b c, b r]: block (i, j) of sum J J^T from the moments
    for blk_i in range(2):
        for blk_j in range(blk_i, 2):
            o = 0 if (blk_i == 0 and blk_j == 0) else (6 if blk_i != blk_j else 12)
            for i in range(3):
                for j in range(3):
                    # the symmetric 3x3 moment block: (1, c, r) x (1, c, r) -> m[o + _MOMENT]
                    v = m[o + _MOMENT[i * 3 + j]]
                    Hm[3 * blk_i + i, 3 * blk_j + j] = v
                    Hm[3 * blk_j + j, 3 * blk_i + i] = v


@njit(cache=True, nogil=True)
def _affine_system(f, gx, gy, half, Hinv, jf, js):
    """Inverse Gauss-Newton Hessian (into ``Hinv``, which must hold the identity), ``sum J f``
    and ``sum J``; False when the Hessian is singular (no texture)."""
    Hm = np.empty((6, 6))
    _hessian_affine(f, gx, gy, half, Hm, jf, js)
    return _solve_spd(Hm, Hinv, 6)


@njit(cache=True, inline="always")
def _second_order_terms(out, o, g, c, r):
    """``out[o : o + 6]`` = ``g (1, c, r, c^2/2, c r, r^2/2)``: one image gradient's half of
    the second-order Jacobian at subset pixel (c, r)."""
    out[o] = g
    out[o + 1] = g * c
    out[o + 2] = g * r
    out[o + 3] = 0.5 * g * c * c
    out[o + 4] = g * c * r
    out[o + 5] = 0.5 * g * r * r


@njit(cache=True, inline="always")
def _add_second_order_row_sums(out, o, s, sc, scc, rr):
    """Add one subset row's sums of ``q``, ``q c`` and ``q c^2`` (``rr`` the row) to
    ``out[o : o + 6]``: the sums of ``q (1, c, r, c^2/2, c r, r^2/2)``, the second-order
    Jacobian's pattern (:func:`~jointwear.dic.icgn._sample.add_row_sums` for the first three)."""
    add_row_sums(out, o, s, sc, rr)
    out[o + 3] += 0.5 * scc
    out[o + 4] += sc * rr
    out[o + 5] += 0.5 * s * rr * rr


@njit(cache=True, nogil=True)
def _quadratic_system(f, gx, gy, half, Hinv, jf, js):
    """As :func:`_affine_system` with the 12-parameter second-order Jacobian."""
    Hm = np.zeros((12, 12))
    J = np.empty(12)
    k = 0
    for r in range(-half, half + 1):
        for c in range(-half, half + 1):
            _second_order_terms(J, 0, gx[k], c, r)
            _second_order_terms(J, 6, gy[k], c, r)
            fk = f[k]
            for i in range(12):
                ji = J[i]
                jf[i] += ji * fk
                js[i] += ji
                for j in range(i + 1):
                    Hm[i, j] += ji * J[j]
            k += 1
    for i in range(12):
        for j in range(i + 1, 12):
            Hm[i, j] = Hm[j, i]
    return _solve_spd(Hm, Hinv, 12)


@njit(cache=True, inline="always")
def _valid_box(def_coef, border):
    """Where warped subset pixels may lie in the deformed image: ``lo <= x <= hix``,
    ``lo <= y <= hiy`` [pixel] (``border`` pixels from its edges)."""
    Hd = def_coef.shape[0] - 2 * PAD
    Wd = def_coef.shape[1] - 2 * PAD
    return float(border), Wd - 1.0 - border, Hd - 1.0 - border


@njit(cache=True, inline="always")
def _invalid_near(def_invalid, xmin, ymin, xmax, ymax):
    """True if the deformed image has invalid pixels within 3 pixels of the warped subset's
    bounding box (``def_invalid`` of shape (1, 1): no invalid pixels)."""
    return def_invalid.shape[0] > 1 and _box_has_invalid(
        def_invalid,
        int(math.floor(xmin)) - 3,
        int(math.floor(ymin)) - 3,
        int(math.ceil(xmax)) + 3,
        int(math.ceil(ymax)) + 3,
    )


@njit(cache=True, inline="always")
def _zncc_of(sg, sgg, sgf, n, fn, it):
    """ZNCC of the sampled deformed subset from its sums ``sum g``, ``sum g^2``, ``sum g f``
    (``fn``: the reference's norm). Returns ``(flag, zncc, gm, ratio)``: flag -1 to go on
    (``gm`` the subset mean, ``ratio`` = fn / gn), else the flag to stop with."""
    gm = sg / n
    gn2 = sgg - n * gm * gm
    if not gn2 > 1e-300:
        return FLAG_NO_TEXTURE, np.nan, gm, 0.0
    gn = math.sqrt(gn2)
    zncc = sgf / (fn * gn)
    if it >= _HOPELESS_AFTER and not (zncc >= _HOPELESS_ZNCC):
        return FLAG_NOT_CONVERGED, zncc, gm, 0.0  # far from any match: stop early
    return -1, zncc, gm, fn / gn


@njit(cache=True, inline="always")
def _gauss_newton_step(Hinv, jf, js, jg, gm, ratio, e, dp, index, scale):
    """The Gauss-Newton increment ``dp[index] = -scale Hinv (Jf - ratio (Jg - gm Js))``
    (``scale``: the subset's kappa, see :func:`_iterate`)."""
    m = e.shape[0]
    for j in range(m):
        e[j] = jf[j] - ratio * (jg[j] - gm * js[j])
    for i in range(m):
        s = 0.0
        for j in range(m):
            s += Hinv[i, j] * e[j]
        dp[index[i]] = -scale * s


@njit(cache=True, inline="always")
def _diverged(p, p_start_u, p_start_v, max_shift):
    """True if a parameter is not finite or (u, v) moved more than ``max_shift`` [pixel]
    from the start."""
    ok = True
    for i in range(12):
        if not math.isfinite(p[i]):
            ok = False
    return not ok or abs(p[0] - p_start_u) > max_shift or abs(p[6] - p_start_v) > max_shift


#: positions of the second-order increment in the 12 parameters (all of them)
QUADRATIC_INDEX = np.arange(12)


@njit(cache=True, inline="always")
def _step_norm(dp, half, quadratic):
    """Size of the increment ``dp`` [pixel]: how far it moves the subset's edge (``half``
    pixels from the centre), the convergence measure of Pan, Li & Tong (2013)."""
    hh = float(half)
    norm = dp[0] * dp[0] + dp[6] * dp[6]
    norm += hh * hh * (dp[1] * dp[1] + dp[2] * dp[2] + dp[7] * dp[7] + dp[8] * dp[8])
    if quadratic:
        q = 0.5 * hh * hh
        norm += q * q * (dp[3] ** 2 + dp[5] ** 2 + dp[9] ** 2 + dp[11] ** 2)
        norm += hh**4 * (dp[4] ** 2 + dp[10] ** 2)
    return math.sqrt(norm)


@njit(cache=True, inline="always")
def _sample_affine_warp(f, gx, gy, def_coef, def_invalid, order, xc, yc, half, p, box, acc):
    """Sample the deformed image over the affinely warped subset into ``acc`` = (``sum g``,
    ``sum g^2``, ``sum g f``, ``sum J g`` (6)). Returns -1, or the flag to stop with: the
    subset leaves ``box`` = ``(lo, hix, hiy)`` (:func:`_valid_box`) or has invalid pixels near.
    """
    lo, hix, hiy = box
    a11 = 1.0 + p[1]
    a12 = p[2]
    a21 = p[7]
    a22 = 1.0 + p[8]
    # the warped subset is a parallelogram: its corners bound it
    xmin = 1e300
    xmax = -1e300
    ymin = 1e300
    ymax = -1e300
    for corner in range(4):
        c = -half if corner % 2 == 0 else half
        r = -half if corner < 2 else half
        xw = xc + p[0] + a11 * c + a12 * r
        yw = yc + p[6] + a21 * c + a22 * r
        xmin = min(xmin, xw)
        xmax = max(xmax, xw)
        ymin = min(ymin, yw)
        ymax = max(ymax, yw)
    if not (xmin >= lo and ymin >= lo and xmax <= hix and ymax <= hiy):
        return FLAG_OUTSIDE
    if _invalid_near(def_invalid, xmin, ymin, xmax, ymax):
        return FLAG_INVALID_PIXELS
    x_start = xc + p[0] - a11 * half
    y_start = yc + p[6] - a21 * half
    sample_affine(def_coef, order, x_start, y_start, a11, a12, a21, a22, half, f, gx, gy, acc)
    return -1


@njit(cache=True, inline="always")
def _sample_quadratic_warp(f, gx, gy, def_coef, def_invalid, order, xc, yc, half, p, box, acc):
    """As :func:`_sample_affine_warp` for the second-order warp: every warped pixel
    bounds-checked, the 12-parameter ``sum J g``; each row's positions first, then the row
    sampled in passes (:func:`~jointwear.dic.icgn._sample.sample_row`)."""
    lo, hix, hiy = box
    jg = acc[3:]
    for i in range(12):
        jg[i] = 0.0
    sg = sgg = sgf = 0.0
    xmin = 1e300
    xmax = -1e300
    ymin = 1e300
    ymax = -1e300
    size = 2 * half + 1
    scratch = row_scratch(size)
    xs, ys, g = scratch[0], scratch[1], scratch[6]
    k0 = 0
    for r in range(-half, half + 1):
        rr = float(r)
        # the warp along the row: a quadratic in the column offset c
        x0 = xc + p[0] + p[2] * rr + 0.5 * p[5] * rr * rr
        x1 = 1.0 + p[1] + p[4] * rr
        y0 = yc + rr + p[6] + p[8] * rr + 0.5 * p[11] * rr * rr
        y1 = p[7] + p[10] * rr
        for j in range(size):
            cc = float(j - half)
            xs[j] = x0 + x1 * cc + 0.5 * p[3] * cc * cc
            ys[j] = y0 + y1 * cc + 0.5 * p[9] * cc * cc
        for j in range(size):
            if not (xs[j] >= lo and ys[j] >= lo and xs[j] <= hix and ys[j] <= hiy):
                return FLAG_OUTSIDE  # (NaN included)
            xmin = min(xmin, xs[j])
            xmax = max(xmax, xs[j])
            ymin = min(ymin, ys[j])
            ymax = max(ymax, ys[j])
        sample_row(def_coef, order, size, scratch)
        ra = rb = rac = rbc = racc = rbcc = 0.0
        for j in range(size):
            k = k0 + j
            cc = float(j - half)
            gv = g[j]
            sg += gv
            sgg += gv * gv
            sgf += gv * f[k]
            qa = gx[k] * gv
            qb = gy[k] * gv
            ra += qa
            rac += qa * cc
            racc += qa * cc * cc
            rb += qb
            rbc += qb * cc
            rbcc += qb * cc * cc
        k0 += size
        _add_second_order_row_sums(jg, 0, ra, rac, racc, rr)
        _add_second_order_row_sums(jg, 6, rb, rbc, rbcc, rr)
    if _invalid_near(def_invalid, xmin, ymin, xmax, ymax):
        return FLAG_INVALID_PIXELS
    acc[0] = sg
    acc[1] = sgg
    acc[2] = sgf
    return -1


@njit(cache=True, inline="always")
def _contracting(it, step, previous):
    """May a point stop on an assumed contraction after its ``it``-th step (norm ``step``,
    ``previous`` the one before)? Only on its first step (nothing of its own is known yet) or
    on its second if that halved the first: a point still iterating after two steps, or whose
    steps do not shrink, is wandering (weak texture, a wrong basin), and stopping it on a small
    step would report a point that never converged."""
    return it == 1 or (it == 2 and step <= 0.5 * previous)


@njit(cache=True, inline="always")
def _iterate(
    f, gx, gy, fn, Hinv, jf, js, def_coef, def_invalid, order, xc, yc, half, p, max_iter, tol,
    max_shift, border, w, quadratic, scale, rho,
):  # fmt: skip
    """Gauss-Newton iterations of the IC-GN from the loaded reference subset, affine or
    second order (``quadratic``); :func:`_iterate_affine` and :func:`_iterate_quadratic` are
    its compiled forms.

    Uses ``sum J (f - fm - fn/gn (g - gm)) = Jf - fn/gn (Jg - gm Js)`` with ``Jf``, ``Js``
    fixed per subset, so each iteration samples the deformed subset once and accumulates.

    ``scale`` multiplies every increment: the subset's ``kappa = sum |g_c|^2 / sum g_c . g_s``
    (:func:`~jointwear.dic.icgn._reference.subset_kappa`; 1 gives the plain Gauss-Newton
    step). The Jacobian holds the central-difference gradients ``g_c`` while the residual
    responds to a change of the warp through the interpolant's gradient ``g_s``, so the plain
    step overshoots by about ``1 / kappa`` (1.10-1.16 on 5-px speckle) and the iterations
    converge only linearly, by a factor ``1 - 1 / kappa`` each; the scaled step removes most of
    that. The solution (where ``sum J_c e = 0``) is the same: on 2 grey levels of noise the
    matches move by less than the tolerance and the iterations fall from 2.5-2.9 to 2.0
    (``benchmarks/bench_dic2d.py``).

    Convergence: the iterations stop when the last step ``dp`` (:func:`_step_norm`, pixels at
    the subset's edge) is below ``tol``, the classic criterion of Pan, Li & Tong (2013), or
    when its predicted remaining error ``rho |dp|`` is, on the point's first or second step
    only (:func:`_contracting`). ``rho`` is the contraction of one iteration (the ratio of
    successive steps): 1 assumes nothing about it (the classic criterion alone);
    the propagation passes the contraction it measured on each group's first points (see
    :func:`~jointwear.dic.icgn._drive.rg_propagate`), which stops most points one iteration
    earlier, a verification step that would have moved them by about ``rho |dp|``. The last
    two step norms are left in ``w[3, 0]`` and ``w[3, 1]`` (NaN when not taken).
    """
    box = _valid_box(def_coef, border)
    n = (2 * half + 1) ** 2
    m = 12 if quadratic else 6
    index = QUADRATIC_INDEX if quadratic else AFFINE_INDEX
    acc = np.empty(3 + m)  # sum g, sum g^2, sum g f, sum J g
    e = np.empty(m)
    dp = np.zeros(12)
    p_start_u = p[0]
    p_start_v = p[6]
    zncc = np.nan
    it = 0
    while it < max_iter:
        it += 1
        if quadratic:
            stop = _sample_quadratic_warp(
                f, gx, gy, def_coef, def_invalid, order, xc, yc, half, p, box, acc
            )
        else:
            stop = _sample_affine_warp(
                f, gx, gy, def_coef, def_invalid, order, xc, yc, half, p, box, acc
            )
        if stop >= 0:
            return np.nan, it, stop
        stop, zncc, gm, ratio = _zncc_of(acc[0], acc[1], acc[2], n, fn, it)
        if stop >= 0:
            return zncc, it, stop
        _gauss_newton_step(Hinv, jf, js, acc[3:], gm, ratio, e, dp, index, scale)
        if not _compose_inverse(p, dp, quadratic):
            return zncc, it, FLAG_DIVERGED
        if _diverged(p, p_start_u, p_start_v, max_shift):
            return np.nan, it, FLAG_DIVERGED
        step = _step_norm(dp, half, quadratic)
        w[3, 0] = w[3, 1]  # the last two step norms: the contraction is their ratio
        w[3, 1] = step
        if step < tol or (rho * step < tol and _contracting(it, step, w[3, 0])):
            _store_sigma(w, fn, zncc, n, m, Hinv[0, 0], Hinv[m // 2, m // 2])
            return zncc, it, FLAG_OK
    return zncc, it, FLAG_NOT_CONVERGED


def _specialise(name: str, quadratic: bool, doc: str, **jit_options):
    """Compile :func:`_iterate` for one warp order (``quadratic`` frozen as a constant) under
    ``name``, which also names its numba cache files; one source for both specialisations."""

    def iterate(
        f, gx, gy, fn, Hinv, jf, js, def_coef, def_invalid, order, xc, yc, half, p, max_iter,
        tol, max_shift, border, w, scale, rho,
    ):  # fmt: skip
        return _iterate(
            f, gx, gy, fn, Hinv, jf, js, def_coef, def_invalid, order, xc, yc, half, p,
            max_iter, tol, max_shift, border, w, quadratic, scale, rho,
        )  # fmt: skip

    iterate.__name__ = iterate.__qualname__ = name
    iterate.__doc__ = doc
    return njit(cache=True, **jit_options)(iterate)


_iterate_affine = _specialise(
    "_iterate_affine", False, ":func:`_iterate` with the affine warp (6 parameters).", nogil=True
)
_iterate_quadratic = _specialise(
    "_iterate_quadratic",
    True,
    ":func:`_iterate` with the second-order warp (12 parameters).",
    fastmath=_FM,
)


@njit(cache=True)
def make_work(half):
    """Scratch arrays for :func:`solve_point` (one set per thread/chunk)."""
    n = (2 * half + 1) ** 2
    return np.empty(n), np.empty(n), np.empty(n), np.empty(n), np.empty((4, 6))


@njit(cache=True)
def solve_point(ref, dfm, opts, xc, yc, p, work, scale, rho=1.0):
    """Match one subset centred at (xc, yc) of the reference; refines ``p`` (12,) in place.

    ``work`` comes from :func:`make_work`; ``scale`` multiplies the Gauss-Newton steps (the
    subset's kappa, see :func:`_iterate`); ``rho`` the contraction per iteration the
    convergence test may assume (1: the classic test, see :func:`_iterate`). Returns
    ``(zncc, iterations, flag)``; the standard uncertainty of (u, v) is left in
    ``work[4][3, 4:6]`` (NaN unless ok), the last two step norms in ``work[4][3, 0:2]``.
    """
    ref_img, ref_gx, ref_gy, ref_coef, ref_invalid = ref
    def_coef, def_invalid = dfm
    half, quadratic, max_iter, tol, min_std, max_shift, border, _, order = opts
    f, gx, gy, _g, w = work
    for q in (0, 1, 4, 5):
        w[3, q] = np.nan
    flag0, fn = _load_reference(
        ref_img, ref_gx, ref_gy, ref_coef, ref_invalid, order, xc, yc, half, min_std, border,
        f, gx, gy, w,
    )  # fmt: skip
    if flag0 != FLAG_OK:
        return np.nan, 0, flag0
    m = 12 if quadratic else 6
    Hinv = np.eye(m)
    jf = np.zeros(m)
    js = np.zeros(m)
    if quadratic:
        if not _quadratic_system(f, gx, gy, half, Hinv, jf, js):
            return np.nan, 0, FLAG_NO_TEXTURE
        return _iterate_quadratic(
            f, gx, gy, fn, Hinv, jf, js, def_coef, def_invalid, order, xc, yc, half, p,
            max_iter, tol, max_shift, border, w, scale, rho,
        )  # fmt: skip
    if not _affine_system(f, gx, gy, half, Hinv, jf, js):
        return np.nan, 0, FLAG_NO_TEXTURE
    return _iterate_affine(
        f, gx, gy, fn, Hinv, jf, js, def_coef, def_invalid, order, xc, yc, half, p, max_iter,
        tol, max_shift, border, w, scale, rho,
    )  # fmt: skip
