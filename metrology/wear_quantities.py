"""Quantities derived from a wear map, each with its standard uncertainty.

Every number a wear map states comes with ``<name>_u`` (standard uncertainty, k = 1,
``coverage_factor`` 1) and a ``comment`` saying what the uncertainty covers:

* ``worn_volume``: the fitted reference's covariance propagated exactly (V = sum w h, h = d - X b,
  so var_fit(V) = aᵀ C a with a = sum w X), plus the scatter of the unworn points with its
  correlation along theta (effective number of independent points = N / correlation length);
* ``max_wear_depth``: the maximum of the map smoothed over about 1 degree, less its
  extreme-value bias (the maximum of noisy values near the top exceeds the top: the expected
  excess, simulated with the map's own noise, :func:`extreme_value_bias`), with the fitted
  reference's variance at that point, the smoothed scatter and the correction's own
  uncertainty (a third of it squared: rectangular over 0..bias);
* ``wear_cylindricity``: the minimum-zone cylindricity of the smoothed wear map, with the
  variances at its highest and lowest points;
* ``cylindricity_before`` / ``cylindricity_after``: the noise at the two extreme points of
  each zone (instrument noise from successive differences); a zone's upward bias by noise is
  not corrected.

:func:`format_pm` prints a value with as many digits as its uncertainty needs, so "± 0.0000"
never appears.
"""

from __future__ import annotations

import math

import numpy as np

from jointwear.metrology.form import cylinder_zone

__all__ = ["derived_quantities", "format_pm", "uncertainty_attrs"]


def uncertainty_attrs(comment: str) -> dict:
    """Attributes of an ``_u`` variable: standard uncertainty, what it covers."""
    return {"coverage_factor": 1.0, "comment": comment}


def _smooth(v: np.ndarray, win: int) -> np.ndarray:
    if win <= 1:
        return v
    k = np.ones(win) / win
    h = win // 2
    ext = np.concatenate([v[:, -h:], v, v[:, :h]], axis=1)
    return np.stack([np.convolve(row, k, mode="valid") for row in ext])


def extreme_value_bias(
    sm: np.ndarray, sigma: float, win: int, draws: int = 64, seed: int = 0
) -> float:
    """Expected excess [m] of the maximum of a noisy smoothed map over the maximum of its mean.

    The map ``sm`` (smoothed over ``win`` samples in theta) near its top (the rows within 5
    standard deviations of the smoothed noise of its maximum) is taken as the mean; white noise
    of standard deviation ``sigma`` [m] per sample, smoothed like the map, is added ``draws``
    times (a fixed seed: reproducible) and the mean excess of the maximum over the top is
    returned. A flat top of n independent values reads about sigma sqrt(2 ln n) / sqrt(win)
    high, a sharp peak hardly at all. The noisy top is more ragged than the truth's, so this is
    short of the bias on a flat top (about 30 % of it there; a local quadratic fit as the mean
    came to 60 % on the flat top but over-corrected grooves, -0.33 u on average): the rest is
    in the u (:func:`derived_quantities`).
    """
    s_sm = sigma / np.sqrt(win)
    if not (np.isfinite(s_sm) and s_sm > 0):
        return 0.0
    rows = np.flatnonzero((sm >= sm.max() - 5.0 * s_sm).any(axis=1))
    mean = sm[rows]
    top = float(mean.max())
    near = mean >= top - 5.0 * s_sm
    rng = np.random.default_rng(seed)
    excess = np.empty(draws)
    for i in range(draws):
        noise = _smooth(sigma * rng.standard_normal(mean.shape), win)
        excess[i] = float(np.max(np.where(near, mean + noise, -np.inf))) - top
    return float(max(np.mean(excess), 0.0))


def derived_quantities(
    wear: np.ndarray,
    var_fit: np.ndarray,
    s2: float,
    tau: float,
    a_vol: np.ndarray,
    cov: np.ndarray,
    wts: np.ndarray,
    z: np.ndarray,
    theta_deg: np.ndarray,
    noise: float | None = None,
) -> dict[str, tuple[float, float, str]]:
    """{name: (value, standard uncertainty, comment)} for volume, max depth, cylindricity.

    Parameters
    ----------
    wear, var_fit : ndarray (nz, nt)
        Wear depth [m] and the variance of the fitted reference at each point [m^2].
    s2 : float
        Variance of the unworn points' residual [m^2] (noise and unmodelled form).
    tau : float
        Correlation length of that residual along theta [samples].
    a_vol, cov : ndarray
        sum of volume weight x design row (p,), and the coefficients' covariance (p, p).
    wts : ndarray (nz, nt)
        Volume weights [m^2] (R dtheta dz).
    noise : float, optional
        Instrument noise per sample [m] (white): the maximum's extreme-value bias is simulated
        with it (unmodelled smooth structure in ``s2`` biases no maximum up). Not given: no
        correction.
    """
    vol = float(np.sum(wts * np.nan_to_num(wear)))
    u_vol = math.sqrt(float(a_vol @ cov @ a_vol) + s2 * tau * float(np.sum(wts**2)))
    nt = theta_deg.size
    win = max(1, int(round(nt / 360.0)) | 1)
    sm = _smooth(np.nan_to_num(wear), win)
    s2_sm = s2 * min(1.0, tau / win)
    k = np.unravel_index(int(np.argmax(sm)), sm.shape)
    ok = noise is not None and np.isfinite(noise) and noise > 0
    bias = extreme_value_bias(sm, min(float(noise), math.sqrt(s2)), win) if ok else 0.0
    near = sm >= sm[k] - 2.0 * math.sqrt(s2_sm)  # values that could be the maximum
    n_top = max(1.0, float(np.count_nonzero(near)) / max(win, tau))
    out = {
        "worn_volume": (
            vol,
            u_vol,
            "fitted reference (covariance propagated) and scatter of the unworn points "
            f"(instrument noise and unmodelled form, correlation length {tau:.3g} samples)",
        ),
        "max_wear_depth": (
            float(sm[k]) - bias,
            math.sqrt(float(var_fit[k]) + s2_sm * (1.0 + 2.0 * math.log(n_top))),
            f"maximum of the map averaged over {win} sample(s) in theta, less its extreme-value "
            f"bias ({bias:.3g}: the expected excess of the maximum of the noisy values near the "
            "top, simulated on the map's own top, which is short of it on a flat top); fitted "
            "reference at that point and the averaged scatter of the unworn points, widened for "
            f"the maximum of {n_top:.3g} independent values near the top (the rest of the bias)",
        ),
    }
    if z.size > 1:
        zone = cylinder_zone(
            np.broadcast_to(z[:, None], sm.shape), np.broadcast_to(theta_deg, sm.shape), sm
        )
        lo = np.unravel_index(int(np.argmin(sm)), sm.shape)
        out["wear_cylindricity"] = (
            float(zone.total),
            math.sqrt(float(var_fit[k] + var_fit[lo]) + 2 * s2_sm),
            "MZ cylindricity of the wear map (averaged as max_wear_depth); fitted reference "
            "and scatter at its highest and lowest points",
        )
    else:
        out["wear_cylindricity"] = (float("nan"), float("nan"), "not assessed: one layer")
    return out


def format_pm(value: float, u: float, scale: float, unit: str) -> str:
    """'value ± u unit' with two significant digits of ``u`` (``scale``: metres per unit)."""
    if not (np.isfinite(value) and np.isfinite(u)):
        return f"{value / scale:.4g} {unit} (uncertainty not assessed)"
    v, uu = value / scale, u / scale
    if uu <= 0:
        return f"{v:.6g} ± {uu:.2g} {unit}"
    dec = max(0, 1 - int(math.floor(math.log10(uu))))
    return f"{v:.{dec}f} ± {uu:.{dec}f} {unit}"
