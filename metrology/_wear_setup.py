"""The set-up between a worn scan and its before-scan: rotation, registration, exact centring.

The part is re-mounted between the scans: another angular position (rotated, or registered by
correlating the unworn regions when asked), another eccentricity and tilt. The exact centring
re-centres each scan on its axis (the before-scan's least-squares axis over the whole circle,
the worn scan's = that plus the change of set-up fitted to the difference on the unworn points),
removing the second-order e^2/(4R) terms that a limaçon leaves.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from jointwear.errors import BadInputError
from jointwear.metrology._wear_fit import _basis, _robust_reference


def _periodic_interp(theta_new: np.ndarray, theta: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Linear interpolation of each row of ``values`` (over ``theta`` [degree]) periodically."""
    order = np.argsort(theta)
    th = theta[order]
    v = values[:, order]
    th_ext = np.concatenate([th[-1:] - 360.0, th, th[:1] + 360.0])
    v_ext = np.concatenate([v[:, -1:], v, v[:, :1]], axis=1)
    tn = np.mod(theta_new, 360.0)
    return np.stack([np.interp(tn, th_ext, row) for row in v_ext])


def _rotate(theta_new: np.ndarray, theta: np.ndarray, values: np.ndarray, off: float) -> np.ndarray:
    """Values of a scan rotated by ``off`` [degree] (feature at t moves to t + off), sampled at
    ``theta_new``. Exact Fourier shift when both grids are the same uniform grid (keeps the noise
    variance, so registration is not biased towards half-sample shifts), else periodic linear
    interpolation."""
    n = theta.size
    uniform = n > 2 and np.allclose(np.diff(theta), 360.0 / n, atol=1e-9, rtol=0)
    if uniform and theta_new.size == n and np.allclose(theta_new, theta, atol=1e-9, rtol=0):
        k = np.arange(n // 2 + 1)
        spec = np.fft.rfft(values, axis=1) * np.exp(-2j * np.pi * k * off / 360.0)[None, :]
        return np.fft.irfft(spec, n, axis=1)
    return _periodic_interp(theta_new, np.mod(theta + off, 360.0), values)


def _refine_offset(
    rw: np.ndarray,
    rbz: np.ndarray,
    th: np.ndarray,
    thb: np.ndarray,
    X: np.ndarray,
    sign: float,
    offset: float,
    mask: np.ndarray,
) -> float:
    """Offset [degree] minimising the RMS of the set-up-corrected difference on ``mask``."""
    from scipy.optimize import minimize_scalar

    Xm = X[mask]
    lhs = np.einsum("nj,nk->jk", Xm, Xm)

    def cost(off: float) -> float:
        d = sign * (rw - _rotate(th, thb, rbz, off)).ravel()[mask]
        b = np.linalg.solve(lhs, np.einsum("nj,n->j", Xm, d))
        return float(np.mean((d - np.einsum("nj,j->n", Xm, b)) ** 2))

    step = max(4.0 * 360.0 / max(thb.size, 1), 2.0)
    res = minimize_scalar(
        cost, bounds=(offset - step, offset + step), method="bounded", options={"xatol": 1e-3}
    )
    return float(res.x) if res.fun <= cost(offset) else offset


def register_angle(
    worn: xr.DataArray, before: xr.DataArray, *, exclude: np.ndarray | None = None
) -> float:
    """Angular offset [degree] that best aligns ``before`` with ``worn`` (canonical theta).

    Both are reduced to their residual from a least-squares limaçon cylinder, averaged over z,
    resampled on a common uniform angle grid and circularly cross-correlated (points flagged in
    ``exclude``, e.g. the worn region, are set to zero); the peak is refined by a parabola.
    Returns the offset to add to the before-scan's theta.
    """
    th_w = np.asarray(worn["theta"].values, dtype=float)
    n = max(th_w.size, 64)
    grid = np.arange(n) * 360.0 / n
    prof = []
    for da, ex in ((worn, exclude), (before, None)):
        z = np.asarray(da["z"].values, dtype=float)
        th = np.asarray(da["theta"].values, dtype=float)
        v = np.asarray(da.values, dtype=float)
        X = _basis(z, th, "cylinder")
        vv = v.ravel()
        ok = np.isfinite(vv)
        if ex is not None:
            ok &= ~ex.ravel()
        b, *_ = np.linalg.lstsq(X[ok], vv[ok], rcond=None)
        res = (vv - X @ b).reshape(v.shape)
        if ex is not None:
            res = np.where(ex, np.nan, res)
        res = np.where(np.isfinite(res), res, 0.0)
        prof.append(_periodic_interp(grid, th, res).mean(axis=0))
    a, b = prof
    xc = np.fft.irfft(np.fft.rfft(a) * np.conj(np.fft.rfft(b)), n)
    k = int(np.argmax(xc))
    y0, y1, y2 = xc[(k - 1) % n], xc[k], xc[(k + 1) % n]
    den = y0 - 2 * y1 + y2
    frac = 0.5 * (y0 - y2) / den if den != 0 else 0.0
    off = (k + frac) * 360.0 / n
    return float((off + 180.0) % 360.0 - 180.0)


def _axis(r_abs: np.ndarray, z: np.ndarray, theta_deg: np.ndarray, mask: np.ndarray):
    """Least-squares limaçon cylinder of ``r_abs`` on ``mask``: coefficients (5,) [m]."""
    X = _basis(z, theta_deg, "cylinder")
    m = np.asarray(mask, dtype=bool).ravel() & np.isfinite(r_abs.ravel())
    return np.linalg.lstsq(X[m], r_abs.ravel()[m], rcond=None)[0]


def _recentre(r_abs: np.ndarray, z: np.ndarray, theta_deg: np.ndarray, b: np.ndarray):
    """Exact distance of each point from the axis ``b`` (see :func:`_axis`) [m]."""
    zc = z - 0.5 * (z.min() + z.max())
    zz = zc / max(np.ptp(zc), 1e-12)
    xc = (b[1] + b[3] * zz)[:, None]
    yc = (b[2] + b[4] * zz)[:, None]
    t = np.radians(theta_deg)[None, :]
    return np.sqrt(r_abs**2 + xc**2 + yc**2 - 2.0 * r_abs * (xc * np.cos(t) + yc * np.sin(t)))


def before_on_layers(z: np.ndarray, zb: np.ndarray, thb: np.ndarray, rb: np.ndarray) -> np.ndarray:
    """The before-scan ``rb`` (zb, thb) on the worn scan's layers ``z`` [m] (same layers within
    1 µm, else linear interpolation in z inside the before-scan's range)."""
    if zb.size == z.size and np.allclose(zb, z, atol=1e-6, rtol=0):
        return rb
    if z.min() >= zb.min() - 1e-9 and z.max() <= zb.max() + 1e-9 and zb.size > 1:
        o = np.argsort(zb)
        return np.stack([np.interp(z, zb[o], rb[o, j]) for j in range(thb.size)], axis=1)
    raise BadInputError(
        f"wear_map: the before scan covers z = [{zb.min():.6g}, {zb.max():.6g}] m but the "
        f"worn scan needs [{z.min():.6g}, {z.max():.6g}] m; scan the same layers or crop "
        "the worn scan"
    )


def registered_offset(rw, rbz, z, th, thb, X, Xcyl, sign, offset, fit_args) -> float:
    """Angular offset [degree] of the before-scan found by registration, starting at ``offset``.

    The worn region is first guessed from the worn scan alone and excluded from a circular
    cross-correlation (:func:`register_angle`); the offset is then refined by minimising the
    RMS of the set-up-corrected difference on the unworn points, re-selected each round.
    ``fit_args``: (threshold, unworn mask or None, max_iter, margin_deg).
    """
    threshold, mask_in, max_iter, margin_deg = fit_args
    common = (threshold, mask_in, max_iter, "wear_map", rw.shape, th, margin_deg)
    wz = xr.DataArray(rw, dims=("z", "theta"), coords={"z": z, "theta": th})
    # first guess of the worn region from the worn scan alone
    _, m0, _, _, _ = _robust_reference(sign * rw.ravel(), X, *common)
    excl = ~m0.reshape(rw.shape)
    rb_i = _rotate(th, thb, rbz, offset)
    bz = xr.DataArray(rb_i, dims=("z", "theta"), coords={"z": z, "theta": th})
    offset += register_angle(wz, bz, exclude=excl)
    unw = ~excl.ravel()
    for _ in range(3):
        new_off = _refine_offset(rw, rbz, th, thb, Xcyl, sign, offset, unw)
        rb_i = _rotate(th, thb, rbz, new_off)
        _, unw, _, _, _ = _robust_reference(sign * (rw - rb_i).ravel(), X, *common, symmetric=True)
        done = abs(new_off - offset) < 1e-3
        offset = new_off
        if done:
            break
    return offset


def exact_difference(rw_abs, rb_abs, z, th, mask, sign) -> np.ndarray:
    """The difference of the two scans, each re-centred exactly on its axis (flattened) [m].

    The before-scan's axis comes from the whole circle (its form is orthogonal to the
    limaçon); the worn scan's is that plus the change of set-up fitted to the difference on
    the unworn points ``mask``, where the form cancels. Fitted to the worn scan's unworn arc
    alone, the form shifts the axis by delta, and the second-order term e delta / R (a constant
    and a second harmonic) biases the map by 0.1-0.6 nm. The set-ups' e^2/(4R) terms are not
    orthogonal to the limaçon on an arc: the change of set-up is refitted twice.
    """
    ok = np.isfinite((rw_abs - rb_abs).ravel())
    axis_b = _axis(rb_abs, z, th, ok)
    rb_c = _recentre(rb_abs, z, th, axis_b)
    axis_w = axis_b + _axis(rw_abs - rb_abs, z, th, mask & ok)
    for _ in range(2):
        axis_w = axis_w + _axis(_recentre(rw_abs, z, th, axis_w) - rb_c, z, th, mask & ok)
    return sign * (_recentre(rw_abs, z, th, axis_w) - rb_c).ravel()
