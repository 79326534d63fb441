"""Exact (geometric, non-linearised) least-squares circle and cylinder fits.

These minimise the sum of squared *orthogonal* distances from the points to the circle /
cylinder surface -- the ISO definition of the least-squares reference -- rather than the
limaçon approximation of :mod:`jointwear.metrology.form`. They work on Cartesian points, so they
also serve CMM-like data; radius profiles r(theta) are converted first. Solved by
Gauss-Newton / Levenberg-Marquardt (:func:`scipy.optimize.least_squares`) from the algebraic
(Kåsa) circle or the limaçon cylinder, with analytic Jacobians.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import least_squares

from jointwear.errors import BadInputError

__all__ = [
    "CircleFit",
    "CylinderFit",
    "fit_circle",
    "fit_circle_polar",
    "fit_cylinder",
    "fit_cylinder_polar",
]


@dataclass(frozen=True)
class CircleFit:
    """Least-squares circle: centre (x0, y0) [m], radius [m], RMS and residuals [m]."""

    x0: float
    y0: float
    radius: float
    rms: float
    residual: np.ndarray = field(repr=False)

    @property
    def eccentricity(self) -> float:
        """Distance of the centre from the origin [m]."""
        return float(np.hypot(self.x0, self.y0))


@dataclass(frozen=True)
class CylinderFit:
    """Least-squares cylinder: axis through (x0, y0) at z = z_ref with slopes (tx, ty) [1].

    ``radius`` [m]; ``residual`` = distance to the axis minus radius [m]; ``rms`` [m].
    """

    x0: float
    y0: float
    tx: float
    ty: float
    z_ref: float
    radius: float
    rms: float
    residual: np.ndarray = field(repr=False)


def _finite(*arrays: np.ndarray) -> np.ndarray:
    ok = np.ones(np.asarray(arrays[0]).shape, dtype=bool)
    for a in arrays:
        ok &= np.isfinite(a)
    return ok


def fit_circle(x: np.ndarray, y: np.ndarray) -> CircleFit:
    """Geometric least-squares circle through points (x, y) [m].

    Minimises ``sum (hypot(x - x0, y - y0) - R)^2``. NaN points are ignored.
    """
    x = np.asarray(x, dtype=float).ravel()
    y = np.asarray(y, dtype=float).ravel()
    ok = _finite(x, y)
    if ok.sum() < 3:
        raise BadInputError(f"circle fit needs at least 3 points, got {int(ok.sum())}")
    xs, ys = x[ok], y[ok]
    # centre and scale the data for conditioning, exactly: the offsets are kept as double-double
    # (hi, lo) pairs and the scale is a power of two
    cx, cy = xs.mean(), ys.mean()
    u, ul = _two_sum(xs, -cx)
    v, vl = _two_sum(ys, -cy)
    rms = np.sqrt(np.mean(u**2 + v**2))
    scale = float(2.0 ** np.round(np.log2(rms))) if rms > 0 else 1.0
    u, ul, v, vl = u / scale, ul / scale, v / scale, vl / scale
    # Kåsa algebraic fit: u^2 + v^2 + D u + E v + F = 0
    A = np.column_stack([u, v, np.ones_like(u)])
    sol, *_ = np.linalg.lstsq(A, -(u**2 + v**2), rcond=None)
    a0, b0 = -sol[0] / 2, -sol[1] / 2
    r0 = np.sqrt(max(a0**2 + b0**2 - sol[2], 1e-12))

    def fun(p):
        return np.hypot(u - p[0], v - p[1]) - p[2]

    def jac(p):
        d = np.hypot(u - p[0], v - p[1])
        d = np.where(d == 0, 1e-300, d)
        return np.column_stack([-(u - p[0]) / d, -(v - p[1]) / d, -np.ones_like(u)])

    def fun_exact(p):
        return _circle_residual(u, ul, v, vl, p)

    res = least_squares(fun, [a0, b0, r0], jac=jac, method="lm", xtol=1e-15, ftol=1e-15, gtol=1e-15)
    a, b, r = _gauss_newton(res.x, fun_exact, jac)
    x0, y0, radius = cx + a * scale, cy + b * scale, r * scale
    resid = np.full(x.shape, np.nan)
    resid[ok] = np.hypot(xs - x0, ys - y0) - radius
    return CircleFit(
        float(x0), float(y0), float(radius), float(np.sqrt(np.nanmean(resid**2))), resid
    )


def _two_sum(a, b):
    """Error-free sum: a + b = s + e exactly (Knuth)."""
    s = a + b
    bb = s - a
    return s, (a - (s - bb)) + (b - bb)


def _two_prod(a, b):
    """Error-free product: a * b = p + e exactly (Dekker, no FMA needed)."""
    p = a * b

    def split(c):
        t = 134217729.0 * c
        hi = t - (t - c)
        return hi, c - hi

    ah, al = split(a)
    bh, bl = split(b)
    return p, ((ah * bh - p) + ah * bl + al * bh) + al * bl


def _circle_residual(u, ul, v, vl, p):
    """hypot(u - a, v - b) - r accurate to its own size, not to r.

    The plain difference loses all digits below eps * r, which is what stalls the fit on short
    arcs; here (u - a)^2 + (v - b)^2 - r^2 is formed in double-double arithmetic from the exact
    offsets (u + ul, v + vl) and divided by d + r.
    """
    a, b, r = p
    s1, e1 = _two_sum(u, -a)
    s2, e2 = _two_sum(v, -b)
    e1 = e1 + ul
    e2 = e2 + vl
    p1, q1 = _two_prod(s1, s1)
    p2, q2 = _two_prod(s2, s2)
    p3, q3 = _two_prod(np.full_like(u, r), np.full_like(u, r))
    hi, lo1 = _two_sum(p1, p2)
    hi, lo2 = _two_sum(hi, -p3)
    lo = lo1 + lo2 + q1 + q2 - q3 + (2 * s1 * e1 + e1 * e1) + (2 * s2 * e2 + e2 * e2)
    q = hi + lo
    d = np.hypot(s1 + e1, s2 + e2)
    return q / (d + r)


def _gauss_newton(p, fun, jac, max_steps: int = 30) -> np.ndarray:
    """Polish a least-squares solution with full Gauss-Newton steps to machine precision.

    Levenberg-Marquardt stops on its tolerances about 1e-10 relative on short arcs, where the
    problem is ill-conditioned; plain Gauss-Newton steps (solved by SVD-based least squares)
    converge quadratically from there. Stops when a step no longer shrinks the residual norm or
    is below a few ulps of the parameters.
    """
    p = np.asarray(p, dtype=float).copy()
    best = float(np.sum(fun(p) ** 2))
    for _ in range(max_steps):
        step, *_ = np.linalg.lstsq(jac(p), -fun(p), rcond=None)
        trial = p + step
        cost = float(np.sum(fun(trial) ** 2))
        if not np.isfinite(cost) or cost > best * (1 + 1e-12):
            break
        small = np.all(np.abs(step) <= 4 * np.finfo(float).eps * np.maximum(np.abs(p), 1.0))
        p, best = trial, min(best, cost)
        if small:
            break
    return p


def fit_circle_polar(theta_deg: np.ndarray, r: np.ndarray) -> CircleFit:
    """Geometric least-squares circle of a radius profile r(theta) [m], theta [degree]."""
    t = np.radians(np.asarray(theta_deg, dtype=float))
    r = np.asarray(r, dtype=float)
    return fit_circle(r * np.cos(t), r * np.sin(t))


def fit_cylinder(x: np.ndarray, y: np.ndarray, z: np.ndarray) -> CylinderFit:
    """Geometric least-squares cylinder through points (x, y, z) [m] with a near-z axis.

    The axis is the line through (x0 + tx (z - z_ref), y0 + ty (z - z_ref), z); the orthogonal
    distance of each point to it, minus the radius, is minimised in the least-squares sense.
    z_ref is the middle of the z range. NaN points are ignored.
    """
    x = np.asarray(x, dtype=float).ravel()
    y = np.asarray(y, dtype=float).ravel()
    z = np.asarray(z, dtype=float).ravel()
    ok = _finite(x, y, z)
    if ok.sum() < 5:
        raise BadInputError(f"cylinder fit needs at least 5 points, got {int(ok.sum())}")
    xs, ys, zs = x[ok], y[ok], z[ok]
    z_ref = 0.5 * (zs.min() + zs.max())
    if np.ptp(zs) == 0:
        raise BadInputError("cylinder fit needs points at two or more heights")
    zc = zs - z_ref
    cx, cy = xs.mean(), ys.mean()
    scale = np.sqrt(np.mean((xs - cx) ** 2 + (ys - cy) ** 2)) or 1.0
    u, v, w = (xs - cx) / scale, (ys - cy) / scale, zc / scale
    # start: limaçon-style linear fit of the centre line
    rr = np.hypot(u, v)
    t = np.arctan2(v, u)
    G = np.column_stack([np.cos(t), np.sin(t), w * np.cos(t), w * np.sin(t), np.ones_like(u)])
    p0, *_ = np.linalg.lstsq(G, rr, rcond=None)

    def dist(p):
        a, b, tx, ty = p[:4]
        dx = u - (a + tx * w)
        dy = v - (b + ty * w)
        n2 = 1.0 + tx * tx + ty * ty
        # |(q) x d| / |d| with q = (dx, dy, 0) relative to the axis point at the same z, d = (tx, ty, 1)
        cx_ = dy * 1.0 - 0.0 * ty
        cy_ = 0.0 * tx - dx * 1.0
        cz_ = dx * ty - dy * tx
        return np.sqrt((cx_**2 + cy_**2 + cz_**2) / n2)

    def fun(p):
        return dist(p) - p[4]

    res = least_squares(
        fun,
        [p0[0], p0[1], p0[2], p0[3], p0[4]],
        method="lm",
        xtol=1e-15,
        ftol=1e-15,
        gtol=1e-15,
    )
    a, b, tx, ty, r = res.x
    resid = np.full(x.shape, np.nan)
    resid[ok] = (dist(res.x) - r) * scale
    return CylinderFit(
        x0=float(cx + a * scale),
        y0=float(cy + b * scale),
        tx=float(tx),
        ty=float(ty),
        z_ref=float(z_ref),
        radius=float(r * scale),
        rms=float(np.sqrt(np.nanmean(resid**2))),
        residual=resid,
    )


def fit_cylinder_polar(z: np.ndarray, theta_deg: np.ndarray, r: np.ndarray) -> CylinderFit:
    """Geometric least-squares cylinder of radius samples r(z, theta) [m]."""
    t = np.radians(np.asarray(theta_deg, dtype=float))
    r = np.asarray(r, dtype=float)
    return fit_cylinder(r * np.cos(t), r * np.sin(t), np.asarray(z, dtype=float))
