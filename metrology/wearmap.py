"""Wear maps: wear depth over (z, theta) from a worn scan and a reference.

Two ways to get the unworn reference
------------------------------------
* **With a before-wear scan** of the same bearing: both scans are put in the canonical angle
  convention, the before-scan is rotated by the set-up's angular offset (or, only if asked, by
  the offset found by registering the unworn regions) and interpolated onto the worn scan's
  grid. The difference d = r_worn - r_before still contains the change of set-up (the part is
  re-mounted: a different eccentricity and tilt, and for deviation data an unknown radius
  offset), so a limaçon cylinder c + (x0 + tx z) cos(theta) + (y0 + ty z) sin(theta) is fitted to
  d on the *unworn* points and removed. The bore's own form errors cancel in d.
* **Without one**: a reference cylinder (or one circle per layer, ``shape="circle"``) is fitted
  by least squares to the unworn part of the worn scan itself; the original form errors of the
  bore then stay in the map and are counted in its uncertainty.

How the unworn part is chosen: unless given explicitly (``unworn``), it is found iteratively.
Start with all points; fit the reference; estimate the scatter of the residuals of the current
unworn set robustly (1.4826 x median absolute deviation); call unworn the points whose residual
lies within ``threshold`` times that scatter of the median; refit; repeat until the set no longer
changes. Worn points (material removed) sit far on one side and drop out after one or two
rounds. This assumes that a part of the bore is unworn (true for a journal bearing loaded on one
side); if wear covers the whole circumference, pass a before-scan.

Uncertainty: ``wear_depth_u`` [m] combines in quadrature the RMS residual of the unworn points
(noise of both scans, unmodelled form and misalignment: how far an unworn point's "wear" scatters
about 0) with the standard error of the fitted reference at each point.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from jointwear.conventions import (
    CANONICAL,
    angle_convention_of,
    convert_theta,
    theta_coord,
    z_coord,
)
from jointwear.errors import BadInputError
from jointwear.metrology.baseline import (
    FormBasis,
    correlation_length,
    noise_sigma,
    select_harmonics,
)
from jointwear.metrology.form import cylinder_zone
from jointwear.metrology.wear_quantities import derived_quantities, uncertainty_attrs

__all__ = ["wear_map", "worn_volume", "register_angle"]

_SCALE_FLOOR = 1e-11  # [m]


def _radius_var(ds: xr.Dataset | xr.DataArray, what: str) -> tuple[xr.DataArray, str]:
    if isinstance(ds, xr.DataArray):
        name = str(ds.name) if ds.name in ("radius", "radial_deviation") else "radius"
        da = ds
    else:
        for name in ("radius", "radial_deviation"):
            if name in ds:
                da = ds[name]
                break
        else:
            raise BadInputError(
                f"{what}: expected a 'radius' or 'radial_deviation' variable over (z, theta); "
                f"found {', '.join(map(str, ds.data_vars)) or 'no variables'}"
            )
    if set(da.dims) != {"z", "theta"}:
        raise BadInputError(f"{what}: '{name}' must have dims (z, theta), found {da.dims}")
    units = da.attrs.get("units", "m")
    if units != "m":
        raise BadInputError(f"{what}: '{name}' has units {units!r}; expected 'm' (SI)")
    angle_convention_of(da, what=what)
    da = convert_theta(da, CANONICAL).transpose("z", "theta")
    return da, name


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


def _theta_weights(theta: np.ndarray) -> np.ndarray:
    """Periodic trapezoid weights [rad] for angles ``theta`` [degree] (sorted)."""
    th = np.radians(np.sort(theta))
    gaps = np.diff(np.concatenate([th, th[:1] + 2 * np.pi]))
    return 0.5 * (gaps + np.roll(gaps, 1))


def _z_weights(z: np.ndarray) -> np.ndarray:
    """Trapezoid weights [m] over the measured z range (one layer: weight 1 m -> per metre)."""
    if z.size == 1:
        return np.ones(1)
    w = np.zeros_like(z)
    d = np.diff(z)
    w[:-1] += 0.5 * d
    w[1:] += 0.5 * d
    return np.abs(w)


def worn_volume(
    wear_depth: np.ndarray, z: np.ndarray, theta_deg: np.ndarray, radius: float
) -> float:
    """Volume of removed material over the measured band [m^3].

    V = integral of h(z, theta) R dtheta dz (trapezoid in z between the first and last layer,
    periodic trapezoid in theta); R the bore radius [m], h the wear depth [m] (NaN ignored).
    """
    h = np.nan_to_num(np.asarray(wear_depth, dtype=float))
    w = _z_weights(np.asarray(z, dtype=float))[:, None] * _theta_weights(theta_deg)[None, :]
    return float(radius * np.sum(w * h))


def _basis(z: np.ndarray, theta_deg: np.ndarray, shape: str):
    nz, nt = z.size, theta_deg.size
    t = np.radians(theta_deg)
    c = np.broadcast_to(np.cos(t)[None, :], (nz, nt)).ravel()
    s = np.broadcast_to(np.sin(t)[None, :], (nz, nt)).ravel()
    if shape == "cylinder":
        zc = z - 0.5 * (z.min() + z.max())
        span = max(np.ptp(zc), 1e-12)
        zz = np.broadcast_to((zc / span)[:, None], (nz, nt)).ravel()
        return np.column_stack([np.ones(nz * nt), c, s, zz * c, zz * s])
    return _LayerBasis(nz, np.stack([np.ones(nt), np.cos(t), np.sin(t)]))


class _LayerBasis:
    """One circle (1, cos, sin) per layer: a block-diagonal basis kept as its shared block."""

    def __init__(self, nz: int, block: np.ndarray):
        self.nz = nz
        self.block = block  # (3, nt)
        self.shape = (nz * block.shape[1], 3 * nz)


def _lsq(X, d: np.ndarray, mask: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Least squares of d on the masked rows: (coefficients, fitted values, normal matrix)."""
    if isinstance(X, FormBasis):
        return X.lsq(d, mask)
    if isinstance(X, _LayerBasis):
        B = X.block
        m = mask.reshape(X.nz, -1).astype(float)
        dd = np.where(mask, d, 0.0).reshape(X.nz, -1)
        G = np.einsum("ln,jn,kn->ljk", m, B, B)
        rhs = np.einsum("ln,jn->lj", dd * m, B)
        b = np.linalg.solve(G, rhs[..., None])[..., 0]
        return b, np.einsum("lj,jn->ln", b, B).ravel(), G
    Xw = X * mask[:, None]  # weights instead of fancy indexing: no copies of rows
    G = np.einsum("nj,nk->jk", Xw, X)
    b = np.linalg.solve(G, np.einsum("nj,n->j", Xw, np.where(mask, d, 0.0)))
    return b, np.einsum("nj,j->n", X, b), G


def _fit_variance(X, G: np.ndarray, s2: float) -> np.ndarray:
    """Variance of the fitted reference at every point [m^2]."""
    cov = np.linalg.inv(G) * s2
    if isinstance(X, FormBasis):
        return X.fit_variance(cov)
    if isinstance(X, _LayerBasis):
        return np.einsum("jn,ljk,kn->ln", X.block, cov, X.block).ravel()
    return np.einsum("nj,jk,nk->n", X, cov, X)


def _smooth_theta(v: np.ndarray, win: int) -> np.ndarray:
    """Periodic moving average of each row over ``win`` samples (NaN ignored)."""
    if win <= 1:
        return v
    ok = np.isfinite(v)
    x = np.where(ok, v, 0.0)
    h = win // 2
    n = v.shape[1]
    h = min(h, n - 1)
    ext = np.concatenate([x[:, n - h :], x, x[:, :h]], axis=1) if h else x
    cnt = np.concatenate([ok[:, n - h :], ok, ok[:, :h]], axis=1) if h else ok
    cs = np.concatenate([np.zeros((v.shape[0], 1)), np.cumsum(ext, axis=1)], axis=1)
    cc = np.concatenate([np.zeros((v.shape[0], 1)), np.cumsum(cnt, axis=1)], axis=1)
    w = 2 * h + 1
    num = cs[:, w:] - cs[:, :-w]
    den = cc[:, w:] - cc[:, :-w]
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(den > 0, num / np.maximum(den, 1), np.nan)


def _robust_reference(
    d: np.ndarray,
    X: np.ndarray,
    threshold: float,
    unworn: np.ndarray | None,
    max_iter: int,
    what: str,
    shape: tuple[int, int] | None = None,
    theta_deg: np.ndarray | None = None,
    margin_deg: float = 5.0,
    smooth_deg: float = 2.0,
    start: np.ndarray | None = None,
    one_sided: bool = True,
    symmetric: bool = False,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, float, int]:
    """Fit X b ~ d on the unworn points (found iteratively unless given).

    A point is unworn when its residual is within ``threshold`` robust standard deviations of
    the median, and it is not within ``margin_deg`` of a worn region (where the residual
    smoothed over ``smooth_deg`` exceeds ``threshold`` robust deviations of the smoothed
    residual) -- so the faint tails of a worn patch do not bias the reference.

    ``one_sided``: wear only removes material, so only a high residual is taken as wear (low
    ones down to twice the threshold are kept); without ``unworn`` and for a limaçon basis the
    first unworn set comes from a lower-quantile fit, which a broad groove hardly pulls.
    ``symmetric`` (for the difference to a before-scan, whose unworn points hold noise only; the
    lower-quantile start is kept): points and smoothed regions are rejected symmetrically about
    the noise centre. A one-sided cut drops only the high tail of the noise, so the points kept
    read low on average and every depth, hence the volume, reads high (0.0044 sigma per point
    at 3 sigma, plus the high smoothed windows).
    """
    finite = np.isfinite(d)
    mask = finite.copy() if unworn is None else (finite & unworn)
    if start is None and unworn is None and one_sided and not isinstance(X, FormBasis):
        start = _lower_quantile_start(X, d, finite, threshold)
    if start is not None and unworn is None:
        mask = finite & start
    n_iter = 0
    win = 1
    if shape is not None and theta_deg is not None:
        win = max(1, int(round(smooth_deg * shape[1] / 360.0)))
    for n_iter in range(1, max_iter + 1):  # noqa: B007
        if mask.sum() < X.shape[1] + 2:
            raise BadInputError(
                f"{what}: only {int(mask.sum())} unworn points left to fit the reference; "
                "pass a before-wear scan (before=..., CLI --before BEFORE.nc), a larger threshold, "
                "or an explicit unworn mask"
            )
        try:
            b, fitted, G = _lsq(X, d, mask)
        except np.linalg.LinAlgError:
            raise BadInputError(
                f"{what}: the unworn points do not determine the reference (they cover too "
                "little of the circumference), so wear cannot be separated from form; pass a "
                "before-wear scan (before=..., CLI --before BEFORE.nc) or an explicit unworn mask"
            ) from None
        resid = d - fitted
        if unworn is not None:
            break
        rm = resid[mask]
        med = np.median(rm)
        # floor: 10 pm, far below any instrument's resolution (noise-free synthetic data)
        scale = max(1.4826 * np.median(np.abs(rm - med)), _SCALE_FLOOR)
        if one_sided and not symmetric:  # only a high residual can be wear
            new = finite & (resid - med <= threshold * scale)
            new &= resid - med >= -2.0 * threshold * scale  # dents and spikes
        else:
            new = finite & (np.abs(resid - med) <= threshold * scale)
        if shape is not None and theta_deg is not None:
            sm = _smooth_theta(resid.reshape(shape), win)
            smm = sm.ravel()[mask]
            smed = np.nanmedian(smm)
            sscale = max(1.4826 * np.nanmedian(np.abs(smm - smed)), _SCALE_FLOOR)
            high = (sm - smed) if one_sided and not symmetric else np.abs(sm - smed)
            region = ~(high > threshold * sscale)
            region = _dilate(region, theta_deg, margin_deg)
            new &= region.ravel()
        changed = int(np.count_nonzero(new != mask))
        mask = new
        if changed <= 1e-4 * mask.size:
            break
    b, fitted, G = _lsq(X, d, mask)
    resid = d - fitted
    s2 = float(np.mean(resid[mask] ** 2) * mask.sum() / max(mask.sum() - X.shape[1], 1))
    var_fit = _fit_variance(X, G, s2)
    return resid, mask, var_fit, s2, n_iter


def _exclude_tails(
    d: np.ndarray,
    X,
    mask: np.ndarray,
    shape: tuple[int, int],
    theta_deg: np.ndarray,
    z_crit: float,
    step_deg: float = 2.0,
    min_fraction: float = 0.25,
) -> tuple[np.ndarray, str]:
    """Drop from the unworn set the bands next to the worn region that hold wear (a test).

    The faint tails of a worn region (wear below the point-wise threshold) sit among the points
    taken as unworn and pull the reference up (a limaçon fitted on an arc extrapolates that
    pull to the worn side: 1-2 % of a wide groove's volume). The noise of the unworn points is
    centred on the reference (symmetric rejection), so the mean residual of a band of unworn
    points next to the worn region is an unbiased estimate of the wear there, with standard
    error s sqrt(tau / n) (s the residual RMS, tau its correlation length, n the band's
    points). Band after band (``step_deg`` wide, on every layer), a band whose mean exceeds
    ``z_crit`` standard errors holds wear: it leaves the unworn set and the reference is
    refitted; the first band consistent with no wear ends the growth (or keeping at least
    ``min_fraction`` of the points). What stays below the test is covered by the "unworn
    selection" term of the uncertainty (the change when a further 10 degree is left out).
    Returns (mask, description).
    """
    nz, nt = shape
    win = max(1, int(round(step_deg * nt / 360.0)))
    # the worn region: most of a step-wide window not unworn (not each isolated noise outlier)
    region = _smooth_theta((~mask).reshape(shape).astype(float), win) > 0.5
    if not region.any() or region.all():
        return mask, "none found (no worn region)"
    n_bands, note = 0, ""
    while True:
        grown = ~_dilate(~region, theta_deg, step_deg)
        band = (grown & ~region).ravel() & mask
        new = mask & ~band
        n = int(band.sum())
        if n == 0 or new.sum() < min_fraction * mask.size:
            break
        # the band's residual from the reference fitted without it (its own wear cannot pull
        # the reference it is tested against)
        _, fitted, G = _lsq(X, d, new)
        r = d - fitted
        s2 = max(float(np.mean(r[new] ** 2)), _SCALE_FLOOR**2)
        tau = correlation_length(r.reshape(shape), new.reshape(shape))
        var_pred = float(np.mean(_fit_variance(X, G, s2)[band]))  # >= var of the band's mean
        tbar, se = float(np.mean(r[band])), float(np.sqrt(s2 * tau / n + var_pred))
        note = f"last band tested: mean {tbar * 1e9:.3g} nm, standard error {se * 1e9:.2g} nm"
        if tbar <= z_crit * se:
            break
        mask, region, n_bands = new, grown, n_bands + 1
    return mask, (
        f"{n_bands} band(s) of {step_deg:g} degree next to the worn region held wear above "
        f"{z_crit:g} standard errors and were left out of the unworn set ({note})"
    )


def _dilate(unworn: np.ndarray, theta_deg: np.ndarray, margin_deg: float) -> np.ndarray:
    """Shrink the unworn mask: drop points within ``margin_deg`` (in theta) of a worn point."""
    if margin_deg <= 0:
        return unworn
    worn = ~unworn
    th = np.asarray(theta_deg, dtype=float)
    step = 360.0 / th.size if th.size else 360.0
    k = int(np.ceil(margin_deg / step))
    if k <= 0 or not worn.any():
        return unworn
    k = min(k, th.size)
    # running maximum over a periodic window of 2k+1 samples via cumulative sums
    ext = np.concatenate([worn[:, -k:], worn, worn[:, :k]], axis=1).astype(np.int32)
    c = np.concatenate([np.zeros((worn.shape[0], 1), np.int32), np.cumsum(ext, axis=1)], axis=1)
    win = c[:, 2 * k + 1 :] - c[:, : -(2 * k + 1)]
    return unworn & (win == 0)


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


def wear_map(
    worn: xr.Dataset | xr.DataArray,
    before: xr.Dataset | xr.DataArray | None = None,
    *,
    angle_offset_deg: float = 0.0,
    register: bool = False,
    shape: str = "auto",
    threshold: float = 3.0,
    unworn: np.ndarray | xr.DataArray | None = None,
    surface: str = "bore",
    radius: float | None = None,
    margin_deg: float | None = None,
    exact_centring: bool = True,
    max_iter: int = 30,
    harmonics: int = 4,
    axial_degree: int = 2,
) -> xr.Dataset:
    """Wear depth over (z, theta) from a worn scan and a before-scan or a fitted reference.

    Parameters
    ----------
    worn : Dataset or DataArray
        Worn scan: ``radius`` or ``radial_deviation`` [m] over (``z`` [m], ``theta`` [degree]);
        theta must state its angle convention.
    before : Dataset or DataArray, optional
        Scan of the same bearing before wear, same layers (z values within 1 µm or inside the
        worn scan's z range for interpolation). Without it the reference is fitted to the
        unworn part of the worn scan (see the module docstring).
    angle_offset_deg : float
        Set-up rotation [degree, canonical convention]: a feature at theta in the before-scan is
        at theta + offset in the worn scan.
    register : bool
        Estimate the offset by correlating the unworn regions instead (added to
        ``angle_offset_deg``). Only when asked.
    shape : {"auto", "cylinder", "circle", "form"}
        Reference fitted to the unworn points: a limaçon cylinder (centre and tilt), one circle
        per layer, or the form model of :mod:`~jointwear.metrology.baseline` (a centre per layer,
        taper/barrel and lobing smooth in z). ``auto``: cylinder with a before-scan (the form
        cancels in the difference), form without one.
    harmonics, axial_degree : int
        Highest lobing harmonic and degree in z of the form model (``shape="form"``).
    threshold : float
        Unworn points lie within ``threshold`` robust standard deviations of the reference.
    unworn : bool array (z, theta), optional
        Explicit unworn mask (canonical theta order of the worn scan); skips the iteration.
    surface : {"bore", "shaft"}
        A bore's radius grows with wear, a shaft's shrinks; wear depth is positive for material
        removed in both.
    radius : float, optional
        Bore radius for the worn volume [m]; by default the mean worn radius (``radius`` data) or
        the ``nominal_radius`` attribute (deviation data).
    margin_deg : float, optional
        Points within this angle [degree] of a worn region are not used as unworn reference
        (default 5, or 15 for the form model, where faint wear tails would bias the form).
    exact_centring : bool
        Re-centre each scan exactly on its own axis before differencing (needs the bore radius:
        ``radius`` data, the ``nominal_radius`` attribute or ``radius=``); removes the
        set-up's second-order term e^2/(4R) that the limaçon leaves.
    max_iter : int
        Maximum rounds of the unworn-region iteration.

    Returns
    -------
    Dataset
        ``wear_depth`` and ``wear_depth_u`` [m] over (z, theta) in the canonical convention,
        ``unworn`` (flag: 1 if the point was used as unworn reference), scalars
        ``worn_volume`` and ``worn_volume_u`` [m^3], ``cylindricity_before`` and
        ``cylindricity_after`` [m] (MZ), ``angle_offset`` [degree]; method in attrs.
    """
    if shape not in ("auto", "cylinder", "circle", "form"):
        raise BadInputError(
            f"wear_map: shape must be 'auto', 'cylinder', 'circle' or 'form', got {shape!r}"
        )
    if shape == "auto":
        shape = "cylinder" if before is not None else "form"
    if margin_deg is None:  # without a before-scan faint wear tails would bias the form fit
        margin_deg = 15.0 if shape == "form" else 5.0
    if surface not in ("bore", "shaft"):
        raise BadInputError(f"wear_map: surface must be 'bore' or 'shaft', got {surface!r}")
    if not threshold > 0:
        raise BadInputError(f"wear_map: threshold must be > 0, got {threshold!r}")
    w, wname = _radius_var(worn, "worn scan")
    z = np.asarray(w["z"].values, dtype=float)
    th = np.asarray(w["theta"].values, dtype=float)
    rw = np.asarray(w.values, dtype=float)
    sign = 1.0 if surface == "bore" else -1.0
    if shape == "form":
        X = FormBasis(z, th, harmonics, axial_degree)
    else:
        X = _basis(z, th, shape)
    Xcyl = X if shape == "cylinder" else _basis(z, th, "cylinder")
    mask_in = None
    if unworn is not None:
        mask_in = np.asarray(unworn, dtype=bool)
        if mask_in.shape != rw.shape:
            raise BadInputError(
                f"wear_map: unworn mask has shape {mask_in.shape}, expected {rw.shape} (z, theta)"
            )
        mask_in = mask_in.ravel()
    offset = float(angle_offset_deg)
    if before is not None:
        b, bname = _radius_var(before, "before scan")
        if (bname == "radius") != (wname == "radius"):
            pass  # a constant offset is fitted anyway
        zb = np.asarray(b["z"].values, dtype=float)
        thb = np.asarray(b["theta"].values, dtype=float)
        rb = np.asarray(b.values, dtype=float)
        if zb.size == z.size and np.allclose(zb, z, atol=1e-6, rtol=0):
            rbz = rb
        elif z.min() >= zb.min() - 1e-9 and z.max() <= zb.max() + 1e-9 and zb.size > 1:
            o = np.argsort(zb)
            rbz = np.stack([np.interp(z, zb[o], rb[o, j]) for j in range(thb.size)], axis=1)
        else:
            raise BadInputError(
                f"wear_map: the before scan covers z = [{zb.min():.6g}, {zb.max():.6g}] m but the "
                f"worn scan needs [{z.min():.6g}, {z.max():.6g}] m; scan the same layers or crop "
                "the worn scan"
            )
        if register:
            wz = xr.DataArray(rw, dims=("z", "theta"), coords={"z": z, "theta": th})
            # first guess of the worn region from the worn scan alone
            _, m0, _, _, _ = _robust_reference(
                sign * rw.ravel(),
                X,
                threshold,
                mask_in,
                max_iter,
                "wear_map",
                rw.shape,
                th,
                margin_deg,
            )
            excl = ~m0.reshape(rw.shape)
            rb_i = _rotate(th, thb, rbz, offset)
            bz = xr.DataArray(rb_i, dims=("z", "theta"), coords={"z": z, "theta": th})
            offset += register_angle(wz, bz, exclude=excl)
            unw = ~excl.ravel()
            for _ in range(3):
                new_off = _refine_offset(rw, rbz, th, thb, Xcyl, sign, offset, unw)
                rb_i = _rotate(th, thb, rbz, new_off)
                _, unw, _, _, _ = _robust_reference(
                    sign * (rw - rb_i).ravel(),
                    X,
                    threshold,
                    mask_in,
                    max_iter,
                    "wear_map",
                    rw.shape,
                    th,
                    margin_deg,
                    symmetric=True,
                )
                done = abs(new_off - offset) < 1e-3
                offset = new_off
                if done:
                    break
        rb_i = _rotate(th, thb, rbz, offset)
        d = sign * (rw - rb_i).ravel()
        method = (
            "difference to the before-wear scan (rotated by angle_offset and interpolated onto "
            "the worn grid) minus a limaçon "
            + ("cylinder" if shape == "cylinder" else "circle per layer")
            + " fitted to the unworn points (change of set-up)"
        )
    else:
        if register:
            raise BadInputError("wear_map: register=True needs a before scan")
        d = sign * rw.ravel()
        rbz = None
        model = {
            "cylinder": "a limaçon cylinder",
            "circle": "a limaçon circle per layer",
            "form": f"the form model (a centre per layer; radius and lobing 2..{getattr(X, 'harmonics', 0)} UPR "
            f"as polynomials of degree {getattr(X, 'deg', 0)} in z)",
        }[shape]
        method = (
            f"residual from {model} fitted by least squares to the unworn part of the worn "
            "scan (no before-wear scan)"
        )
    X, fit, alt = _reference(
        d, X, shape, z, th, harmonics, threshold, mask_in, max_iter, margin_deg, rbz is not None
    )
    resid, mask, var_fit, s2, n_iter = fit
    # exact centring: the limaçon leaves each scan's e^2/(4R) second harmonic, which differs
    # between set-ups; with the bore radius known, re-centre each scan exactly on its own axis
    # (fitted to the unworn points) and redo the fit
    r0_w = 0.0 if wname == "radius" else (radius or _attr_radius(worn, w))
    centring = "limaçon only (bore radius unknown: pass radius= for exact centring)"
    if not exact_centring:
        centring = "limaçon only (exact_centring=False)"
    elif isinstance(X, FormBasis):
        centring = (
            "form model: its second harmonic, quadratic in z, holds the limaçon's e^2/(4R) term"
        )
    elif r0_w is not None and not isinstance(X, FormBasis):
        if rbz is not None:
            r0_b = 0.0 if bname == "radius" else (radius or _attr_radius(before, b) or r0_w)
            rb_abs = _rotate(th, thb, rbz, offset) + r0_b
            ok = np.isfinite(d)
            # the before scan's axis from the whole circle (its form is orthogonal to the
            # limaçon); the worn scan's = that plus the change of set-up fitted to the difference
            # on the unworn points, where the form cancels. Fitted to the worn scan's unworn arc
            # alone, the form shifts the axis by delta, and the second-order term e delta / R
            # (a constant and a second harmonic) biases the map by 0.1-0.6 nm
            axis_b = _axis(rb_abs, z, th, ok)
            rb_c = _recentre(rb_abs, z, th, axis_b)
            axis_w = axis_b + _axis(rw + r0_w - rb_abs, z, th, mask & ok)
            for _ in range(2):  # the set-ups' e^2/(4R) terms, not orthogonal on an arc: iterate
                diff = _recentre(rw + r0_w, z, th, axis_w) - rb_c
                axis_w = axis_w + _axis(diff, z, th, mask & ok)
            d = sign * (_recentre(rw + r0_w, z, th, axis_w) - rb_c).ravel()
        else:
            rw_c = _recentre(rw + r0_w, z, th, _axis(rw + r0_w, z, th, mask))
            d = sign * (rw_c - r0_w).ravel()
        X, fit, alt = _reference(
            d, X, shape, z, th, harmonics, threshold, mask_in, max_iter, margin_deg, rbz is not None
        )
        resid, mask, var_fit, s2, n_iter = fit
        centring = (
            "exact: the before scan re-centred on its least-squares axis (all points), the "
            "worn scan on that axis plus the change of set-up (difference on the unworn "
            "points)"
            if rbz is not None
            else "exact: the scan re-centred on its least-squares axis (unworn points)"
        ) + ", then the limaçon reference fitted to the unworn points"
    tails = (
        "not assessed (explicit unworn mask)"
        if mask_in is not None
        else "not tested (no before-scan: the unworn form is modelled; a margin of "
        f"{margin_deg:g} degree around the worn region is left out instead)"
    )
    if mask_in is None and rbz is not None:
        mask, tails = _exclude_tails(d, X, mask, rw.shape, th, 2.0, 5.0)
        resid, mask, var_fit, s2, _ = _robust_reference(
            d, X, threshold, mask, 1, "wear_map", rw.shape, th, margin_deg
        )
    wear = resid.reshape(rw.shape)
    u = np.sqrt(s2 + var_fit).reshape(rw.shape)
    mask2 = mask.reshape(rw.shape)
    radius = _volume_radius(radius, wname, rw, worn, w)
    wts = _z_weights(z)[:, None] * _theta_weights(th)[None, :] * radius
    _, _, G = _lsq(X, d, mask)
    cov = np.linalg.inv(G) * s2
    if cov.ndim == 3:  # one block per layer (circle per layer)
        from scipy.linalg import block_diag

        cov = block_diag(*cov)
    tau = correlation_length(wear, mask2)
    q = derived_quantities(
        wear, var_fit.reshape(rw.shape), s2, tau, _design_sum(X, wts), cov, wts, z, th
    )
    if alt is not None:
        other = alt[0].reshape(rw.shape)
        _model_order_term(q, other, wts, z, th, "form-model order")
        u = np.hypot(u, wear - other)  # each depth's dependence on the model order
    if rbz is not None and mask_in is None and not mask2.all():
        # faint wear tails next to the worn region bias the reference: refit without the
        # points within a further 10 degree of it and count the change. The worn region: where
        # most of a 2-degree window is not unworn (not every isolated noise outlier)
        win = max(1, int(round(2.0 * th.size / 360.0)))
        region = _smooth_theta((~mask2).astype(float), win) <= 0.5
        narrower = (mask2 & _dilate(region, th, 10.0)).ravel()
        if narrower.sum() > 0.1 * narrower.size:
            try:
                sel, *_ = _robust_reference(
                    d, X, threshold, narrower, 1, "wear_map", rw.shape, th, margin_deg
                )
                other = sel.reshape(rw.shape)
                _model_order_term(q, other, wts, z, th, "unworn selection")
                u = np.hypot(u, wear - other)
            except BadInputError:
                pass
    noise = noise_sigma(wear)  # successive differences of the residual: the probe noise
    if rbz is not None and np.sqrt(s2) > max(1.5 * noise, 1e-9) and tau > 20.0:
        raise BadInputError(
            f"wear_map: the difference of the scans leaves {np.sqrt(s2) * 1e9:.3g} nm RMS of "
            f"smooth structure (correlation length {tau:.0f} samples) on the points taken as "
            f"unworn, against {noise * 1e9:.3g} nm of noise: wear spread around most of the "
            "bore (or a change of form between the scans) cannot be separated from the change "
            "of set-up; pass an explicit unworn mask (unworn=...) of points known to be unworn"
        )
    if rbz is None:
        lobing = _lobing_rms((d - resid).reshape(rw.shape)) if isinstance(X, FormBasis) else 0.0
        _separable(q, s2, noise, mask2, threshold, lobing)
    cyl_after, cyl_before, cyl_before_note = _cylindricities(
        rw, rbz, z, th, thb if rbz is not None else th, mask2
    )
    zc = z_coord(z)
    tc = theta_coord(th, CANONICAL)
    out = xr.Dataset(
        {
            "wear_depth": (
                ("z", "theta"),
                wear,
                {
                    "units": "m",
                    "long_name": "wear depth of the bearing surface (positive = material removed)",
                    "ancillary_variables": "wear_depth_u",
                },
            ),
            "wear_depth_u": (
                ("z", "theta"),
                u,
                {
                    "units": "m",
                    "long_name": "standard uncertainty of wear_depth",
                    **uncertainty_attrs(
                        "scatter of the unworn points about the reference (instrument noise, "
                        "unmodelled form and set-up) and the fitted reference's standard error"
                    ),
                },
            ),
            "unworn": (
                ("z", "theta"),
                mask2.astype(np.int8),
                {
                    "units": "1",
                    "long_name": "point used as unworn reference",
                    "flag_values": np.array([0, 1], dtype=np.int8),
                    "flag_meanings": "worn_or_outlier unworn_reference",
                },
            ),
            **_scalars(q, cyl_before, cyl_after, cyl_before_note, noise),
            "angle_offset": (
                (),
                offset,
                {
                    "units": "degree",
                    "long_name": "rotation applied to the before-wear scan (canonical theta)",
                },
            ),
        },
        coords={"z": zc, "theta": tc},
        attrs={
            "title": "wear map",
            "wear_reference": method,
            "unworn_selection": (
                "explicit mask"
                if mask_in is not None
                else f"iterative: |residual - median| <= {threshold} x 1.4826 MAD ({n_iter} rounds)"
            ),
            "n_unworn_points": int(mask.sum()),
            "reference_rms_residual": float(np.sqrt(s2)),
            "residual_correlation_length_samples": float(tau),
            "instrument_noise_estimate": float(noise),
            "volume_radius": float(radius),
            "surface": surface,
            "registered": bool(register),
            "centring": centring,
            "faint_wear_tails": tails,
        },
    )
    origins = {str(getattr(o, "attrs", {}).get("data_origin", "")) for o in (worn, before)}
    origins.discard("")
    if origins:  # keep the inputs' origin: one synthetic scan makes the map synthetic
        out.attrs["data_origin"] = "synthetic" if "synthetic" in origins else sorted(origins)[0]
    return out


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


def _attr_radius(orig: xr.Dataset | xr.DataArray, da: xr.DataArray) -> float | None:
    for src in (da.attrs, getattr(orig, "attrs", {})):
        for key in ("nominal_radius", "radius"):
            if key in src:
                try:
                    return float(src[key])
                except (TypeError, ValueError):
                    pass
    return None


def _volume_radius(radius, wname, rw, worn, w) -> float:
    """Bore radius for the volume [m]: given, the mean radius, or the nominal radius."""
    if radius is None:
        radius = float(np.nanmean(rw)) if wname == "radius" else _attr_radius(worn, w)
    if radius is None or not np.isfinite(radius) or radius <= 0:
        raise BadInputError(
            "wear_map: the worn scan holds radial deviations without a 'nominal_radius' "
            "attribute; pass radius=<bore radius in m> for the worn volume"
        )
    return float(radius)


def _design_sum(X, w: np.ndarray) -> np.ndarray:
    """sum_i w_i X_i over all points (p,): the volume's sensitivity to the coefficients."""
    if isinstance(X, FormBasis):
        return X.weighted_sum(w)
    if isinstance(X, _LayerBasis):
        return (w @ X.block.T).ravel()
    return w.ravel() @ X


def _lobing_rms(surface: np.ndarray) -> float:
    """RMS of the harmonics 2 and up of a fitted surface (nz, nt) [m]."""
    spec = np.fft.rfft(surface, axis=1) / surface.shape[1]
    return float(np.sqrt(np.mean(2.0 * np.sum(np.abs(spec[:, 2:]) ** 2, axis=1))))


def _separable(
    q: dict, s2: float, noise: float, unworn: np.ndarray, threshold: float, lobing: float
) -> None:
    """Refuse a map without a before-scan where wear cannot be told from form."""
    frac = float(unworn.mean())
    fix = (
        "pass the scan of the bore before wear (before=..., CLI --before BEFORE.nc), or an "
        "explicit unworn mask"
    )
    if frac < 0.25:
        raise BadInputError(
            f"wear_map: only {frac:.0%} of the points look unworn: too little of the bore is "
            f"left to fit its unworn form, so wear cannot be separated from form; {fix}"
        )
    depth, u_depth, _ = q["max_wear_depth"]
    s = float(np.sqrt(s2))
    if depth < 5.0 * u_depth and np.isfinite(noise) and lobing > 5.0 * noise:
        raise BadInputError(
            f"wear_map: without a before-wear scan no significant wear stands out (max "
            f"{depth * 1e6:.3g} ± {u_depth * 1e6:.2g} µm), but the bore's "
            f"lobing ({lobing * 1e6:.3g} µm RMS, instrument noise {noise * 1e6:.3g} µm) could "
            "hold wear as broad as its lobes: whether the bore is unworn or evenly worn "
            f"cannot be separated from its form; {fix}"
        )
    if u_depth > 0.3 * depth and not (np.isfinite(noise) and u_depth <= 5.0 * noise):
        raise BadInputError(
            f"wear_map: without a before-wear scan the wear found (max {depth * 1e6:.3g} µm) "
            f"depends on the form model (standard uncertainty {u_depth * 1e6:.2g} µm, including "
            "the change at the neighbouring lobing order): the worn region is as wide as the "
            f"bore's lobes, so wear cannot be separated from form; {fix}"
        )
    if np.isfinite(noise) and s > 3.0 * noise and depth < 5.0 * s:
        raise BadInputError(
            f"wear_map: without a before-wear scan the form model leaves {s * 1e6:.3g} µm RMS "
            f"on the unworn points (instrument noise {noise * 1e6:.3g} µm): unmodelled form of "
            f"the size of the wear found (max {depth * 1e6:.3g} ± {u_depth * 1e6:.2g} µm), so "
            f"wear cannot be separated from form; {fix}"
        )


def _cylindricities(rw, rbz, z, th, thb, unworn):
    """(MZ cylindricity of the worn scan, of the before-scan or the unworn points, note)."""
    if z.size < 2:
        return float("nan"), float("nan"), "not assessed: one layer"

    def zone(v, t):
        return cylinder_zone(
            np.broadcast_to(z[:, None], v.shape), np.broadcast_to(t, v.shape), v
        ).total

    if rbz is not None:
        return zone(rw, th), zone(rbz, thb), "MZ cylindricity of the before-wear scan"
    return (
        zone(rw, th),
        zone(np.where(unworn, rw, np.nan), th),
        "MZ cylindricity of the unworn points of the worn scan (estimate of the cylindricity "
        "before wear; no before-wear scan)",
    )


_LONG = {
    "worn_volume": ("m3", "volume of material removed over the measured band"),
    "max_wear_depth": ("m", "largest wear depth (map averaged over about 1 degree)"),
    "wear_cylindricity": ("m", "MZ cylindricity of the wear map"),
}


def _scalars(q: dict, cyl_before, cyl_after, note: str, noise: float) -> dict:
    """The map's scalar quantities with their ``_u`` variables."""
    out = {}
    for name, (v, u, comment) in q.items():
        unit, long_name = _LONG[name]
        out[name] = (
            (),
            v,
            {"units": unit, "long_name": long_name, "ancillary_variables": f"{name}_u"},
        )
        out[f"{name}_u"] = (
            (),
            u,
            {
                "units": unit,
                "long_name": f"standard uncertainty of {name}",
                **uncertainty_attrs(comment),
            },
        )
    u_zone = float(np.sqrt(2.0) * noise) if np.isfinite(cyl_after) else float("nan")
    zone_comment = (
        "instrument noise (from successive differences) at the zone's two extreme points; the "
        "upward bias of a zone by noise is not corrected"
    )
    for name, v, long_name in (
        ("cylindricity_before", cyl_before, note),
        ("cylindricity_after", cyl_after, "MZ cylindricity of the worn scan"),
    ):
        out[name] = (
            (),
            v,
            {"units": "m", "long_name": long_name, "ancillary_variables": f"{name}_u"},
        )
        out[f"{name}_u"] = (
            (),
            u_zone,
            {
                "units": "m",
                "long_name": f"standard uncertainty of {name}",
                **uncertainty_attrs(zone_comment),
            },
        )
    return out


def _reference(
    d, X, shape, z, th, harmonics, threshold, mask_in, max_iter, margin_deg, difference=False
):
    """(basis used, robust fit, fit at the neighbouring lobing order or None).

    ``difference``: ``d`` is the difference to a before-scan, whose unworn points hold noise
    only: the iteration rejects them symmetrically about the noise centre (an unbiased volume;
    see :func:`_robust_reference`).

    For the form model the lobing order starts at 2 (which also holds the limaçon's
    e^2/(4R) second harmonic) and grows one harmonic at a time, up to ``harmonics``, while the
    Bayesian information criterion on the current unworn points asks for more; every stage is
    refitted robustly (one-sided: only material removed is wear) from the previous stage's
    unworn points, so that wear found at a low order is not absorbed by a higher one. The fit
    at the neighbouring order measures how much the result depends on that choice.
    """
    shape2d = (z.size, th.size)
    args = (threshold, mask_in, max_iter, "wear_map", shape2d, th, margin_deg)
    if not isinstance(X, FormBasis):
        return X, _robust_reference(d, X, *args, symmetric=difference), None
    k = min(2, X.harmonics)
    basis = FormBasis(z, th, k, X.deg)
    fit = _robust_reference(d, basis, *args, one_sided=True)
    while k < X.harmonics:
        best, _ = select_harmonics(X, d, fit[1])
        if best <= k:
            break
        k += 1
        basis = FormBasis(z, th, k, X.deg)
        fit = _robust_reference(d, basis, *args, start=fit[1], one_sided=True)
    # the worn region found one-sidedly, the noise is then rejected symmetrically about its
    # centre (a one-sided cut keeps the low tail only: every depth, hence the volume, high)
    one_sided_mask = fit[1]
    fit = _robust_reference(d, basis, *args, start=one_sided_mask, symmetric=True)
    k_alt = k + 1 if k < max(X.harmonics, 3) else k - 1
    alt_basis = FormBasis(z, th, k_alt, X.deg)
    alt = _robust_reference(d, alt_basis, *args, start=one_sided_mask, symmetric=True)
    return basis, fit, alt


def _model_order_term(q: dict, other: np.ndarray, wts: np.ndarray, z, th, what: str) -> None:
    """Add, in quadrature, how much each quantity changes under another defensible choice
    (the form model's order, the unworn selection): a source of uncertainty."""
    zeros = np.zeros_like(other)
    alt = derived_quantities(other, zeros, 0.0, 1.0, np.zeros(1), np.zeros((1, 1)), wts, z, th)
    for name, (v, u, comment) in list(q.items()):
        dv = abs(alt[name][0] - v)
        if np.isfinite(dv):
            q[name] = (v, float(np.hypot(u, dv)), comment + f"; {what} ({dv:.3g})")


def _lower_quantile_start(X, d: np.ndarray, finite: np.ndarray, threshold: float, tau=0.25):
    """First unworn set from a ``tau``-quantile fit (iteratively reweighted least squares).

    Wear only removes material, so it lies above the unworn surface: a low quantile of the
    data is hardly pulled by a broad groove, which a least-squares fit to all points absorbs
    (into the centre terms, then nothing stands out and the map reads zero wear).
    """
    dd = np.where(finite, d, 0.0)
    w = finite.astype(float)
    r = dd
    for _ in range(30):
        try:
            _, fitted, _ = _lsq(X, dd, w)
        except np.linalg.LinAlgError:
            return finite
        r = dd - fitted
        scale = max(float(np.median(np.abs(r[finite]))), _SCALE_FLOOR)
        w = np.where(
            finite, np.where(r > 0, tau, 1.0 - tau) / np.maximum(np.abs(r), 1e-3 * scale), 0.0
        )
    rf = r[finite]
    med = np.median(rf[rf <= np.percentile(rf, 50)])  # centre of the lower half
    low = rf[rf <= np.percentile(rf, 50)]
    scale = max(1.4826 * np.median(np.abs(low - np.median(low))) * 1.5, _SCALE_FLOOR)
    return finite & (r - med <= threshold * scale)
