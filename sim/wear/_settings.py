"""Settings of a wear run (:class:`WearSettings`) and the checks on the wear coefficient kw."""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass
from typing import Any, Literal

from jointwear.errors import ParameterError
from jointwear.params import check_fields, checked, non_negative, within

__all__ = [
    "DEFAULT_KW",
    "DEFAULT_CYCLES",
    "CALIBRATION_RTOL",
    "KW_RANGE",
    "WearSettings",
    "check_kw",
    "default_snapshots",
]

#: Default Archard wear coefficient [m²/N = m³/(N m)]; derivation in docs/sim-wear.md.
DEFAULT_KW: float = 9.0e-16

#: Default target of a wear run [cycles].
DEFAULT_CYCLES: float = 1e6

#: Relative tolerance of a re-simulated kw calibration's match to the measurement.
CALIBRATION_RTOL: float = 0.02

#: Accepted range of kw [m²/N]. Above 1e-11 (1e-2 mm³/(N m), beyond severe dry wear) the bore of
#: the study would wear through in hours; below 1e-20 nothing measurable wears in any lifetime.
KW_RANGE: tuple[float, float] = (1.0e-20, 1.0e-11)


def check_kw(kw: float, *, name: str = "kw") -> float:
    """``kw`` as a float [m²/N]; refuses non-numbers, non-positive and absurd values."""
    try:
        kw = float(kw)
    except (TypeError, ValueError):
        raise ParameterError(f"{name} must be a number [m²/N], got {kw!r}") from None
    if not math.isfinite(kw) or kw <= 0:
        raise ParameterError(
            f"{name} = {kw!r}: the wear coefficient must be a positive number [m²/N = m³/(N m)]"
        )
    lo, hi = KW_RANGE
    if kw > hi:
        raise ParameterError(
            f"{name} = {kw:g} m²/N is absurd: more than {hi:g} m²/N would wear the bore through "
            "within hours. The study's tabulated 5.05e-10 cannot be SI (see docs/sim-wear.md); "
            f"give kw in m²/N, e.g. the default {DEFAULT_KW:g}"
        )
    if kw < lo:
        raise ParameterError(
            f"{name} = {kw:g} m²/N is absurdly small (below {lo:g}, no measurable wear in any "
            "lifetime); did you convert from mm³/(N m) twice? 1 mm³/(N m) = 1e-9 m²/N"
        )
    return kw


def default_snapshots(target: float) -> list[float]:
    """Snapshot cycle counts: 1, 2, 5 x 10^k from target/1000 up to the target (included)."""
    lo = max(1.0, float(target) / 1000.0)
    out = [
        m * 10.0**k for k in range(0, 13) for m in (1, 2, 5) if lo <= m * 10.0**k < float(target)
    ]
    return [*out, float(target)]


def _whole(where: str, name: str, v: object) -> int:
    if isinstance(v, float) and v.is_integer():
        v = int(v)
    if not isinstance(v, numbers.Integral) or isinstance(v, bool) or v < 1:
        raise ParameterError(f"{where}.{name} must be an integer >= 1 [cycles], got {v!r}")
    return int(v)


def _cycles(default: int) -> Any:
    """A field holding a whole number of cycles >= 1 (kept as int)."""
    return checked(default, _whole)


@dataclass(frozen=True)
class WearSettings:
    """Settings of the wear computation.

    Parameters
    ----------
    kw : float
        Archard wear coefficient [m²/N]; default :data:`DEFAULT_KW`.
    scheme : {"adaptive", "fixed", "schedule"}
        Update-interval control (see :mod:`jointwear.sim.wear`); ``"schedule"`` uses the
        intervals of ``schedule`` in order (e.g. an adaptive run's ``update_dn`` with every
        interval halved, to check its convergence).
    dn : int
        Cycles per update for ``"fixed"``; the first interval for ``"adaptive"``.
    tol : float
        Adaptive: allowed relative change of the wear-rate field per update [1].
    schedule : tuple of int
        ``"schedule"``: the update intervals [cycles], the last one repeated.
    dn_min, dn_max : int
        Adaptive: bounds of the interval [cycles].
    max_increment : float or None
        Cap on the largest depth increment of one update [m] (all schemes); None = no cap.
    settle_cycles : float
        Cycles simulated and discarded after each update before wear is accumulated.
    initial_settle_cycles : float
        Cycles discarded at the very start (from the initial conditions).
    reject_factor : float
        Adaptive: reject an update whose wear-driven rate change exceeds ``reject_factor``
        times the tolerance in force.
    average_cycles, max_average_cycles : int
        Adaptive: single cycles averaged per measurement of the wear rate, at least
        ``average_cycles``, more (up to ``max_average_cycles``) when the cycle-to-cycle
        variability hides changes of ``tol``; the first measurement averages
        ``max(average_cycles, 4)`` (at most ``max_average_cycles``) to start the noise estimate.
        The fixed and schedule schemes measure one cycle (their accuracy is not assessed).
    """

    kw: float = DEFAULT_KW
    scheme: Literal["adaptive", "fixed", "schedule"] = "adaptive"
    dn: int = _cycles(200)
    schedule: tuple[int, ...] = ()
    tol: float = within(0.1, "(0, 1)")
    dn_min: int = _cycles(1)
    dn_max: int = _cycles(200_000)
    max_increment: float | None = None
    settle_cycles: float = non_negative(1.0, unit="cycles")
    initial_settle_cycles: float = non_negative(2.0, unit="cycles")
    reject_factor: float = 3.0
    average_cycles: int = _cycles(2)
    max_average_cycles: int = _cycles(8)

    def __post_init__(self) -> None:
        object.__setattr__(self, "kw", check_kw(self.kw))
        try:
            sched = tuple(int(v) for v in self.schedule)
        except (TypeError, ValueError):
            raise ParameterError(
                "wear.schedule must be a list of whole numbers of cycles"
            ) from None
        if any(v < 1 or v != w for v, w in zip(sched, self.schedule, strict=True)):
            raise ParameterError("wear.schedule must hold whole numbers of cycles >= 1")
        if self.scheme == "schedule" and not sched:
            raise ParameterError("wear.scheme = 'schedule' needs a non-empty wear.schedule")
        object.__setattr__(self, "schedule", sched)
        check_fields(self, "wear")
        if self.dn_min > self.dn_max:
            raise ParameterError(f"wear.dn_min = {self.dn_min} exceeds wear.dn_max = {self.dn_max}")
        if self.average_cycles > self.max_average_cycles:
            raise ParameterError(
                f"wear.average_cycles = {self.average_cycles} exceeds wear.max_average_cycles = "
                f"{self.max_average_cycles}"
            )
        if self.max_increment is not None and not (
            math.isfinite(self.max_increment) and self.max_increment > 0
        ):
            raise ParameterError(
                f"wear.max_increment must be a positive depth [m] or None, got {self.max_increment!r}"
            )
        if not self.reject_factor > 1:
            raise ParameterError(f"wear.reject_factor must be > 1, got {self.reject_factor!r}")
