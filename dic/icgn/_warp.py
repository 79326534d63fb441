"""IC-GN warp algebra (numba): small linear solves, inverse-compositional updates of affine
and second-order warps, extrapolation of shape parameters to a neighbour.

Shape parameters are always a 12-vector (layout in :mod:`jointwear.dic.icgn._match`); second-order
warps are composed through their 6x6 matrix representation (Gao et al. 2015).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True)
def _solve_spd(A, b, n):
    """Solve A x = b (n x n symmetric positive definite) by Cholesky; None-safe: returns ok flag."""
    L = np.zeros((n, n))
    for i in range(n):
        for j in range(i + 1):
            s = A[i, j]
            for k in range(j):
                s -= L[i, k] * L[j, k]
            if i == j:
                if s <= 0.0:
                    return False
                L[i, i] = math.sqrt(s)
            else:
                L[i, j] = s / L[j, j]
    # forward / backward substitution for each column of b
    m = b.shape[1]
    y = np.empty(n)
    for c in range(m):
        for i in range(n):
            s = b[i, c]
            for k in range(i):
                s -= L[i, k] * y[k]
            y[i] = s / L[i, i]
        for i in range(n - 1, -1, -1):
            s = y[i]
            for k in range(i + 1, n):
                s -= L[k, i] * b[k, c]
            b[i, c] = s / L[i, i]
    return True


@njit(cache=True, inline="always")
def _square_row(M, i, a0, a1, a2, a3, a4, a5):
    """Row ``i`` of :func:`_quad_matrix`: the square of a warp component
    ``a0 + a1 x + a2 y + a3 x^2 + a4 x y + a5 y^2`` in the basis (x^2, x y, y^2, x, y, 1)."""
    M[i, 0] = a1 * a1 + 2 * a0 * a3
    M[i, 1] = 2 * a1 * a2 + 2 * a0 * a4
    M[i, 2] = a2 * a2 + 2 * a0 * a5
    M[i, 3] = 2 * a0 * a1
    M[i, 4] = 2 * a0 * a2
    M[i, 5] = a0 * a0


@njit(cache=True, inline="always")
def _linear_row(M, i, a0, a1, a2, a3, a4, a5):
    """Row ``i`` of :func:`_quad_matrix`: a warp component itself in that basis."""
    M[i, 0] = a3
    M[i, 1] = a4
    M[i, 2] = a5
    M[i, 3] = a1
    M[i, 4] = a2
    M[i, 5] = a0


@njit(cache=True)
def _quad_matrix(p, M):
    a0 = p[0]
    a1 = 1.0 + p[1]
    a2 = p[2]
    a3 = 0.5 * p[3]
    a4 = p[4]
    a5 = 0.5 * p[5]
    b0 = p[6]
    b1 = p[7]
    b2 = 1.0 + p[8]
    b3 = 0.5 * p[9]
    b4 = p[10]
    b5 = 0.5 * p[11]
    _square_row(M, 0, a0, a1, a2, a3, a4, a5)
    M[1, 0] = a1 * b1 + a0 * b3 + a3 * b0
    M[1, 1] = a1 * b2 + a2 * b1 + a0 * b4 + a4 * b0
    M[1, 2] = a2 * b2 + a0 * b5 + a5 * b0
    M[1, 3] = a0 * b1 + a1 * b0
    M[1, 4] = a0 * b2 + a2 * b0
    M[1, 5] = a0 * b0
    _square_row(M, 2, b0, b1, b2, b3, b4, b5)
    _linear_row(M, 3, a0, a1, a2, a3, a4, a5)
    _linear_row(M, 4, b0, b1, b2, b3, b4, b5)
    for j in range(5):
        M[5, j] = 0.0
    M[5, 5] = 1.0


@njit(cache=True)
def _invert(A, out):
    """Gauss-Jordan inverse with partial pivoting of a small square matrix; False if singular."""
    n = A.shape[0]
    M = A.copy()
    for i in range(n):
        for j in range(n):
            out[i, j] = 1.0 if i == j else 0.0
    for col in range(n):
        piv = col
        best = abs(M[col, col])
        for r in range(col + 1, n):
            if abs(M[r, col]) > best:
                best = abs(M[r, col])
                piv = r
        if not best > 1e-300:
            return False
        if piv != col:
            for j in range(n):
                M[col, j], M[piv, j] = M[piv, j], M[col, j]
                out[col, j], out[piv, j] = out[piv, j], out[col, j]
        d = 1.0 / M[col, col]
        for j in range(n):
            M[col, j] *= d
            out[col, j] *= d
        for r in range(n):
            if r != col:
                fct = M[r, col]
                if fct != 0.0:
                    for j in range(n):
                        M[r, j] -= fct * M[col, j]
                        out[r, j] -= fct * out[col, j]
    return True


@njit(cache=True)
def _compose_affine(p, dp):
    """p <- p o dp^-1 for affine warps W = [[1+ux, uy, u], [vx, 1+vy, v]]; False if singular."""
    a11 = 1.0 + dp[1]
    a12 = dp[2]
    a21 = dp[7]
    a22 = 1.0 + dp[8]
    det = a11 * a22 - a12 * a21
    if det == 0.0 or not math.isfinite(det):
        return False
    i11 = a22 / det
    i12 = -a12 / det
    i21 = -a21 / det
    i22 = a11 / det
    it1 = -(i11 * dp[0] + i12 * dp[6])
    it2 = -(i21 * dp[0] + i22 * dp[6])
    w11 = 1.0 + p[1]
    w12 = p[2]
    w21 = p[7]
    w22 = 1.0 + p[8]
    t1 = p[0]
    t2 = p[6]
    p[1] = w11 * i11 + w12 * i21 - 1.0
    p[2] = w11 * i12 + w12 * i22
    p[0] = w11 * it1 + w12 * it2 + t1
    p[7] = w21 * i11 + w22 * i21
    p[8] = w21 * i12 + w22 * i22 - 1.0
    p[6] = w21 * it1 + w22 * it2 + t2
    return True


@njit(cache=True)
def _compose_quadratic(p, dp):
    """p <- p o dp^-1 for second-order warps through their 6x6 matrices (Gao et al. 2015)."""
    Mp = np.empty((6, 6))
    Md = np.empty((6, 6))
    Mi = np.empty((6, 6))
    _quad_matrix(p, Mp)
    _quad_matrix(dp, Md)
    if not _invert(Md, Mi):
        return False
    R = np.zeros((6, 6))
    for i in range(3, 5):
        for j in range(6):
            s = 0.0
            for k in range(6):
                s += Mp[i, k] * Mi[k, j]
            R[i, j] = s
    p[3] = 2.0 * R[3, 0]
    p[4] = R[3, 1]
    p[5] = 2.0 * R[3, 2]
    p[1] = R[3, 3] - 1.0
    p[2] = R[3, 4]
    p[0] = R[3, 5]
    p[9] = 2.0 * R[4, 0]
    p[10] = R[4, 1]
    p[11] = 2.0 * R[4, 2]
    p[7] = R[4, 3]
    p[8] = R[4, 4] - 1.0
    p[6] = R[4, 5]
    return True


@njit(cache=True)
def _compose_inverse(p, dp, quadratic):
    """p <- p o dp^-1 (inverse-compositional update), in place. Returns False if singular."""
    if quadratic:
        return _compose_quadratic(p, dp)
    return _compose_affine(p, dp)


@njit(cache=True)
def _extrapolate(p_from, dx, dy, out):
    """Shape parameters of a neighbour at offset (dx, dy) from a solved point."""
    for i in range(12):
        out[i] = p_from[i]
    for o in (0, 6):
        out[o] = (
            p_from[o]
            + p_from[o + 1] * dx
            + p_from[o + 2] * dy
            + 0.5 * p_from[o + 3] * dx * dx
            + p_from[o + 4] * dx * dy
            + 0.5 * p_from[o + 5] * dy * dy
        )
        out[o + 1] = p_from[o + 1] + p_from[o + 3] * dx + p_from[o + 4] * dy
        out[o + 2] = p_from[o + 2] + p_from[o + 4] * dx + p_from[o + 5] * dy
