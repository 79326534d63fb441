"""Robust fit of the unworn reference of a wear map (the points that are not worn).

The reference (a limaçon cylinder, a limaçon circle per layer or the form model of
:mod:`~jointwear.metrology.baseline`) is fitted by least squares to the points found unworn
iteratively: start with all points (or a lower-quantile fit), fit, keep the points whose residual
lies within ``threshold`` robust standard deviations (1.4826 MAD) of the median and outside a
margin around smoothed worn regions, refit, until the set no longer changes. With a before-scan
the noise is rejected symmetrically about its centre and the faint wear tails next to the worn
region are tested band by band (:func:`_exclude_tails`).
"""

from __future__ import annotations

import numpy as np

from jointwear.errors import BadInputError
from jointwear.metrology.baseline import FormBasis, correlation_length, select_harmonics

_SCALE_FLOOR = 1e-11  # [m]


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


def _design_sum(X, w: np.ndarray) -> np.ndarray:
    """sum_i w_i X_i over all points (p,): the volume's sensitivity to the coefficients."""
    if isinstance(X, FormBasis):
        return X.weighted_sum(w)
    if isinstance(X, _LayerBasis):
        return (w @ X.block.T).ravel()
    return w.ravel() @ X


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
    symmetric_regions: bool | None = None,
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
    at 3 sigma, plus the high smoothed windows). ``symmetric_regions`` False: the margin is
    kept around high windows only (a low window of a modelled form is no evidence of wear; a
    margin around it could empty a layer).
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
            dev = sm - smed
            both = symmetric if symmetric_regions is None else symmetric_regions
            if one_sided and not symmetric:
                region = _dilate(~(dev > threshold * sscale), theta_deg, margin_deg)
            elif both:
                region = _dilate(~(np.abs(dev) > threshold * sscale), theta_deg, margin_deg)
            else:  # low windows dropped too (unbiased), without a margin (no wear beside them)
                region = _dilate(~(dev > threshold * sscale), theta_deg, margin_deg)
                region &= ~(dev < -threshold * sscale)
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
    points). While a zone of 1, 2, 4 or 8 bands (``step_deg`` wide, on every layer) next to the
    worn region has a mean above ``z_crit`` standard errors, the next band leaves the unworn
    set and the reference is refitted. Where that would leave fewer than ``min_fraction`` of
    the points, the tails reach around the bore: the test stops there and returns the tail it
    still measures (mean + 2 standard errors), whose consequence the map carries in its u
    (:mod:`._wear_unseen`: decided by consequence, not refused for its presence; a 1-nm tail
    against 7 um of wear used to refuse the map). What stays below the test is in the
    uncertainty: the larger of the "unworn selection" term (the change when a further 10-30
    degree is left out) and the undetected tail (:func:`undetected_tail`).
    Returns (mask, description, remaining tail [m] or None when the test did not stop early).
    """
    nz, nt = shape
    win = max(1, int(round(step_deg * nt / 360.0)))
    # the worn region: most of a step-wide window not unworn (not each isolated noise outlier)
    region = _smooth_theta((~mask).reshape(shape).astype(float), win) > 0.5
    if not region.any() or region.all():
        return mask, "none found (no worn region)", None
    n_bands, note, remaining = 0, "", None
    while True:
        grown = ~_dilate(~region, theta_deg, step_deg)
        new = mask & ~(grown & ~region).ravel()
        if new.sum() == mask.sum():
            break
        # zones of 1, 2, 4 and 8 bands: a long faint tail shows in a wide zone's mean
        found = False
        for k in (1, 2, 4, 8):
            zone = ~_dilate(~region, theta_deg, k * step_deg)
            zone = (zone & ~region).ravel() & mask
            if mask.sum() - zone.sum() < 0.4 * min_fraction * mask.size:
                break  # too few points left to test against
            tbar, se = _deleted_mean(d, X, mask & ~zone, zone, shape)
            note = f"last zone tested: mean {tbar * 1e9:.3g} nm, standard error {se * 1e9:.2g} nm"
            if tbar > max(z_crit * se, _SCALE_FLOOR):  # (noise-free data: 10 pm)
                found = True
                break
        if not found:
            break
        if new.sum() < min_fraction * mask.size:  # the tails reach around the bore
            remaining = tbar + 2.0 * se
            note += (
                f"; the tails reach around the bore: stopped with {mask.mean():.0%} of the "
                f"points left, their remaining wear ({tbar * 1e9:.2g} ± {se * 1e9:.2g} nm) is "
                "carried in the u"
            )
            break
        mask, region, n_bands = new, grown, n_bands + 1
    return (
        mask,
        f"{n_bands} band(s) of {step_deg:g} degree next to the worn region held wear above "
        f"{z_crit:g} standard errors and were left out of the unworn set ({note})",
        remaining,
    )


def _deleted_mean(d, X, fit_mask, zone, shape) -> tuple[float, float]:
    """Mean residual [m] of the points ``zone`` from the reference fitted on ``fit_mask``
    (without them: their own wear cannot pull the reference they are tested against), and
    its standard error: s sqrt(tau / n) and the reference's prediction error."""
    _, fitted, G = _lsq(X, d, fit_mask)
    r = d - fitted
    s2 = max(float(np.mean(r[fit_mask] ** 2)), _SCALE_FLOOR**2)
    tau = correlation_length(r.reshape(shape), fit_mask.reshape(shape))
    n = int(zone.sum())
    a = _design_sum(X, zone.reshape(shape) / n)  # the zone's mean design row
    cov = np.linalg.inv(G) * s2
    if cov.ndim == 3:  # one block per layer (circle per layer)
        from scipy.linalg import block_diag

        cov = block_diag(*cov)
    var_pred = max(float(a @ cov @ a), 0.0)
    return float(np.mean(r[zone])), float(np.sqrt(s2 * tau / n + var_pred))


def _reference(
    d, X, shape, z, th, harmonics, threshold, mask_in, max_iter, margin_deg, difference=False
):
    """(basis used, robust fit, fit at the neighbouring lobing order or None, the one-sided
    (fit, neighbouring fit) of the form model or None).

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
        return X, _robust_reference(d, X, *args, symmetric=difference), None, None
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
    # (point by point: a low smoothed region of a modelled form is no evidence of wear, and
    # leaving it out with its margin could empty a layer)
    polish = {"start": one_sided_mask, "symmetric": True, "symmetric_regions": False}
    # the one-sided fits are kept: wear_map refuses where either cannot separate wear from form
    k_alt = k + 1 if k < max(X.harmonics, 3) else k - 1
    alt_basis = FormBasis(z, th, k_alt, X.deg)
    first = (fit, _robust_reference(d, alt_basis, *args, start=one_sided_mask, one_sided=True))
    fit = _robust_reference(d, basis, *args, **polish)
    alt = _robust_reference(d, alt_basis, *args, **polish)
    return basis, fit, alt, first


def _layer_distance(region: np.ndarray, theta_deg: np.ndarray) -> np.ndarray:
    """Angular distance [degree] of every point to the nearest ``region`` point of its layer
    (periodic; inf in a layer without one)."""
    nz, nt = region.shape
    step = 360.0 / nt
    out = np.full(region.shape, np.inf)
    idx = np.arange(nt)
    for i in range(nz):
        w = np.flatnonzero(region[i])
        if w.size == 0:
            continue
        ext = np.concatenate([w - nt, w, w + nt])
        pos = np.searchsorted(ext, idx)
        left = ext[np.clip(pos - 1, 0, ext.size - 1)]
        right = ext[np.clip(pos, 0, ext.size - 1)]
        out[i] = np.minimum(np.abs(idx - left), np.abs(right - idx)) * step
    return out


def undetected_tail(
    d: np.ndarray,
    X,
    mask: np.ndarray,
    shape: tuple[int, int],
    theta_deg: np.ndarray,
    wts: np.ndarray,
    z_crit: float = 2.0,
    step_deg: float = 5.0,
    lengths: tuple[float, ...] = (2.5, 5.0, 10.0, 20.0, 40.0, 80.0),
) -> tuple[float, np.ndarray, str]:
    """The largest faint wear tail among the unworn points that the band test would not see,
    and what it does to the map: (volume change [m^3], reference shift at every point [m],
    description).

    A tail decaying as exp(-distance / L) away from the worn region (L in ``lengths`` degree)
    on the unworn points is fitted like the data; its amplitude is the largest for which no
    zone of 1, 2, 4 or 8 bands (``step_deg`` wide) next to the worn region has a deleted mean
    (:func:`_deleted_mean`) above ``z_crit`` of that zone's standard error on the data. The
    reference fitted on an arc extrapolates the tail to the worn side (a limaçon on a short
    arc amplifies it many times); the tail of the largest volume change is returned.
    """
    nz, nt = shape
    zeros = np.zeros(nz * nt)
    win = max(1, int(round(step_deg * nt / 360.0)))
    region = _smooth_theta((~mask).reshape(shape).astype(float), win) > 0.5
    if not region.any() or region.all():
        return 0.0, zeros, "none (no worn region)"
    zones = []
    for k in (1, 2, 4, 8):
        zone = (~_dilate(~region, theta_deg, k * step_deg) & ~region).ravel() & mask
        if not zone.any() or mask.sum() - zone.sum() < 0.1 * mask.size:
            break
        try:
            tbar, se = _deleted_mean(d, X, mask & ~zone, zone, shape)
        except np.linalg.LinAlgError:  # the zone empties a layer of the form model
            break
        zones.append((zone, max(tbar, 0.0) + se))
    if not zones:
        return float("nan"), zeros, "not assessed (too few unworn points to test a tail)"
    dist = _layer_distance(region, theta_deg).ravel()
    w = wts.ravel()
    best = (0.0, zeros, "")
    # a tail decays over a fraction of the worn region's width (a Gaussian groove's tail
    # beyond the threshold: a tenth of it; up to a third is allowed)
    width = float(region.sum(axis=1).mean()) * 360.0 / nt
    for length in [x for x in lengths if x <= max(width / 3.0, lengths[0])]:
        g = np.where(mask, np.exp(-dist / length), 0.0)
        amp = np.inf
        for zone, bound in zones:
            t = float(np.mean((g - _lsq(X, g, mask & ~zone)[1])[zone]))  # same fit as above
            if t > 0:
                amp = min(amp, bound / t)
        if not np.isfinite(amp):
            continue
        shift = amp * _lsq(X, g, mask)[1]
        dv = abs(float(np.sum(w * shift)))
        if dv > best[0]:
            edge = amp * 1e9
            best = (
                dv,
                shift,
                f"a tail of {edge:.2g} nm at the worn region's edge, decaying "
                f"over {length:g} degree, passes the band test",
            )
    return best
