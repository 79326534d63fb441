"""Validation metrics on aligned simulation/measurement data (plain numpy, SI units).

Every metric here is a pure function of arrays that are already on a common grid
(:mod:`jointwear.compare.align` puts them there). ``S`` is the simulation ("computed"), ``D`` the
measurement ("data"), both in the same units. :data:`DEFINITIONS` holds the one-line
definition and the unit rule of every metric; :mod:`jointwear.compare.comparison` copies them
into the attributes of the result so that every number carries its meaning.

References
----------
- Sprague, M. A., Geers, T. L. (2004). A spectral-element method for modelling cavitation in
  transient fluid-structure interaction. *Int. J. Numer. Meth. Eng.* 60, 2467-2499 (the
  magnitude/phase/comprehensive error factors; also Schwer 2007, *Eng. Comput.* 23, 295-309).
- ASME V&V 20-2009 (R2021), *Standard for Verification and Validation in Computational Fluid
  Dynamics and Heat Transfer*, sections 1-2 (E = S - D, u_val, expanded U_val).
- Ferson, S., Oberkampf, W. L., Ginzburg, L. (2008). Model validation and predictive
  capability for the thermal challenge problem. *CMAME* 197, 2408-2430 (area validation metric).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from jointwear.errors import BadInputError

__all__ = [
    "DEFINITIONS",
    "rmse",
    "nrmse",
    "pearson_r",
    "sprague_geers",
    "SpragueGeers",
    "area_validation_metric",
    "VV20",
    "vv20",
    "detectable_error",
    "wrap_angle_deg",
    "max_location",
    "worn_volume",
    "lsq_cylindricity",
]

#: metric name -> (long name, one-line definition, unit rule). The unit rule is ``"same"``
#: (units of the compared quantity), ``"1"`` (dimensionless) or a UDUNITS string.
DEFINITIONS: dict[str, tuple[str, str, str]] = {
    "rmse": (
        "root-mean-square error",
        "sqrt(mean((S - D)^2)) over the common grid (S simulation, D measurement)",
        "same",
    ),
    "nrmse": (
        "normalised root-mean-square error",
        "RMSE / (max(D) - min(D)), the range of the measurement on the common grid",
        "1",
    ),
    "pearson_r": (
        "Pearson correlation coefficient",
        "cov(S, D) / (std(S) std(D)) over the common grid; 1 = same shape up to scale and offset",
        "1",
    ),
    "mean_error": ("mean error", "mean(S - D) over the common grid (bias)", "same"),
    "max_abs_error": ("maximum absolute error", "max |S - D| over the common grid", "same"),
    "sg_magnitude": (
        "Sprague-Geers magnitude error M",
        "sqrt(sum S^2 / sum D^2) - 1 on the common time base (0 = same energy)",
        "1",
    ),
    "sg_phase": (
        "Sprague-Geers phase error P",
        "arccos(sum S D / sqrt(sum S^2 sum D^2)) / pi (0 = in phase, 1 = opposite)",
        "1",
    ),
    "sg_comprehensive": (
        "Sprague-Geers comprehensive error C",
        "sqrt(M^2 + P^2)",
        "1",
    ),
    "area_validation_metric": (
        "area validation metric",
        "integral |F_S(x) - F_D(x)| dx between the empirical distribution functions of S and D",
        "same",
    ),
    "max_angle_error": (
        "error of the angle of maximum wear",
        "theta(max S) - theta(max D) wrapped to (-180, 180], canonical convention",
        "degree",
    ),
    "max_z_error": (
        "error of the axial position of maximum wear",
        "z(max S) - z(max D)",
        "m",
    ),
    "volume_fraction_compared": (
        "fraction of the simulated worn volume compared",
        "integral of the simulated wear depth over the axial range the measurement covers / its "
        "integral over the whole simulated width",
        "1",
    ),
    "volume_fraction_outside": (
        "share of the simulated worn volume outside the measured band",
        "1 - volume_fraction_compared: the part of the simulation the comparison does not "
        "validate (extrapolation)",
        "1",
    ),
    "sim_global_max": (
        "global maximum of the simulated wear",
        "largest wear depth of the whole simulated map, inside or outside the measured band",
        "m",
    ),
    "sim_global_max_z": ("axial position of the simulated global maximum", "z of it", "m"),
    "sim_global_max_theta": (
        "angle of the simulated global maximum",
        "theta of it, canonical convention",
        "degree",
    ),
    "value_sim": ("simulated value", "value of the quantity from the simulation", "same"),
    "value_meas": ("measured value", "value of the quantity from the measurement", "same"),
    "relative_error": ("relative error", "(S - D) / |D|", "1"),
    "E": ("comparison error E", "E = S - D (ASME V&V 20)", "same"),
    "u_num": ("numerical standard uncertainty", "u_num of the simulation (ASME V&V 20)", "same"),
    "u_input": (
        "input standard uncertainty",
        "u_input: simulation uncertainty propagated from its input parameters (ASME V&V 20)",
        "same",
    ),
    "u_D": ("measurement standard uncertainty", "u_D of the measured value (ASME V&V 20)", "same"),
    "u_val": (
        "validation standard uncertainty",
        "u_val = sqrt(u_num^2 + u_input^2 + u_D^2) (ASME V&V 20)",
        "same",
    ),
    "U_val": ("expanded validation uncertainty", "U_val = k u_val (ASME V&V 20)", "same"),
    "time_shift": (
        "time shift of the motion alignment",
        "measurement time - simulation time of the same instant, modulo the crank period",
        "same",
    ),
    "time_shift_u": ("standard uncertainty of the time shift", "u of time_shift", "same"),
    "phase_shift": ("phase of the motion alignment", "time_shift / period * 360", "same"),
    "phase_shift_u": ("standard uncertainty of the phase", "u of phase_shift", "same"),
    "pearson_r_alpha": (
        "lower quantile of the Pearson r if the model is right",
        "the field_false_fail_rate quantile of r(S, S + e), e drawn from the comparison's "
        "C_input, u_num and u_D (Monte Carlo): the shape criterion fails below min(wear_r_min, it)",
        "1",
    ),
    "pearson_r_u": (
        "standard uncertainty of the Pearson r if the model is right",
        "standard deviation of r(S, S + e) over the same draws",
        "1",
    ),
    "detectable_turn": (
        "smallest detectable turn of the wear pattern",
        "the turn of the simulated map (both ways, the larger) at which its Pearson r with "
        "itself falls to the shape criterion's limit, min(wear_r_min, r_alpha): its resolution",
        "degree",
    ),
    "mahalanobis_d2": (
        "Mahalanobis distance squared",
        "D² = eᵀ C⁺ e of the feature difference e = f(S) - f(D), C = C_input + C_num + C_D, over "
        "the principal components of C (Hills & Leslie 2003; Rebba & Mahadevan 2006)",
        "1",
    ),
    "mahalanobis_dof": ("degrees of freedom of D²", "number of principal components kept", "1"),
    "mahalanobis_threshold": (
        "threshold of D²",
        "chi² quantile at 1 - the stated false-fail rate, with the degrees of freedom",
        "1",
    ),
    "mahalanobis_p": ("p-value of D²", "P(chi²(K) > D²) under the right-model hypothesis", "1"),
    "detectable_scale_error": (
        "smallest detectable common scale error of the field",
        "sqrt(threshold / sᵀ C⁺ s): a field S (1 + e) fails when |e| exceeds it (resolution)",
        "1",
    ),
    "detectable_error_low": (
        "smallest detectable under-prediction",
        "the relative error (S - D) / |D| < 0 at which |E| = U_val, with the budget's parts that "
        "are applied relative to S scaled to S = D (1 + error): a model that under-predicts by "
        "less passes; -inf = no under-prediction down to S = 0 is detectable (resolution)",
        "1",
    ),
    "detectable_error_high": (
        "smallest detectable over-prediction",
        "the relative error (S - D) / |D| > 0 at which |E| = U_val, scaled as for "
        "detectable_error_low: a model that over-predicts by less passes; inf = no "
        "over-prediction is detectable (resolution)",
        "1",
    ),
}


def _pair(s: np.ndarray, d: np.ndarray, what: str = "S and D") -> tuple[np.ndarray, np.ndarray]:
    """Flatten, check shapes and drop pairs where either side is NaN."""
    s = np.asarray(s, dtype=float).ravel()
    d = np.asarray(d, dtype=float).ravel()
    if s.shape != d.shape:
        raise BadInputError(
            f"{what} must be on the same grid; got {s.size} and {d.size} values - align them first "
            "(jointwear.compare.align_wear_maps / align_time_series)"
        )
    ok = np.isfinite(s) & np.isfinite(d)
    if not np.any(ok):
        raise BadInputError(f"{what} have no finite value in common")
    return s[ok], d[ok]


def rmse(s: np.ndarray, d: np.ndarray) -> float:
    """Root-mean-square error ``sqrt(mean((S - D)^2))`` [units of the inputs]."""
    s, d = _pair(s, d)
    return float(np.sqrt(np.mean((s - d) ** 2)))


def nrmse(s: np.ndarray, d: np.ndarray) -> float:
    """RMSE normalised by the range of the measurement ``max(D) - min(D)`` [1].

    NaN when the measurement is constant (the normalisation is undefined).
    """
    s, d = _pair(s, d)
    span = float(np.max(d) - np.min(d))
    if span <= 0:
        return float("nan")
    return float(np.sqrt(np.mean((s - d) ** 2)) / span)


def pearson_r(s: np.ndarray, d: np.ndarray) -> float:
    """Pearson correlation coefficient of ``S`` and ``D`` [1]; NaN if either is constant."""
    s, d = _pair(s, d)
    sc = s - s.mean()
    dc = d - d.mean()
    den = math.sqrt(float(np.sum(sc * sc)) * float(np.sum(dc * dc)))
    if den == 0.0:
        return float("nan")
    return float(np.clip(np.sum(sc * dc) / den, -1.0, 1.0))


@dataclass(frozen=True)
class SpragueGeers:
    """Sprague-Geers error factors (all dimensionless).

    Attributes
    ----------
    M : float
        Magnitude error ``sqrt(psi_cc / psi_mm) - 1``.
    P : float
        Phase error ``arccos(psi_mc / sqrt(psi_mm psi_cc)) / pi``.
    C : float
        Comprehensive error ``sqrt(M^2 + P^2)``.
    """

    M: float
    P: float
    C: float


def sprague_geers(
    s: np.ndarray, d: np.ndarray, *, weights: np.ndarray | None = None
) -> SpragueGeers:
    """Sprague-Geers magnitude, phase and comprehensive errors of a computed history.

    Parameters
    ----------
    s : ndarray
        Computed (simulated) history on the common time base [any unit].
    d : ndarray
        Measured history on the same time base [same unit].
    weights : ndarray, optional
        Quadrature weights (time steps [s]); uniform sampling needs none.

    Returns
    -------
    SpragueGeers
        ``M``, ``P``, ``C``. With ``s = a d`` (pure amplitude error, ``a > 0``): ``M = a - 1``,
        ``P = 0``. With a pure phase shift of a sinusoid over whole periods: ``M = 0``,
        ``P = shift / pi`` (shift in radians).
    """
    s_arr = np.asarray(s, dtype=float).ravel()
    d_arr = np.asarray(d, dtype=float).ravel()
    w = np.ones_like(s_arr) if weights is None else np.asarray(weights, dtype=float).ravel()
    if w.shape != s_arr.shape:
        raise BadInputError(f"weights have {w.size} values, the histories {s_arr.size}")
    if s_arr.shape != d_arr.shape:
        raise BadInputError(
            f"histories have {s_arr.size} and {d_arr.size} samples; align them first"
        )
    ok = np.isfinite(s_arr) & np.isfinite(d_arr) & np.isfinite(w)
    if not np.any(ok):
        raise BadInputError("Sprague-Geers: the histories have no finite sample in common")
    s_arr, d_arr, w = s_arr[ok], d_arr[ok], w[ok]
    psi_mm = float(np.sum(w * d_arr * d_arr))
    psi_cc = float(np.sum(w * s_arr * s_arr))
    psi_mc = float(np.sum(w * s_arr * d_arr))
    if psi_mm == 0.0 or psi_cc == 0.0:
        return SpragueGeers(float("nan"), float("nan"), float("nan"))
    m = math.sqrt(psi_cc / psi_mm) - 1.0
    p = math.acos(max(-1.0, min(1.0, psi_mc / math.sqrt(psi_mm * psi_cc)))) / math.pi
    return SpragueGeers(m, p, math.hypot(m, p))


def area_validation_metric(s: np.ndarray, d: np.ndarray) -> float:
    """Area between the empirical cumulative distribution functions of ``S`` and ``D``.

    ``d = integral |F_S(x) - F_D(x)| dx`` [units of the inputs] (Ferson et al. 2008). It is 0 only
    for identical distributions; for two point masses it is their distance, and shifting a
    distribution by ``c`` gives ``|c|``. ``S`` and ``D`` may have different sizes; NaNs are
    dropped.
    """
    a = np.sort(np.asarray(s, dtype=float).ravel())
    b = np.sort(np.asarray(d, dtype=float).ravel())
    a = a[np.isfinite(a)]
    b = b[np.isfinite(b)]
    if a.size == 0 or b.size == 0:
        raise BadInputError("area validation metric: both samples need at least one finite value")
    x = np.union1d(a, b)
    fa = np.searchsorted(a, x, side="right") / a.size
    fb = np.searchsorted(b, x, side="right") / b.size
    return float(np.sum(np.abs(fa - fb)[:-1] * np.diff(x)))


@dataclass(frozen=True)
class VV20:
    """ASME V&V 20 validation of one scalar quantity (same units for every field).

    Attributes
    ----------
    S, D : float
        Simulated and measured values.
    E : float
        Comparison error ``S - D``.
    u_num, u_input, u_D : float
        Standard uncertainties: numerical, input-parameter, measurement.
    u_val : float
        ``sqrt(u_num^2 + u_input^2 + u_D^2)``.
    k : float
        Coverage factor.
    U_val : float
        ``k u_val``.
    passed : bool
        ``|E| <= U_val``: the model error is not distinguishable from the validation
        uncertainty at this level.
    """

    S: float
    D: float
    E: float
    u_num: float
    u_input: float
    u_D: float
    u_val: float
    k: float
    U_val: float
    passed: bool


def vv20(
    s: float,
    d: float,
    *,
    u_num: float = 0.0,
    u_input: float = 0.0,
    u_d: float = 0.0,
    k: float = 2.0,
) -> VV20:
    """Validation comparison of ASME V&V 20: ``E = S - D`` against ``U_val = k u_val``.

    Parameters
    ----------
    s, d : float
        Simulated and measured value [same unit].
    u_num, u_input, u_d : float
        Standard uncertainties (numerical, input, measurement) [same unit], >= 0.
    k : float
        Coverage factor (2 for about 95 % with a normal distribution).

    Returns
    -------
    VV20
        ``passed`` is ``|E| <= U_val``.
    """
    for name, value in (("u_num", u_num), ("u_input", u_input), ("u_D", u_d), ("k", k)):
        if not (np.isfinite(value) and value >= 0):
            raise BadInputError(f"V&V 20: {name} must be a finite number >= 0, got {value!r}")
    e = float(s) - float(d)
    u_val = math.sqrt(u_num**2 + u_input**2 + u_d**2)
    big_u = k * u_val
    return VV20(
        float(s),
        float(d),
        e,
        float(u_num),
        float(u_input),
        float(u_d),
        u_val,
        float(k),
        big_u,
        bool(abs(e) <= big_u),
    )


def detectable_error(
    d: float, s: float, *, u_fixed: float, u_relative: float, k: float
) -> tuple[float, float]:
    """The resolution of a V&V 20 criterion: the relative errors at which ``|E| = U_val``.

    The budget is ``u_val(S')**2 = u_fixed**2 + (b |S'|)**2`` with ``b = u_relative / |S|``:
    the part ``u_relative`` of the compared budget is applied relative to the simulated value
    ``s`` (a user-stated ``rel·|S|``, a relative verification u_num), so a model predicting
    ``S' = D (1 + e)`` carries ``b |D (1 + e)|``; the rest (``u_D``, an ensemble's spread, the
    simulation's own ``_u``) is fixed. With ``alpha = k u_fixed / |D|`` and ``beta = k b``,
    ``|E| = U_val`` is ``e**2 = alpha**2 + beta**2 (1 + e)**2``, a quadratic in ``e``.

    Parameters
    ----------
    d, s : float
        Measured and simulated value [units of the quantity].
    u_fixed, u_relative : float
        The fixed and the relative-to-S parts of u_val at ``s`` (standard uncertainties,
        ``u_val**2 = u_fixed**2 + u_relative**2``) [units of the quantity].
    k : float
        Coverage factor [1].

    Returns
    -------
    (float, float)
        ``(low, high)`` relative errors ``(S' - D) / |D|`` [1]: errors in ``(low, high)`` pass,
        errors outside fail. ``low`` is ``-inf`` when no under-prediction down to ``S' = 0`` is
        detectable, ``high`` ``inf`` when no over-prediction is (``beta >= 1``); NaN when
        ``d`` is 0 or a value is not finite.

    Examples
    --------
    A fixed budget is symmetric, ``±k u_val / |D|``:

    >>> [round(e, 4) for e in detectable_error(10.0, 10.0, u_fixed=1.0, u_relative=0.0, k=2.0)]
    [-0.2, 0.2]

    u_input = 20 % of S: over-predictions carry more uncertainty, the band is asymmetric:

    >>> [round(e, 4) for e in detectable_error(10.0, 10.0, u_fixed=0.0, u_relative=2.0, k=2.0)]
    [-0.2857, 0.6667]
    """
    values = (d, s, u_fixed, u_relative, k)
    if not all(np.isfinite(v) for v in values) or d == 0:
        return float("nan"), float("nan")
    alpha = k * u_fixed / abs(d)
    beta = k * u_relative / abs(s) if s != 0 else 0.0
    # (1 - beta^2) e^2 - 2 beta^2 e - (alpha^2 + beta^2) = 0
    roots = np.roots([1.0 - beta**2, -2.0 * beta**2, -(alpha**2 + beta**2)])
    real = [float(r.real) for r in np.atleast_1d(roots) if abs(r.imag) <= 1e-12 * (1 + abs(r))]
    low = max((r for r in real if -1.0 <= r < 0.0), default=-math.inf)
    high = min((r for r in real if r > 0.0), default=math.inf)
    if alpha == 0 and beta == 0:
        low = high = 0.0
    return low, high


def wrap_angle_deg(angle_deg: float | np.ndarray) -> float | np.ndarray:
    """Wrap an angle difference to (-180, 180] degree."""
    out = -((-np.asarray(angle_deg, dtype=float) + 180.0) % 360.0) + 180.0
    return float(out) if np.ndim(out) == 0 else out


def max_location(
    field: np.ndarray, z: np.ndarray, theta_deg: np.ndarray
) -> tuple[float, float, float]:
    """Value and location ``(value, z, theta_deg)`` of the maximum of a ``(z, theta)`` field.

    The angle is refined by a periodic parabola through the maximum and its two neighbours in
    its layer (sub-grid location, so a rotation that is not a multiple of the grid step is
    still recovered); ``z`` is the layer of the maximum.
    """
    f = np.asarray(field, dtype=float)
    if f.ndim != 2 or f.shape != (len(z), len(theta_deg)):
        raise BadInputError(
            f"field of shape {f.shape} does not match (z, theta) = ({len(z)}, {len(theta_deg)})"
        )
    if not np.any(np.isfinite(f)):
        raise BadInputError("the field has no finite value")
    i, j = np.unravel_index(np.nanargmax(f), f.shape)
    n = f.shape[1]
    th = float(theta_deg[j])
    value = float(f[i, j])
    if n >= 3:
        ym, y0, yp = f[i, (j - 1) % n], f[i, j], f[i, (j + 1) % n]
        den = ym - 2 * y0 + yp
        step = float(np.median(np.diff(theta_deg))) if n > 1 else 0.0
        if np.isfinite(den) and den < 0:
            delta = 0.5 * (ym - yp) / den
            th = float((th + delta * step) % 360.0)
            value = float(y0 - 0.25 * (ym - yp) * delta)
    return value, float(z[i]), th


def worn_volume(field: np.ndarray, z: np.ndarray, theta_deg: np.ndarray, radius: float) -> float:
    """Worn volume ``R * integral h dtheta dz`` over the grid [m^3].

    Trapezoid rule in ``z`` over the given layers (so the integral covers ``[z_min, z_max]``),
    periodic rectangle rule in ``theta`` (uniform grid over the full circle). First order in
    ``h / R``. ``radius`` is the unworn bore radius [m]; NaN gives NaN.
    """
    f = np.nan_to_num(np.asarray(field, dtype=float), nan=0.0)
    dtheta = 2 * math.pi / len(theta_deg)
    per_layer = f.sum(axis=1) * dtheta * radius
    if len(z) == 1:
        return float("nan")
    return float(np.trapezoid(per_layer, np.asarray(z, dtype=float)))


def lsq_cylindricity(field: np.ndarray, z: np.ndarray, theta_deg: np.ndarray) -> float:
    """Least-squares cylindricity (LSCY, limacon model) of a radial-deviation field [m].

    The bore radius is ``R + h(z, theta)``; a least-squares cylinder (radius, centre offset and
    tilt: ``a0 + (a1 + a2 z) cos(theta) + (b1 + b2 z) sin(theta)``) is removed and the peak-to-
    valley of the residual returned. Independent of the angle convention (the cosine/sine pair
    spans the same functions in any convention).
    """
    f = np.asarray(field, dtype=float)
    zz, tt = np.meshgrid(np.asarray(z, dtype=float), np.deg2rad(theta_deg), indexing="ij")
    ok = np.isfinite(f)
    c, s = np.cos(tt[ok]), np.sin(tt[ok])
    zk = zz[ok]
    a = np.column_stack([np.ones_like(c), c, zk * c, s, zk * s])
    coef, *_ = np.linalg.lstsq(a, f[ok], rcond=None)
    res = f[ok] - a @ coef
    return float(res.max() - res.min())
