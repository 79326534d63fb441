"""Numerical uncertainty from a refinement study: the least-squares procedure of Eça & Hoekstra.

A refinement study repeats a computation with a refinement parameter ``h`` made finer (here the
wear-update interval ΔN) and records the quantities of interest. In a chaotic simulation one
run per level is not enough: each level is run several times (replicates starting at different
phases of the motion) and the procedure works on the replicate *means* ``phi_i`` with their
standard errors ``s_i``.

Procedure (Eça & Hoekstra, J. Comput. Phys. 262 (2014) 104-130; sections 3 and 4, summarised
step by step in their Appendix A), for ``n_g >= 4`` levels sorted finest first:

1. **Error estimate** (sec. 3.1-3.2). Least-squares fits of the power series
   ``phi_i = phi_0 + alpha h_i^p`` (``delta_RE``, observed order ``p``), each with two weightings,
   the unweighted one and ``w_i ∝ 1/h_i`` (the paper's weighted fit, which favours the fine
   levels); with replicate standard errors both are further weighted by ``1/s_i^2`` (the
   statistically correct weights of means with different scatter). Each fit has the standard
   deviation ``U_s = sqrt(sum n_g w_i r_i^2 / (n_g - n_par))`` (``sum w_i = 1``); of the two
   weightings the one with the smaller ``U_s`` is kept.

   * ``0.5 <= p < 1.05 p_formal`` (the paper's ``0.5 <= p < 2.1`` for a formally second-order
     method; here ΔN enters an explicit Euler update, formal order 1): the error estimate is
     ``eps = |phi_fit(h_1) - phi_0|`` of this fit, safety factor ``Fs = 1.25``;
   * ``p >= 1.05 p_formal``: fits with the order fixed (``delta_1``, and ``delta_2`` for a
     second-order method: every whole order up to the formal one), ``Fs = 3``;
   * ``p < 0.5``: fits with fixed orders ``delta_1``, ``delta_2`` and
     ``delta_12 = alpha_1 h + alpha_2 h^2``, ``Fs = 3``;

   among the fixed-order fits (both weightings each) the one with the smallest ``U_s`` is used.
2. **Data range parameter** (sec. 4): ``Delta_phi = (max phi_i - min phi_i) / (n_g - 1)``.
3. **Uncertainty** of the finest level (sec. 4, Appendix A steps 3-4):
   ``U_phi = Fs eps + U_s + |phi_1 - phi_fit(h_1)|`` when ``U_s < Delta_phi``; otherwise the data
   are too scattered for the fit to be trusted (``Fs = 3`` whatever ``p``) and
   ``U_phi = 3 U_s / Delta_phi (eps + U_s + |phi_1 - phi_fit(h_1)|)``.

``U_phi`` is meant to bound the error with about 95 % coverage; the standard uncertainty of the
refinement is ``u_refinement = U_phi / 2`` (k = 2, :data:`COVERAGE_K`: the project's one rule for
every numerical-uncertainty bound, also the GCI of :mod:`jointwear.compare.verification`). The statistical part is the standard error of
the finest level's mean, ``u_stat = s_1``; a grid term ``u_grid`` is added by the caller (a run at
the next grid, :func:`study_uncertainty`) and ``u_num^2 = u_stat^2 + u_refinement^2 + u_grid^2``
(k = 1). Identical solutions at every level mean that the refinement parameter is inert (it does
not change the computation): *not assessed*, never zero.

References
----------
- Eça, L., Hoekstra, M. (2014). A procedure for the estimation of the numerical uncertainty of
  CFD calculations based on grid refinement studies. *J. Comput. Phys.* 262, 104-130.
- Roache, P. J. (1998). *Verification and Validation in Computational Science and
  Engineering*. Hermosa (the two-grid GCI with ``Fs = 3`` used for the grid term).
- ASME V&V 20-2009 (R2021): ``u_num`` as a standard uncertainty.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

import numpy as np
import xarray as xr

from jointwear.errors import BadInputError

__all__ = [
    "RefinementFit",
    "eca_hoekstra",
    "grid_term",
    "study_uncertainty",
    "location_jump",
    "level_statistics",
    "COVERAGE_K",
    "P_LOW",
    "P_HIGH_FACTOR",
]

#: The one rule converting a numerical-uncertainty *bound* to a standard uncertainty: a bound
#: meant to cover the error with about 95 % (Eça & Hoekstra's U_phi, Roache's GCI with its Fs,
#: the two-grid term) is an expanded uncertainty with k = 2 (JCGM 100:2008, the GUM, 6.3.3 and
#: G.1.3: about 95 % for a normal distribution; Eça & Hoekstra 2014 build U_phi as such a 95 %
#: bound, as Roache's GCI). ASME V&V 20-2009 2-4.1 also offers GCI / 1.15 for Fs = 1.25; it is
#: not used: two factors for the same bound made four levels (U_phi / 2) give a u_num 1.74x
#: smaller than three (GCI / 1.15) of the same data, and it says nothing for Fs = 3.
COVERAGE_K = 2.0
#: Lower bound of a credible observed order (Eça & Hoekstra 2014, sec. 4).
P_LOW = 0.5
#: Upper bound of a credible observed order relative to the formal order (2.1 / 2 in the paper).
P_HIGH_FACTOR = 1.05
#: Safety factors of the paper: credible order / everything else.
FS_CREDIBLE, FS_OTHER = 1.25, 3.0

_NAN = float("nan")


@dataclass(frozen=True)
class RefinementFit:
    """Numerical uncertainty of one quantity from a refinement study (Eça & Hoekstra 2014).

    Attributes
    ----------
    quantity : str
        Name of the quantity.
    assessed : bool
        False: ``reason`` says why, the uncertainties are NaN.
    reason : str
        Why it is not assessed ('' when it is; notes otherwise, e.g. about the grid term).
    branch : str
        The branch of the procedure taken and why.
    h : tuple of float
        Refinement parameter per level, finest first.
    means, sems : tuple of float
        Replicate mean and its standard error per level [unit of the quantity].
    value : float
        Best estimate: the finest level's mean [unit].
    extrapolated : float
        ``phi_0`` of the fit used (NaN if none) [unit].
    order, order_sd : float
        Observed order ``p`` of the ``delta_RE`` fit and its standard deviation [1].
    safety_factor : float
        ``Fs`` of the branch.
    u_stat, u_refinement, u_grid, u_num : float
        Standard uncertainties (k = 1, absolute) [unit]: statistical, refinement (U_phi / 2),
        grid (NaN when not included) and their root sum of squares (the grid term included
        only when it is finite; see ``reason``). They are the uncertainty of ``value``, the
        *mean* of the finest level's replicates.
    sd_run : float
        Standard deviation of a single run at the finest level (replicate scatter) [unit]; 0
        for deterministic solutions, NaN when the replicate counts are not known.
    u_num_run : float
        u_num of a *single* run at the finest level (what a comparison of one simulated run
        needs): ``sqrt(sd_run^2 + u_refinement^2 + u_grid^2)`` [unit].
    """

    quantity: str
    assessed: bool
    reason: str
    branch: str
    h: tuple[float, ...]
    means: tuple[float, ...]
    sems: tuple[float, ...]
    value: float
    extrapolated: float
    order: float
    order_sd: float
    safety_factor: float
    u_stat: float
    u_refinement: float
    u_grid: float
    u_num: float
    sd_run: float = _NAN
    u_num_run: float = _NAN

    def describe(self) -> str:
        """One line for the report: value, u_num and its parts, or why it is not assessed."""
        seq = " → ".join(f"{v:.4g}" for v in self.means[::-1])
        if not self.assessed:
            return f"{self.quantity}: not assessed - {self.reason} (coarse to fine: {seq})"
        grid = f"{self.u_grid:.3g}" if math.isfinite(self.u_grid) else "not included"
        note = f"; {self.reason}" if self.reason else ""
        return (
            f"{self.quantity} = {self.value:.6g}, u_num = {self.u_num:.3g} (k = 1; u_stat "
            f"{self.u_stat:.3g}, u_refinement {self.u_refinement:.3g}, u_grid {grid}); "
            f"Eça-Hoekstra: {self.branch}, p = {self.order:.2f} ± {self.order_sd:.2g}"
            f"{note} (coarse to fine: {seq})"
        )

    def with_grid(self, u_grid: float, note: str = "") -> RefinementFit:
        """The same fit with the grid term ``u_grid`` [unit] added to ``u_num``.

        A NaN ``u_grid`` (grid term not assessed) makes the whole fit *not assessed* with
        ``note`` as the reason: a missing part of u_num is never taken as zero.
        """
        if not self.assessed:
            return replace(self, u_grid=u_grid)
        if not math.isfinite(u_grid):
            return replace(
                self,
                assessed=False,
                reason=note or "the grid term is not assessed",
                u_grid=_NAN,
                u_num=_NAN,
                u_num_run=_NAN,
            )
        u = math.sqrt(self.u_stat**2 + self.u_refinement**2 + u_grid**2)
        u_run = math.sqrt(self.sd_run**2 + self.u_refinement**2 + u_grid**2)
        return replace(self, u_grid=float(u_grid), u_num=u, u_num_run=u_run, reason=note)


@dataclass(frozen=True)
class _Fit:
    """One least-squares fit: model name, parameters, fitted values, U_s."""

    model: str  # "p", "1", "2", "12"
    phi0: float
    coef: tuple[float, ...]
    order: float
    fitted: np.ndarray
    std: float
    weights: np.ndarray
    weighting: str


def _weightings(h: np.ndarray, sems: np.ndarray | None) -> list[tuple[str, np.ndarray]]:
    """The two weightings of the paper (uniform, 1/h), times 1/s^2 with standard errors."""
    stat = np.ones_like(h) if sems is None else 1.0 / sems**2
    out = []
    for name, w in (("unweighted", np.ones_like(h)), ("weighted 1/h", 1.0 / h)):
        w = w * stat
        out.append((name + (" x 1/s²" if sems is not None else ""), w / w.sum()))
    return out


def _std(residual: np.ndarray, w: np.ndarray, n_par: int) -> float:
    n = residual.size
    return math.sqrt(float(np.sum(n * w * residual**2)) / (n - n_par))


def _linear(x: np.ndarray, phi: np.ndarray, w: np.ndarray, columns: list[np.ndarray]):
    a = np.column_stack([np.ones_like(x), *columns])
    sw = np.sqrt(w)
    coef, *_ = np.linalg.lstsq(a * sw[:, None], phi * sw, rcond=None)
    return coef, a @ coef


def _fit_fixed(model: str, x: np.ndarray, phi: np.ndarray, w: np.ndarray, name: str) -> _Fit:
    cols = {"1": [x], "2": [x**2], "12": [x, x**2]}[model]
    coef, fitted = _linear(x, phi, w, cols)
    order = {"1": 1.0, "2": 2.0, "12": 1.0}[model]
    return _Fit(
        model,
        float(coef[0]),
        tuple(map(float, coef[1:])),
        order,
        fitted,
        _std(phi - fitted, w, len(coef)),
        w,
        name,
    )


#: Search range of the observed order (the fit's p is bounded to it).
P_RANGE = (0.01, 10.0)


def _fit_power(x: np.ndarray, phi: np.ndarray, w: np.ndarray, name: str) -> _Fit:
    """phi = phi0 + alpha x^p: linear in (phi0, alpha) for fixed p; p by a bounded 1-D search."""
    from scipy.optimize import minimize_scalar

    def sse(p: float) -> float:
        _, fitted = _linear(x, phi, w, [x**p])
        return float(np.sum(w * (phi - fitted) ** 2))

    grid = np.geomspace(*P_RANGE, 121)
    k = int(np.argmin([sse(p) for p in grid]))
    lo, hi = grid[max(k - 1, 0)], grid[min(k + 1, grid.size - 1)]
    p = float(grid[k])
    if hi > lo:
        res = minimize_scalar(sse, bounds=(lo, hi), method="bounded", options={"xatol": 1e-10})
        if res.fun <= sse(p):
            p = float(res.x)
    coef, fitted = _linear(x, phi, w, [x**p])
    return _Fit(
        "p", float(coef[0]), (float(coef[1]),), p, fitted, _std(phi - fitted, w, 3), w, name
    )


def _order_sd(fit: _Fit, x: np.ndarray, phi: np.ndarray, sems: np.ndarray | None) -> float:
    """Standard deviation of the observed order from the fit's Jacobian (linearised).

    With standard errors: covariance ``(J' S^-1 J)^-1`` scaled by the reduced chi-square when
    the fit is worse than the scatter allows; without: ``(J' J)^-1 U_s^2``.
    """
    alpha, p = fit.coef[0], fit.order
    jac = np.column_stack([np.ones_like(x), x**p, alpha * x**p * np.log(x)])
    r = phi - fit.fitted
    dof = x.size - 3
    if sems is not None:
        wts = 1.0 / sems**2
        scale = max(1.0, float(np.sum(wts * r**2)) / dof)
    else:
        wts = np.ones_like(x)
        scale = float(np.sum(r**2)) / dof
    try:
        cov = np.linalg.inv(jac.T @ (jac * wts[:, None])) * scale
    except np.linalg.LinAlgError:
        return math.inf
    v = float(cov[2, 2])
    return math.sqrt(v) if v >= 0 and math.isfinite(v) else math.inf


def _best(fits: list[_Fit]) -> _Fit:
    return min(fits, key=lambda f: f.std)


def _not_assessed(quantity, reason, h, m, s, *, branch="", order=_NAN, order_sd=_NAN):
    value = float(m[0]) if len(m) else _NAN
    return RefinementFit(
        quantity,
        False,
        reason,
        branch,
        tuple(map(float, h)),
        tuple(map(float, m)),
        tuple(map(float, s)),
        value,
        _NAN,
        order,
        order_sd,
        _NAN,
        _NAN,
        _NAN,
        _NAN,
        _NAN,
    )


def _check(h, means, sems, quantity):
    h_arr = np.asarray(h, dtype=float)
    m_arr = np.asarray(means, dtype=float)
    if h_arr.ndim != 1 or h_arr.shape != m_arr.shape:
        raise BadInputError(
            f"refinement study of {quantity}: {h_arr.size} refinement values for {m_arr.size} "
            "means; give one mean per level"
        )
    if sems is None:
        s_arr = np.full(h_arr.shape, np.nan)
    else:
        s_arr = np.asarray(sems, dtype=float)
        if s_arr.shape != h_arr.shape:
            raise BadInputError(
                f"refinement study of {quantity}: {s_arr.size} standard errors for "
                f"{h_arr.size} levels"
            )
        if np.any(s_arr[np.isfinite(s_arr)] < 0):
            raise BadInputError(f"refinement study of {quantity}: a standard error is negative")
    if not np.all(np.isfinite(h_arr)) or np.any(h_arr <= 0):
        raise BadInputError(
            f"refinement study of {quantity}: the refinement parameter h must be finite and "
            f"> 0, got {h_arr.tolist()}"
        )
    if np.unique(h_arr).size != h_arr.size:
        raise BadInputError(
            f"refinement study of {quantity}: two levels share the refinement value; each "
            f"level needs its own h (got {h_arr.tolist()})"
        )
    order = np.argsort(h_arr)
    return h_arr[order], m_arr[order], s_arr[order]


def _error_estimate(h_arr, m_arr, s_fit, formal_order: float):
    """Eça-Hoekstra fit and error estimate: (fit, order p, its sd, Fs, u_refinement, branch)."""
    x = h_arr / h_arr[0]
    weightings = _weightings(x, s_fit)
    power = _best([_fit_power(x, m_arr, w, name) for name, w in weightings])
    p = power.order
    p_sd = _order_sd(power, x, m_arr, s_fit)
    p_high = P_HIGH_FACTOR * formal_order
    if P_LOW <= p < p_high:
        fit, fs = power, FS_CREDIBLE
        branch = f"p credible ({P_LOW:g} <= p < {p_high:.3g})"
    else:
        if p >= p_high:
            models = [str(k) for k in (1, 2) if k <= max(1.0, formal_order)]
            why = f"p >= {p_high:.3g}"
        else:
            models = ["1", "2", "12"]
            why = f"p < {P_LOW:g}"
        fit = _best([_fit_fixed(m, x, m_arr, w, n) for m in models for n, w in weightings])
        fs = FS_OTHER
        label = {"1": "order 1", "2": "order 2", "12": "orders 1 and 2"}[fit.model]
        branch = f"{why}: fit with fixed {label}"
    eps = abs(float(fit.fitted[0]) - fit.phi0)
    resid1 = abs(float(m_arr[0] - fit.fitted[0]))
    data_range = float(np.ptp(m_arr)) / (m_arr.size - 1)
    if fit.std < data_range:
        big_u = fs * eps + fit.std + resid1
        branch += f": Fs = {fs:g}"
    else:
        fs = FS_OTHER
        ratio = fit.std / data_range
        big_u = fs * ratio * (eps + fit.std + resid1)
        branch = (
            f"scattered (U_s >= data range parameter): data range x 3 "
            f"(U = 3 U_s/Δφ (ε + U_s + |φ1 - fit|), U_s/Δφ = {ratio:.3g}; fit: {branch})"
        )
    u_ref = big_u / COVERAGE_K
    branch += f" [{fit.weighting}]"
    return fit, p, p_sd, fs, u_ref, branch


def eca_hoekstra(
    h: Sequence[float],
    means: Sequence[float],
    sems: Sequence[float] | None = None,
    *,
    formal_order: float = 1.0,
    quantity: str = "quantity",
    resolution: float = 0.0,
    counts: Sequence[int] | None = None,
) -> RefinementFit:
    """Numerical uncertainty of the finest level by the least-squares procedure of Eça & Hoekstra.

    Parameters
    ----------
    h : sequence of float
        Refinement parameter of each level (> 0, smaller is finer; any order), e.g. the
        wear-update interval ΔN [cycles].
    means : sequence of float
        The quantity at each level (replicate mean) [unit]; a NaN level (failed runs) is left
        out.
    sems : sequence of float, optional
        Standard error of each mean [unit] (from the replicates). The fits are then weighted by
        ``1/s^2`` and ``u_stat`` is the finest level's standard error. None: the solutions are
        deterministic (one exact run per level), ``u_stat = 0`` - do not pass None for
        replicate means of a chaotic simulation.
    formal_order : float
        Formal order of the discretisation in ``h`` (1 for the explicit Euler update in ΔN);
        sets the upper bound ``1.05 formal_order`` of a credible observed order.
    quantity : str
        Name used in messages.
    resolution : float
        Step in which the quantity moves, if it is quantised (the location of the deepest wear
        moves from grid point to grid point) [unit]; 0 for a continuous quantity. Identical
        solutions at every level then mean "no change within one step":
        ``u_refinement = resolution / sqrt(12)`` (uniform over one step) instead of *inert*.
    counts : sequence of int, optional
        Replicates per level (gives ``sd_run = s_1 sqrt(n_1)`` and ``u_num_run``).

    Returns
    -------
    RefinementFit
        ``u_grid`` is NaN (not included); :meth:`RefinementFit.with_grid` adds a grid term.
        Not assessed (with the reason) with fewer than four usable levels, with a NaN standard
        error at the finest level, or when the refinement parameter is inert (identical
        solutions at every level).

    Raises
    ------
    BadInputError
        Mismatched lengths, ``h <= 0``, repeated ``h``, negative standard errors.
    """
    if not (isinstance(formal_order, (int, float)) and formal_order > 0):
        raise BadInputError(f"formal_order must be > 0, got {formal_order!r}")
    h_arr, m_arr, s_arr = _check(h, means, sems, quantity)
    n_arr = np.full(h_arr.shape, np.nan)
    if counts is not None:
        n_arr = np.asarray(counts, dtype=float)[np.argsort(np.asarray(h, dtype=float))]
    deterministic = sems is None
    keep = np.isfinite(m_arr) & (deterministic | np.isfinite(s_arr))
    if not keep[0]:
        return _not_assessed(
            quantity,
            f"the finest level (h = {h_arr[0]:g}) has no value or standard error (its runs "
            "failed or fewer than two succeeded): the uncertainty would be that of another level",
            h_arr,
            m_arr,
            s_arr,
        )
    dropped = int(np.sum(~keep))
    h_arr, m_arr, s_arr, n_arr = h_arr[keep], m_arr[keep], s_arr[keep], n_arr[keep]
    sd_run = 0.0 if deterministic else (float(s_arr[0] * np.sqrt(n_arr[0])) if len(s_arr) else _NAN)
    note = (
        f"{dropped} level(s) without a value (or, with replicates, a standard error: fewer than "
        "two runs ok) left out"
        if dropped
        else ""
    )
    if h_arr.size < 4:
        return _not_assessed(
            quantity,
            f"{h_arr.size} usable refinement level(s): the least-squares procedure needs at "
            "least 4 (three fit parameters and a standard deviation)"
            + (f"; {note}" if note else ""),
            h_arr,
            m_arr,
            s_arr,
        )
    if np.ptp(m_arr) == 0 and resolution > 0:
        u_ref = resolution / math.sqrt(12.0)
        u_stat = 0.0 if deterministic or not np.isfinite(s_arr[0]) else float(s_arr[0])
        return RefinementFit(
            quantity,
            True,
            note,
            f"no change with h at any level (quantised in steps of {resolution:.4g}): "
            "u_refinement = step/√12",
            tuple(map(float, h_arr)),
            tuple(map(float, m_arr)),
            tuple(map(float, s_arr)),
            float(m_arr[0]),
            float(m_arr[0]),
            _NAN,
            _NAN,
            _NAN,
            u_stat,
            u_ref,
            _NAN,
            math.hypot(u_stat, u_ref),
            sd_run,
            math.hypot(sd_run, u_ref),
        )
    if np.ptp(m_arr) == 0:
        return _not_assessed(
            quantity,
            "identical solutions at every level: the refinement parameter is inert (it does not "
            "change the computation) and cannot measure its numerical error",
            h_arr,
            m_arr,
            s_arr,
        )
    # a level whose replicates agree exactly carries no weight information: no weighting
    s_fit = None if deterministic or not np.all(s_arr > 0) else s_arr
    u_stat = 0.0 if deterministic else float(s_arr[0])
    fit, p, p_sd, fs, u_ref, branch = _error_estimate(h_arr, m_arr, s_fit, formal_order)
    notes = [note] if note else []
    if deterministic:
        notes.append("deterministic solutions (no standard errors): u_stat = 0")
    return RefinementFit(
        quantity,
        True,
        "; ".join(notes),
        branch,
        tuple(map(float, h_arr)),
        tuple(map(float, m_arr)),
        tuple(map(float, s_arr)),
        float(m_arr[0]),
        fit.phi0,
        p,
        p_sd,
        fs,
        u_stat,
        u_ref,
        _NAN,
        math.sqrt(u_stat**2 + u_ref**2),
        sd_run,
        math.sqrt(sd_run**2 + u_ref**2),
    )


def level_statistics(
    values: np.ndarray, *, period: float | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Mean, standard error and count of replicates along the last axis (NaN runs left out).

    Parameters
    ----------
    values : ndarray (..., replicate)
        Replicate values [unit].
    period : float, optional
        Period of a circular quantity (360 for an angle in degrees): the replicates are
        unwrapped around their circular mean before averaging, the mean is wrapped to
        ``[0, period)``.

    Returns
    -------
    (mean, sem, n) : ndarrays (...)
        ``sem`` is NaN with fewer than two replicates.
    """
    v = np.asarray(values, dtype=float)
    if period:
        ang = 2 * np.pi * v / period
        ref = np.angle(np.nanmean(np.exp(1j * ang), axis=-1, keepdims=True))
        ref = np.where(np.isfinite(ref), ref, 0.0) * period / (2 * np.pi)
        v = ref + (v - ref + period / 2) % period - period / 2
    n = np.sum(np.isfinite(v), axis=-1)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = np.nansum(np.where(np.isfinite(v), v, 0.0), axis=-1) / n
        dev = np.where(np.isfinite(v), v - mean[..., None], 0.0)
        sd = np.sqrt(np.sum(dev**2, axis=-1) / (n - 1))
        sem = np.where(n > 1, sd / np.sqrt(n), np.nan)
    mean = np.where(n > 0, mean, np.nan)
    if period:
        mean = mean % period
    return mean, sem, n


def grid_term(
    base: tuple[float, float],
    finer: tuple[float, float],
    *,
    ratio: float,
    order: float = 1.0,
    period: float | None = None,
) -> float:
    """Standard uncertainty of the grid from one run (replicate mean) at the next grid.

    Two grids cannot show an order, so Roache's two-grid estimate with ``Fs = 3`` and the
    assumed ``order`` is used: ``U = 3 |d| / (r^p - 1)`` with the difference ``d`` of the two
    means, whose own scatter is added in quadrature (``d^2 + s_base^2 + s_finer^2``), and
    ``u_grid = U / 2``.

    Parameters
    ----------
    base, finer : (mean, sem)
        The quantity on the study's grid and on the finer grid, same refinement level [unit].
    ratio : float
        Grid refinement ratio ``r > 1`` (cell size of the base over the finer grid).
    order : float
        Assumed order of the grid error.
    period : float, optional
        Period of a circular quantity (the difference is wrapped).
    """
    (mb, sb), (mf, sf) = base, finer
    if not ratio > 1:
        raise BadInputError(f"grid refinement ratio must be > 1, got {ratio!r}")
    if not all(math.isfinite(v) for v in (mb, mf)):
        return _NAN
    d = mf - mb
    if period:
        d = (d + period / 2) % period - period / 2
    spread = sum(v * v for v in (sb, sf) if math.isfinite(v))
    return FS_OTHER * math.sqrt(d * d + spread) / (ratio**order - 1) / COVERAGE_K


def _replicate_values(study: xr.Dataset, quantity: str, fn) -> tuple[np.ndarray, np.ndarray]:
    if fn is None:
        lv = study["replicate_value"].sel(quantity=quantity).transpose("level", "replicate")
        gv = study["grid_replicate_value"].sel(quantity=quantity)
        return np.asarray(lv.values, dtype=float), np.asarray(gv.values, dtype=float)
    runs = study["wear_depth_run"].transpose("level", "replicate", "z", "theta")
    lv = np.array(
        [
            [_apply(fn, runs.isel(level=i, replicate=j)) for j in range(runs.sizes["replicate"])]
            for i in range(runs.sizes["level"])
        ]
    )
    if "wear_depth_grid_run" in study:
        g = study["wear_depth_grid_run"].transpose("grid_replicate", "z_grid", "theta_grid")
        g = g.rename(z_grid="z", theta_grid="theta")
        gv = np.array(
            [_apply(fn, g.isel(grid_replicate=k)) for k in range(g.sizes["grid_replicate"])]
        )
    else:
        gv = np.array([])
    return lv, gv


def _apply(fn: Callable[[xr.DataArray], float], wear: xr.DataArray) -> float:
    if not bool(np.all(np.isfinite(wear.values))):
        return _NAN  # a failed run
    return float(fn(wear))


def study_uncertainty(
    study: xr.Dataset,
    quantity: str,
    fn: Callable[[xr.DataArray], float] | None = None,
) -> RefinementFit:
    """u_num of a quantity from a verification study file (``jointwear sim verify``).

    Parameters
    ----------
    study : Dataset
        The study (``jointwear_file = "verification_study"``).
    quantity : str
        Name of the quantity: one of the study's ``quantity`` values when ``fn`` is None, else
        the name given to ``fn``'s result.
    fn : callable, optional
        Applied to every stored run's final wear map (DataArray ``wear_depth`` over ``z``,
        ``theta`` [m]; a grid run's map on its own coordinates) - e.g. a quantity computed
        within the measured band; its result's unit is the caller's.

    Returns
    -------
    RefinementFit
        With the grid term from the grid runs; not assessed when the grid term cannot be.
    """
    if study.attrs.get("jointwear_file") != "verification_study":
        raise BadInputError(
            "not a verification study (attribute jointwear_file = "
            f"{study.attrs.get('jointwear_file')!r}); make one with 'jointwear sim verify'"
        )
    if fn is None and quantity not in [str(q) for q in study["quantity"].values]:
        raise BadInputError(
            f"verification study: no quantity {quantity!r}; it has "
            f"{', '.join(map(str, study['quantity'].values))} (or pass fn to compute one "
            "from the stored wear maps)"
        )
    period, resolution = None, 0.0
    if fn is None and "quantity_period" in study:
        per = float(study["quantity_period"].sel(quantity=quantity))
        period = per if math.isfinite(per) and per > 0 else None
    if fn is None and "quantity_resolution" in study:
        res = float(study["quantity_resolution"].sel(quantity=quantity))
        resolution = res if math.isfinite(res) and res > 0 else 0.0
    lv, gv = _replicate_values(study, quantity, fn)
    h = np.asarray(study["h"].values, dtype=float)
    if resolution > 0:
        jump = location_jump(lv, gv, h, resolution=resolution, period=period)
        if jump:
            fit = eca_hoekstra(h, np.full(h.size, np.nan), quantity=quantity)
            return replace(fit, reason=jump)
    mean, sem, count = level_statistics(lv, period=period)
    if period:
        mean = _unwrap_levels(mean, h, period)
    fit = eca_hoekstra(
        h,
        mean,
        sem,
        formal_order=float(study.attrs.get("formal_order", 1.0)),
        quantity=quantity,
        resolution=resolution,
        counts=count,
    )
    if gv.size == 0:
        return fit.with_grid(_NAN, "the study has no grid runs: the grid term is not assessed")
    gm, gs, gn = level_statistics(gv, period=period)
    base_level = int(study.attrs.get("grid_level", int(np.argmin(h))))
    bm, bs = float(mean[base_level]), float(sem[base_level])
    if gn == 0:
        return fit.with_grid(_NAN, "every run at the finer grid failed: grid term not assessed")
    u_grid = grid_term(
        (bm, bs),
        (float(gm), float(gs)),
        ratio=float(study.attrs.get("grid_ratio", 2.0)),
        order=float(study.attrs.get("grid_order", 1.0)),
        period=period,
    )
    return fit.with_grid(u_grid, fit.reason)


#: Runs of one level whose location of the maximum differs by more than this many grid steps
#: have their maximum on separate wear peaks.
JUMP_STEPS = 5


def location_jump(
    levels: np.ndarray,
    grid_runs: np.ndarray,
    h: np.ndarray,
    *,
    resolution: float,
    period: float | None = None,
) -> str:
    """Why the location of a maximum is not one quantity, or '' when it is.

    Two wear peaks of nearly equal depth make the location of the maximum jump between them from
    run to run (the reference rig: 124 and 301 degree). Its replicate mean is then a point
    between two peaks, and its scatter no uncertainty of a location: when the runs of one level
    (or the grid runs) differ by more than :data:`JUMP_STEPS` grid steps the quantity is *not
    assessed*.

    Parameters
    ----------
    levels : ndarray (level, replicate)
        Each run's location [unit]; NaN for a failed run.
    grid_runs : ndarray (grid_replicate,)
    h : ndarray (level,)
        Refinement parameter of each level.
    resolution : float
        Grid step of the location [unit].
    period : float, optional
        Period of a circular location (360 degree).
    """
    groups = [
        (f"h = {hv:g}", np.asarray(row, dtype=float)) for hv, row in zip(h, levels, strict=True)
    ]
    groups.append(("the finer grid", np.asarray(grid_runs, dtype=float)))
    for label, v in groups:
        v = v[np.isfinite(v)]
        if v.size < 2:
            continue
        d = v[:, None] - v[None, :]
        if period:
            d = (d + period / 2) % period - period / 2
        i, j = np.unravel_index(np.argmax(np.abs(d)), d.shape)
        if abs(d[i, j]) > JUMP_STEPS * resolution:
            return (
                f"the location of the maximum jumps between separate wear peaks from run to run "
                f"({label}: {v[i]:.4g} and {v[j]:.4g}, more than {JUMP_STEPS} grid steps apart): "
                "it is not one quantity, its mean would lie between the peaks"
            )
    return ""


def _unwrap_levels(mean: np.ndarray, h: np.ndarray, period: float) -> np.ndarray:
    """Level means of a circular quantity made continuous around the finest level's."""
    ref = float(mean[int(np.argmin(h))])
    if not math.isfinite(ref):
        return mean
    return ref + (mean - ref + period / 2) % period - period / 2
