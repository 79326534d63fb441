"""Rigid-body fits of tracked points and smoothing differentiation of time series."""

from __future__ import annotations

import functools

import numpy as np

from jointwear.errors import BadInputError

__all__ = [
    "fit_rigid",
    "fit_rigid_robust",
    "pose_point_uncertainty",
    "time_derivative",
    "derivative_truncation",
    "rotation_angle_z",
]


def fit_rigid(
    P: np.ndarray, Q: np.ndarray, weights: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Least-squares rigid transform ``Q ≈ R P + t`` (Kabsch/Umeyama without scale).

    Parameters
    ----------
    P, Q : (N, d) arrays
        Corresponding points (d = 2 or 3) [m or pixel].
    weights : (N,) array, optional
        Non-negative weights.

    Returns
    -------
    R : (d, d) array
        Proper rotation (det = +1).
    t : (d,) array
        Translation.
    """
    P = np.asarray(P, dtype=float)
    Q = np.asarray(Q, dtype=float)
    if P.shape != Q.shape or P.ndim != 2 or P.shape[1] not in (2, 3):
        raise BadInputError(
            f"rigid fit needs two (N, 2|3) arrays of equal shape, got {P.shape}, {Q.shape}"
        )
    w = np.ones(len(P)) if weights is None else np.asarray(weights, dtype=float)
    if w.sum() <= 0 or np.count_nonzero(w) < P.shape[1]:
        raise BadInputError(
            f"rigid fit needs at least {P.shape[1]} points, got {np.count_nonzero(w)}"
        )
    w = w / w.sum()
    cp = w @ P
    cq = w @ Q
    H = (P - cp).T @ ((Q - cq) * w[:, None])
    U, _, Vt = np.linalg.svd(H)
    d = np.sign(np.linalg.det(Vt.T @ U.T))
    D = np.eye(P.shape[1])
    D[-1, -1] = d
    R = Vt.T @ D @ U.T
    return R, cq - R @ cp


def fit_rigid_robust(
    P: np.ndarray,
    Q: np.ndarray,
    *,
    threshold: float = 4.0,
    iterations: int = 3,
    min_points: int = 3,
    cov_p: np.ndarray | None = None,
    cov_q: np.ndarray | None = None,
    gate: float | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """Rigid fit with outlier rejection (residual > ``threshold`` x 1.4826 x MAD, iterated).

    NaN rows are ignored.

    With the points' covariances (``cov_p`` and/or ``cov_q``, (N, d, d)), a point is an outlier
    only if its residual is also beyond ``gate`` standard deviations of its own uncertainty
    (Mahalanobis distance with the residual's covariance ``cov_q + R cov_p R^T``; default: the
    chi-square(d) quantile at 1e-4, 4.6 in 3D). The MAD limit alone trims ordinary points of
    the noise's tail too, and which of them it trims flips with sub-noise changes of the
    matches (another IC-GN start); the excluded points of a thin plate can tilt the fitted
    pose by much more than its uncertainty suggests. Gross mismatches lie far beyond both.

    Returns
    -------
    R, t : arrays
        The transform ``Q ≈ R P + t``.
    inliers : (N,) bool array
    rms : float
        RMS residual of the inliers (same unit as the points).
    """
    P = np.asarray(P, dtype=float)
    Q = np.asarray(Q, dtype=float)
    ok = np.all(np.isfinite(P), axis=1) & np.all(np.isfinite(Q), axis=1)
    if ok.sum() < min_points:
        raise BadInputError(
            f"rigid fit: only {ok.sum()} valid points, at least {min_points} needed"
        )
    d = P.shape[1]
    R = np.empty((d, d))
    t = np.empty(d)
    inl = np.empty(len(P), dtype=np.bool_)
    n = len(P)
    use_cov = cov_p is not None or cov_q is not None
    cp, cq = (
        np.zeros((n, d, d)) if c is None else np.ascontiguousarray(c, dtype=float).reshape(n, d, d)
        for c in (cov_p, cov_q)
    )
    # points whose covariance is unknown get no gate (the MAD limit alone decides)
    gated = ok & np.all(np.isfinite(cp), axis=(1, 2)) & np.all(np.isfinite(cq), axis=(1, 2))
    if use_cov:
        gate2 = float(gate) ** 2 if gate is not None else _chi2_gate(d)
    else:
        gate2 = -1.0
    rms = _robust_rigid(
        np.ascontiguousarray(P), np.ascontiguousarray(Q), ok, float(threshold), int(iterations),
        int(min_points), np.where(gated[:, None, None], cp, 0.0),
        np.where(gated[:, None, None], cq, 0.0), gated, gate2, R, t, inl,
    )  # fmt: skip
    return R, t, inl, float(rms)


@functools.lru_cache(maxsize=4)
def _chi2_gate(d: int) -> float:
    """Squared Mahalanobis distance beyond which a point of a d-dimensional Gaussian lies with
    probability 1e-4 (21.1 in 3D, 18.4 in 2D)."""
    from scipy.stats import chi2

    return float(chi2.isf(1e-4, d))


def pose_point_uncertainty(
    P: np.ndarray,
    Q: np.ndarray,
    R: np.ndarray,
    t: np.ndarray,
    inliers: np.ndarray,
    point: np.ndarray,
    cov_q: np.ndarray | None = None,
) -> np.ndarray:
    """Standard uncertainty (d,) of ``R point + t``, a body-fixed point moved with a fitted
    rigid pose (per axis).

    The least-squares pose of the inliers is linearised in a small rotation and a translation
    at the inliers' centroid, ``Q_i ~ X_i + w x (X_i - c) + dt`` with ``X_i = R P_i + t``, and
    the point's variance is the diagonal of the sandwich ``J A^-1 B A^-1 J^T`` (``J`` the
    point's Jacobian, ``A = sum J_i^T J_i``). ``B`` is taken twice: from the points'
    covariances ``cov_q`` (N, d, d), and from the fit's own residuals
    (``sum J_i^T e_i e_i^T J_i``, scaled by n / (n - parameters)); the larger variance of each
    axis is kept. Unlike the centroid's uncertainty, this holds the rotation's uncertainty
    times the lever arm of the point: a point away from a narrow plate moves by the plate's
    poorly determined tilt.
    """
    P = np.asarray(P, dtype=float)
    Q = np.asarray(Q, dtype=float)
    inl = np.asarray(inliers, dtype=bool) & np.all(np.isfinite(Q), axis=1)
    d = P.shape[1]
    n = int(inl.sum())
    k = 3 if d == 2 else 6  # pose parameters
    X = P[inl] @ R.T + t
    c = X.mean(axis=0)
    x = R @ np.asarray(point, dtype=float) + t

    def jac(v):  # (m, d) offsets from the centroid -> (m, d, k)
        J = np.zeros((len(v), d, k))
        if d == 2:
            J[:, 0, 0], J[:, 1, 0] = -v[:, 1], v[:, 0]
            J[:, :, 1:] = np.eye(2)
        else:
            J[:, 0, 1], J[:, 0, 2] = v[:, 2], -v[:, 1]
            J[:, 1, 0], J[:, 1, 2] = -v[:, 2], v[:, 0]
            J[:, 2, 0], J[:, 2, 1] = v[:, 1], -v[:, 0]
            J[:, :, 3:] = np.eye(3)
        return J

    if n <= k:
        return np.full(d, np.nan)
    J = jac(X - c)
    A = np.einsum("nij,nik->jk", J, J)
    try:
        Ai = np.linalg.inv(A)
    except np.linalg.LinAlgError:
        return np.full(d, np.nan)
    G = jac((x - c)[None])[0] @ Ai  # (d, k)
    M = J @ G.T  # (n, d, d): the point's sensitivity to each inlier
    e = Q[inl] - X
    me = np.einsum("nia,ni->na", M, e)
    var = np.einsum("na,na->a", me, me) * n / (n - k)
    if cov_q is not None:
        C = np.asarray(cov_q, dtype=float)[inl]
        if np.all(np.isfinite(C)):
            var = np.maximum(var, np.einsum("nia,nij,nja->a", M, C, M))
    return np.sqrt(var)


def _kabsch_impl(P, Q, mask, R, t):
    """Least-squares rotation R and translation t with Q ~ R P + t over the ``mask`` rows."""
    d = P.shape[1]
    m = 0
    cp = np.zeros(d)
    cq = np.zeros(d)
    for i in range(P.shape[0]):
        if mask[i]:
            m += 1
            for k in range(d):
                cp[k] += P[i, k]
                cq[k] += Q[i, k]
    cp /= m
    cq /= m
    H = np.zeros((d, d))
    for i in range(P.shape[0]):
        if mask[i]:
            for a in range(d):
                for b in range(d):
                    H[a, b] += (P[i, a] - cp[a]) * (Q[i, b] - cq[b])
    U, _, Vt = np.linalg.svd(H)
    D = np.eye(d)
    D[d - 1, d - 1] = np.sign(np.linalg.det(Vt.T @ U.T))
    R[:, :] = Vt.T @ D @ U.T
    t[:] = cq - R @ cp


def _robust_rigid_impl(
    P, Q, ok, threshold, iterations, min_points, cov_p, cov_q, gated, gate2, R, t, inl
):
    """The iterations of :func:`fit_rigid_robust` (fit, MAD limit, refit); returns the RMS.
    ``gate2`` >= 0: a ``gated`` point within that squared Mahalanobis distance (residual
    covariance ``cov_q + R cov_p R^T``) is kept whatever the MAD limit."""
    n = P.shape[0]
    d = P.shape[1]
    inl[:] = ok
    res = np.empty(n)
    m2 = np.empty(n)
    e = np.empty(d)
    S = np.empty((d, d))

    def residuals():
        for i in range(n):
            if ok[i]:
                s = 0.0
                for a in range(d):
                    e[a] = Q[i, a] - t[a]
                    for b in range(d):
                        e[a] -= R[a, b] * P[i, b]
                    s += e[a] * e[a]
                res[i] = np.sqrt(s)
                m2[i] = np.inf
                if gate2 >= 0.0 and gated[i]:
                    # residual covariance cov_q + R cov_p R^T, and e^T S^-1 e by cofactors
                    for a in range(d):
                        for b in range(d):
                            v = cov_q[i, a, b]
                            for k in range(d):
                                for m in range(d):
                                    v += R[a, k] * cov_p[i, k, m] * R[b, m]
                            S[a, b] = v
                    m2[i] = _mahalanobis2(S, e, d)
            else:
                res[i] = np.inf
                m2[i] = np.inf

    for _ in range(iterations):
        _kabsch(P, Q, inl, R, t)
        residuals()
        r_in = res[inl]
        med = np.median(r_in)
        mad = np.median(np.abs(r_in - med))
        limit = max(med + threshold * 1.4826 * max(mad, 1e-12) + 1e-12, 1e-9)
        new = ok & ((res <= limit) | (m2 <= gate2))
        if new.sum() < min_points or np.all(new == inl):
            break
        inl[:] = new
    _kabsch(P, Q, inl, R, t)
    residuals()
    return np.sqrt(np.mean(res[inl] ** 2))


def _mahalanobis2_impl(S, e, d):
    """``e^T S^-1 e`` for a symmetric 2 x 2 or 3 x 3 ``S`` (inf unless positive definite)."""
    if d == 2:
        det = S[0, 0] * S[1, 1] - S[0, 1] * S[1, 0]
        if not (det > 0.0 and S[0, 0] > 0.0):
            return np.inf
        return (S[1, 1] * e[0] ** 2 - 2.0 * S[0, 1] * e[0] * e[1] + S[0, 0] * e[1] ** 2) / det
    c00 = S[1, 1] * S[2, 2] - S[1, 2] * S[2, 1]
    c01 = S[1, 2] * S[2, 0] - S[1, 0] * S[2, 2]
    c02 = S[1, 0] * S[2, 1] - S[1, 1] * S[2, 0]
    det = S[0, 0] * c00 + S[0, 1] * c01 + S[0, 2] * c02
    if not (det > 0.0 and S[0, 0] > 0.0 and c00 > 0.0):
        return np.inf
    c11 = S[0, 0] * S[2, 2] - S[0, 2] * S[2, 0]
    c12 = S[0, 1] * S[2, 0] - S[0, 0] * S[2, 1]
    c22 = S[0, 0] * S[1, 1] - S[0, 1] * S[1, 0]
    q = c00 * e[0] ** 2 + c11 * e[1] ** 2 + c22 * e[2] ** 2
    q += 2.0 * (c01 * e[0] * e[1] + c02 * e[0] * e[2] + c12 * e[1] * e[2])
    return q / det


def _robust_rigid(*args):
    """Compiled on first use (numba), so importing this module stays light."""
    global _robust_rigid, _kabsch, _mahalanobis2
    from numba import njit

    _kabsch = njit(cache=True)(_kabsch_impl)
    _mahalanobis2 = njit(cache=True)(_mahalanobis2_impl)
    _robust_rigid = njit(cache=True)(_robust_rigid_impl)
    return _robust_rigid(*args)


def rotation_angle_z(R: np.ndarray) -> np.ndarray:
    """Rotation angle about z of rotation matrices (..., 3, 3) or (..., 2, 2) [rad]."""
    R = np.asarray(R)
    return np.arctan2(R[..., 1, 0], R[..., 0, 0])


def time_derivative(
    t: np.ndarray, x: np.ndarray, *, window: int = 9, order: int = 5, centred: bool = True
) -> tuple[np.ndarray, np.ndarray]:
    """First derivative by local polynomial least squares (Savitzky–Golay on actual times).

    At every sample a polynomial of degree ``order`` in ``t - t_i`` is fitted to the ``window``
    samples centred on it (shifted inwards at the ends; NaN samples skipped) and its slope
    taken. On uniform samples this is the Savitzky–Golay differentiator; gaps (dropped frames)
    are handled exactly because the real times are used.

    Parameters
    ----------
    t : (N,) array
        Sample times [s], increasing.
    x : (N, ...) array
        Samples.
    window : int
        Odd number of samples per fit (default 9: 0.18 s at 50 fps).
    order : int
        Polynomial degree (default 5). With 9/5 the truncation error on the study's four-bar
        kinematics at 50 fps is 0.23 % of the peak follower speed.

    Returns
    -------
    dxdt : (N, ...) array
        Derivative [unit of x per s]; NaN at the first and last sample and where too few
        valid samples remain. Within ``window // 2`` samples of an end the window shrinks
        symmetrically (centred differences; degree at most ``2 * distance to the end``);
        with ``centred=False`` the full window and degree are kept there instead (an
        off-centre fit: less truncation, more noise; used to estimate the truncation error).
    gain : (N,) array
        Noise gain ``sqrt(sum c_j^2)`` [1/s]: the derivative's standard uncertainty is
        ``gain * sigma_x`` for independent sample noise ``sigma_x``.
    """
    t = np.asarray(t, dtype=float)
    x = np.asarray(x, dtype=float)
    n = len(t)
    if window % 2 == 0 or window <= order:
        raise BadInputError(
            f"derivative window must be odd and > order; got window={window}, order={order}"
        )
    if n < window:
        window = n if n % 2 == 1 else n - 1
        order = min(order, window - 1)
    if n < 2 or window < 2:
        return np.full_like(x, np.nan), np.full(n, np.nan)
    flat = x.reshape(n, -1)
    h = window // 2
    starts = np.clip(np.arange(n) - h, 0, n - window)
    idx = starts[:, None] + np.arange(window)[None, :]
    dt = t[idx] - t[:, None]
    scale = np.nanmax(np.abs(dt)) or 1.0
    A = (dt / scale)[..., None] ** np.arange(order + 1)  # (n, w, p+1)
    vals = flat[idx]  # (n, w, k)
    valid = np.all(np.isfinite(vals), axis=2)
    # near the record ends the window shrinks symmetrically (half-width = distance to the end)
    # and the degree with it: an off-centre evaluation of the fitted polynomial is strongly
    # biased; the first and last samples get NaN
    pos = np.arange(n)[:, None]
    reach = np.minimum(np.arange(n), n - 1 - np.arange(n))[:, None]
    if centred:
        valid &= np.abs(idx - pos) <= reach
        deg = np.minimum(order, 2 * reach[:, 0])
    else:
        deg = np.full(n, order)
    A = np.where(np.arange(order + 1)[None, None, :] <= deg[:, None, None], A, 0.0)
    Aw = A * valid[..., None]
    pinv = np.linalg.pinv(Aw)  # (n, p+1, w)
    c = pinv[:, 1, :] / scale  # slope coefficients
    enough = (valid.sum(axis=1) >= deg + 1) & (deg >= 1)
    out = np.einsum("nw,nwk->nk", c, np.where(valid[..., None], vals, 0.0))
    out[~enough] = np.nan
    gain = np.sqrt(np.sum(c**2, axis=1))
    gain[~enough] = np.nan
    return out.reshape(x.shape), gain


def derivative_truncation(
    t: np.ndarray, x: np.ndarray, *, window: int = 9, order: int = 5
) -> np.ndarray:
    """Estimated truncation (model) error of :func:`time_derivative` per sample [unit of x/s].

    Inside the record: the difference between the derivative of degree ``order`` on
    ``window`` samples and that of degree ``order + 2`` on ``window + 2`` samples (whose own
    truncation error is far smaller), the larger over three neighbouring samples. Within
    ``window // 2`` samples of an end, where :func:`time_derivative` shrinks its window and
    degree: the difference from the full-degree off-centre fit. Both differences also hold
    some noise, so the estimate errs on the large side.
    """
    t = np.asarray(t, dtype=float)
    x = np.asarray(x, dtype=float)
    n = len(t)
    v, _ = time_derivative(t, x, window=window, order=order)
    if n < window + 2:
        return np.full_like(x, np.nan)
    hi, _ = time_derivative(t, x, window=window + 2, order=order + 2)
    off, _ = time_derivative(t, x, window=window, order=order, centred=False)
    reach = np.minimum(np.arange(n), n - 1 - np.arange(n))
    shape = (n,) + (1,) * (x.ndim - 1)
    e = np.where((reach < window // 2).reshape(shape), np.abs(v - off), np.abs(v - hi))
    padded = np.concatenate([e[:1], e, e[-1:]], axis=0)
    stacked = np.stack([padded[:-2], padded[1:-1], padded[2:]])
    with np.errstate(invalid="ignore"):
        out = np.nanmax(np.where(np.isfinite(stacked), stacked, -np.inf), axis=0)
    out[~np.isfinite(v)] = np.nan
    out[np.isinf(out)] = np.nan
    return out


def position_noise(t: np.ndarray, x: np.ndarray, *, window: int = 9, order: int = 5) -> np.ndarray:
    """Empirical upper estimate of the sample noise of ``x`` (N, k) per column [unit of x].

    Every interior sample is compared with the local polynomial (degree ``order`` on its
    ``window - 1`` neighbours, actual times); the residuals, corrected for the fit's variance,
    hold the noise actually present (image noise, rigid-fit scatter, lever arms) plus the
    polynomial's model error, so this bounds the noise from above (closely for slow motion).
    """
    t = np.asarray(t, dtype=float)
    x = np.asarray(x, dtype=float).reshape(len(t), -1)
    n, h = len(t), window // 2
    if n < window + 2:
        return np.full(x.shape[1], np.nan)
    centres = np.arange(h, n - h)
    idx = centres[:, None] + np.arange(-h, h + 1)[None, :]
    dt = t[idx] - t[centres][:, None]
    scale = np.max(np.abs(dt)) or 1.0
    A = (dt / scale)[..., None] ** np.arange(order + 1)
    vals = x[idx]
    valid = np.all(np.isfinite(vals), axis=2)
    valid[:, h] = False  # leave the sample out of its own fit
    pinv = np.linalg.pinv(A * valid[..., None])
    c0 = pinv[:, 0, :]  # value of the fitted polynomial at the centre
    pred = np.einsum("nw,nwk->nk", c0, np.where(valid[..., None], vals, 0.0))
    ok = (valid.sum(axis=1) > order + 1) & np.all(np.isfinite(x[centres]), axis=1)
    if ok.sum() < 3:
        return np.full(x.shape[1], np.nan)
    res = (x[centres] - pred)[ok]
    infl = 1.0 + np.sum(c0[ok] ** 2, axis=1)  # var(residual) = sigma^2 (1 + sum c0^2)
    return np.sqrt(np.mean(res**2 / infl[:, None], axis=0))
