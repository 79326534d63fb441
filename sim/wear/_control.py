"""Update-interval control of the wear loop: noise-aware rate change, interval, accuracy.

The wear loop (:mod:`jointwear.sim.wear`) advances the profile by ``dN`` cycles with the wear
rate measured on the current profile (explicit Euler in the cycle count). This module holds the
pure functions that decide ``dN`` and estimate the error of the result:

* every measurement averages ``m`` single cycles (:func:`sample_rates`); their scatter gives the
  cycle-to-cycle variability of the wear-rate field *on the current profile* (re-estimated at
  every update, never once for the whole run);
* the change of the averaged rate field over an update, ``eta_raw``, contains the noise of both
  averages; the noise part (:func:`change_noise`) is removed in quadrature and changes below the
  detection limit ``2 sigma_eta`` are indistinguishable from noise, so the controller aims at
  ``max(tol, 2 sigma_eta)`` (:func:`effective_tolerance`). dN therefore never falls below the
  interval at which the wear-driven change becomes detectable: no livelock;
* ``m`` is chosen so that the detection limit is at most ``tol`` (:func:`cycles_to_average`),
  bounded by ``max_average_cycles``; if that is not enough the run still finishes, is flagged
  and says how accurate it is;
* the accuracy of the depth field is accumulated along the run (:class:`ErrorBudget`): the
  explicit-Euler truncation ``dN (r_new - r_old) / 2`` per update (signed sum: the systematic
  part adds up, the noise part telescopes) and the statistical error of each averaged rate,
  ``dN^2 var(r_mean)``, added in quadrature over the updates; earlier errors are damped by the
  per-point ratio of new to old rate (wear corrects its own errors).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from jointwear.sim.wear._settings import WearSettings

__all__ = [
    "RateSample",
    "ErrorBudget",
    "sample_rates",
    "rate_change",
    "change_noise",
    "effective_tolerance",
    "cycles_to_average",
    "next_interval",
    "propose_interval",
    "smoothed_noise",
    "COVERAGE",
    "DETECTION_SIGMAS",
    "UNRESOLVED_RATE_CHANGE",
    "PERSISTENT_SHARE",
    "unresolved_updates",
    "convergence_notes",
]

#: Coverage factor of the reported accuracy (expanded uncertainty, about 95 %).
COVERAGE: float = 2.0

#: A rate change is "detected" when it exceeds this many standard deviations of its noise.
DETECTION_SIGMAS: float = 2.0


@dataclass(frozen=True)
class RateSample:
    """The wear rate measured on one profile, averaged over ``n`` single cycles.

    Attributes
    ----------
    rate : ndarray (Nl, Nd)
        Mean wear rate per point [m/cycle].
    var : ndarray (Nl, Nd)
        Variance of that mean per point [(m/cycle)²] (sample variance / n); NaN for n = 1.
    work_rate : float
        Mean normal work per cycle [N m].
    volume_rate : float
        Mean worn-volume rate ``sum(rate * area)`` [m³/cycle].
    volume_var : float
        Variance of the mean volume rate [(m³/cycle)²]; NaN for n = 1.
    rel_noise : float
        Cycle-to-cycle variability of a single cycle's rate field, relative (area-weighted RMS of
        the per-point standard deviation over the RMS rate) [1]; NaN for n = 1.
    n : int
        Number of single cycles averaged.
    """

    rate: np.ndarray
    var: np.ndarray
    work_rate: float
    volume_rate: float
    volume_var: float
    rel_noise: float
    n: int


def sample_rates(
    rates: Sequence[np.ndarray], work_rates: Sequence[float], area: np.ndarray
) -> RateSample:
    """Average single-cycle wear-rate fields [m/cycle] and measure their scatter.

    Parameters
    ----------
    rates : sequence of ndarray (Nl, Nd)
        The wear rate of each single cycle [m/cycle].
    work_rates : sequence of float
        The normal work of each cycle [N m].
    area : ndarray (Nl, Nd)
        Bore area of each point [m²] (weights).
    """
    stack = np.stack([np.asarray(r, dtype=float) for r in rates])
    n = stack.shape[0]
    mean = stack.mean(axis=0)
    vol = np.array([float(np.sum(r * area)) for r in stack])
    if n < 2:
        nan_field = np.full(mean.shape, np.nan)
        return RateSample(
            mean, nan_field, float(np.mean(work_rates)), float(vol[0]), math.nan, math.nan, 1
        )
    var1 = stack.var(axis=0, ddof=1)  # single-cycle variance per point
    ref = float(np.sum(area * mean * mean))
    rel = math.sqrt(float(np.sum(area * var1)) / ref) if ref > 0 else 0.0
    return RateSample(
        rate=mean,
        var=var1 / n,
        work_rate=float(np.mean(work_rates)),
        volume_rate=float(vol.mean()),
        volume_var=float(vol.var(ddof=1)) / n,
        rel_noise=rel,
        n=n,
    )


def rate_change(new: np.ndarray, old: np.ndarray, area: np.ndarray) -> float:
    """``||new - old|| / ||old||`` with the area-weighted L2 norm [1] (inf if old is 0, new not)."""
    ref = math.sqrt(float(np.sum(area * old * old)))
    diff = math.sqrt(float(np.sum(area * (new - old) ** 2)))
    if ref == 0:
        return 0.0 if diff == 0 else math.inf
    return diff / ref


def change_noise(sigma: float, n_new: int, n_old: int) -> float:
    """Standard deviation of the relative rate change caused by noise alone [1].

    Two averages of ``n_new`` and ``n_old`` cycles, each cycle with relative variability
    ``sigma``, differ by noise of relative size ``sigma sqrt(1/n_new + 1/n_old)``. NaN sigma
    (not measured) counts as 0.
    """
    if not np.isfinite(sigma):
        return 0.0
    return sigma * math.sqrt(1.0 / n_new + 1.0 / n_old)


def systematic_change(eta_raw: float, sigma_eta: float) -> float:
    """The wear-driven part of a rate change: noise removed in quadrature [1]."""
    return math.sqrt(max(0.0, eta_raw * eta_raw - sigma_eta * sigma_eta))


def effective_tolerance(tol: float, sigma_eta: float) -> float:
    """What the controller can aim at: ``tol`` or the detection limit, whichever is larger."""
    return max(tol, DETECTION_SIGMAS * sigma_eta)


def cycles_to_average(sigma: float, tol: float, lo: int, hi: int) -> int:
    """Cycles to average per measurement so that the detection limit is at most ``tol``.

    With ``m`` cycles on both sides of an update the detection limit is
    ``DETECTION_SIGMAS * sigma * sqrt(2 / m)``; ``m`` is clipped to ``[lo, hi]``.
    """
    if not np.isfinite(sigma) or sigma <= 0:
        return lo
    m = math.ceil(2.0 * (DETECTION_SIGMAS * sigma / tol) ** 2 - 1e-9)
    return int(min(hi, max(lo, m)))


def next_interval(dn: int, eta: float, tol_eff: float, dn_min: int, dn_max: int) -> int:
    """The next update interval: ``dN * 0.9 tol_eff / eta``, at most doubled, at least 0.2x."""
    fac = 2.0 if eta == 0 else min(2.0, max(0.2, 0.9 * tol_eff / eta))
    return int(min(dn_max, max(dn_min, int(dn * fac))))


def propose_interval(
    settings: WearSettings, dn_next: int, accepted: int, rate: np.ndarray, room: int
) -> tuple[int, int]:
    """The interval of the next update: (dN to use now, dN proposed before clipping to ``room``).

    ``dn_next`` is the control's proposal (``"schedule"``: the schedule's entry after
    ``accepted`` accepted updates, its last one repeated); ``settings.max_increment`` [m]
    caps the deepest point's increment ``dN max(rate)`` (never below ``dn_min`` in the adaptive
    scheme, 1 otherwise); ``room`` is the number of cycles left to the next stop.
    """
    st = settings
    dn = int(dn_next)
    if st.scheme == "schedule":
        dn = st.schedule[min(accepted, len(st.schedule) - 1)]
    if st.max_increment is not None:
        rmax = float(np.max(rate))
        if rmax > 0:  # cap the deepest increment (never below dn_min in the adaptive scheme)
            floor = st.dn_min if st.scheme == "adaptive" else 1
            dn = min(dn, max(floor, int(st.max_increment / rmax)))
    dn = max(1, dn)
    return min(dn, room), dn


def smoothed_noise(noise_hist: Sequence[float]) -> float:
    """Smoothed relative single-cycle variability (RMS of the last four finite estimates) [1];
    NaN when none is known."""
    vals = [v for v in noise_hist[-4:] if np.isfinite(v)]
    return math.sqrt(float(np.mean(np.square(vals)))) if vals else math.nan


#: Smallest factor by which one update may damp an earlier depth error (see :func:`damping`).
MIN_DAMPING: float = 0.5


def damping(old: RateSample, new: RateSample) -> np.ndarray:
    """Per-point factor by which an update damps the depth errors made before it [1].

    For ``dh/dN = r(h)`` a depth error evolves like ``de/dN = r'(h) e`` with
    ``r'(h) = (dr/dN) / r`` along the solution, so wear that lowers a point's rate corrects
    its earlier error by ``r_new / r_old``. Cycle-to-cycle noise in the two averages would,
    clipped at 1, damp a little at every update and erase the budget over a long run (by
    ``1 - 0.4 sigma`` per update on average: to 0.1 after 27 updates at 20 % noise). The
    observed relative change ``d`` is therefore shrunk towards 0 by the positive-part
    James-Stein factor ``max(0, 1 - (2 sigma_d / d)^2)`` (``sigma_d``: noise of the change
    of the two averages): a change below the detection limit damps nothing, a clear one
    almost fully. Where strong noise hides a real self-correction, less of it is credited and
    the stated accuracy is conservative. A fall below
    :data:`MIN_DAMPING` in one update is not self-correction but the load leaving the point,
    which freezes its error instead of removing it; the factor is floored there. Capped at 1:
    no amplification is assumed where the load moves onto a point.
    """
    noise = np.nan_to_num(np.sqrt(old.var + new.var), nan=0.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        pos = old.rate > 0
        ref = np.where(pos, old.rate, 1.0)
        d = np.where(pos, new.rate / ref - 1.0, 0.0)  # observed relative change
        s2 = (noise / ref) ** 2  # its noise variance
        # positive-part James-Stein shrinkage of the change towards 0, at the detection limit
        shrink = np.where(
            d * d > 0,
            np.maximum(0.0, 1.0 - DETECTION_SIGMAS**2 * s2 / np.where(d * d > 0, d * d, 1.0)),
            0.0,
        )
    return np.clip(1.0 + d * shrink, MIN_DAMPING, 1.0)


@dataclass(frozen=True)
class ErrorBudget:
    """Accumulated error estimate of the wear-depth field and the worn volume.

    Attributes
    ----------
    depth_trunc : ndarray (Nl, Nd)
        Signed sum of the explicit-Euler local errors ``dN (r_new - r_old) / 2`` [m].
    depth_var : ndarray (Nl, Nd)
        Sum of ``dN² var(r_mean)`` over the updates [m²] (NaN once a measurement had n = 1).
    volume_trunc : float
        The same for the worn volume [m³].
    volume_var : float
        [m⁶].
    """

    depth_trunc: np.ndarray
    depth_var: np.ndarray
    volume_trunc: float
    volume_var: float

    @classmethod
    def zero(cls, shape: tuple[int, ...]) -> ErrorBudget:
        return cls(np.zeros(shape), np.zeros(shape), 0.0, 0.0)

    def add(self, dn: int, old: RateSample, new: RateSample) -> ErrorBudget:
        """The budget after an accepted update of ``dn`` cycles from ``old`` to ``new``.

        Errors made earlier are damped by wear's self-correction (:func:`damping`).
        """
        g = damping(old, new)
        return ErrorBudget(
            self.depth_trunc * g + dn * (new.rate - old.rate) / 2.0,
            self.depth_var * g * g + float(dn) ** 2 * old.var,
            self.volume_trunc + dn * (new.volume_rate - old.volume_rate) / 2.0,
            self.volume_var + float(dn) ** 2 * old.volume_var,
        )

    def depth_u(self) -> np.ndarray:
        """Expanded uncertainty (k = :data:`COVERAGE`) of the depth per point [m]."""
        return COVERAGE * np.sqrt(self.depth_trunc**2 + self.depth_var)

    def volume_u(self) -> float:
        """Expanded uncertainty (k = :data:`COVERAGE`) of the worn volume [m³]."""
        return COVERAGE * math.sqrt(self.volume_trunc**2 + self.volume_var)


#: Relative change of the wear-rate field over one accepted update (its noise removed) above
#: which the update is unresolved (:func:`unresolved_updates`), when the change also exceeds the
#: detection limit of the run's rate noise.
UNRESOLVED_RATE_CHANGE: float = 0.5

#: Share of the accepted updates that must be unresolved for "not converged in dN": an overshoot
#: of the profile feedback repeats at every update, an outlier cycle of the dynamics does not.
PERSISTENT_SHARE: float = 0.25


def unresolved_updates(eta_raw: np.ndarray, noise: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Which updates' rate changes the profile feedback, not the noise, must explain.

    Parameters
    ----------
    eta_raw : ndarray
        Measured relative change of the wear-rate field over each update [1].
    noise : ndarray
        Standard deviation of that change caused by the cycle-to-cycle noise alone [1]
        (0: a deterministic contact model; NaN counts as 0).

    Returns
    -------
    (flagged, eta_sys)
        ``flagged``: the change exceeds the detection limit ``DETECTION_SIGMAS * noise`` (a
        change within the noise is not non-convergence) and its systematic part
        ``eta_sys = sqrt(eta_raw^2 - noise^2)`` exceeds :data:`UNRESOLVED_RATE_CHANGE`.
    """
    eta_raw = np.asarray(eta_raw, dtype=float)
    noise = np.nan_to_num(np.asarray(noise, dtype=float), nan=0.0)
    eta_sys = np.sqrt(np.maximum(eta_raw**2 - noise**2, 0.0))
    flagged = (eta_sys > UNRESOLVED_RATE_CHANGE) & (eta_raw > DETECTION_SIGMAS * noise)
    return flagged, eta_sys


def convergence_notes(
    accepted: np.ndarray, noise: np.ndarray, sigma: float, *, measured: bool
) -> tuple[str | None, str | None]:
    """(convergence warning, outlier note) of a run's accepted updates, each None if none.

    ``accepted``: the accepted rows of the update history (start, dn, rate_change, ...);
    ``noise``: each change's noise standard deviation [1]; ``sigma``: the relative noise of one
    cycle [1]; ``measured``: whether the run knows it. Unresolved updates
    (:func:`unresolved_updates`) in at least :data:`PERSISTENT_SHARE` of the updates mean the
    interval is too large for the profile feedback (the explicit update overshoots at every
    update: not converged in dN). Fewer are outliers of the chaotic dynamics (a cycle with
    another impact sequence, which a two-cycle noise estimate does not foresee): their effect
    on the result is scatter between runs, which replicates measure (``sim verify``).
    """
    flagged, eta = unresolved_updates(accepted[:, 2], noise)
    if not flagged.any():
        return None, None
    worst = int(np.argmax(np.where(flagged, eta, -1.0)))
    known = (
        f" (its rate noise alone explains changes up to "
        f"{100 * DETECTION_SIGMAS * noise[worst]:.0f} %, from {100 * sigma:.0f} % per cycle)"
        if measured
        else " (the run's rate noise was not measured: the run did not finish)"
    )
    text = (
        f"the wear-rate field changed by {100 * accepted[worst, 2]:.0f} % over the update of "
        f"{int(accepted[worst, 1])} cycles starting at {int(accepted[worst, 0])} cycles{known}, "
        f"in {int(flagged.sum())} of {len(accepted)} updates: "
    )
    if flagged.sum() >= PERSISTENT_SHARE * len(accepted):
        return (
            text + "the update interval is too large to resolve the profile feedback and the "
            "result is not converged; use the adaptive scheme or a smaller dN",
            None,
        )
    return None, text + (
        "isolated outliers of the cycle-to-cycle variability, not a persistent overshoot; "
        "their effect is scatter between runs"
    )
