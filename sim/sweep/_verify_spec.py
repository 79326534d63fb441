"""What a verification study runs, :class:`VerifySpec`, and its default study: one source for
:func:`jointwear.sim.verify_wear` and ``jointwear sim verify``, whose help describes the default
study from here (:func:`default_study`; light: no numpy)."""

from __future__ import annotations

import dataclasses
import json
import math
import random
from dataclasses import dataclass
from typing import Any

from jointwear.errors import ParameterError

__all__ = [
    "DEFAULT_GRID_FACTOR",
    "DEFAULT_LEVELS",
    "DEFAULT_REPLICATES",
    "FINEST_UPDATES",
    "LEVEL_RATIO",
    "VerifySpec",
    "default_study",
]

#: Default number of ΔN levels, their ratio, and the finest ΔN as a fraction of the cycles.
DEFAULT_LEVELS, LEVEL_RATIO, FINEST_UPDATES = 4, 2, 80
DEFAULT_REPLICATES = 4
DEFAULT_GRID_FACTOR = 2


@dataclass(frozen=True)
class VerifySpec:
    """What a verification study runs (see :mod:`jointwear.sim.sweep._verify` and docs/sim-wear.md).

    Attributes
    ----------
    cycles : float
        Wear cycles of every run.
    levels : tuple of int
        Wear-update intervals ΔN [cycles], finest first.
    replicates : int
        Runs per level (different start phases).
    grid : int
        Refinement factor of the next grid (cell size ratio ``r``).
    grid_replicates : int
        Runs at the next grid, at the finest ΔN.
    formal_order : float
        Formal order of the update in ΔN (explicit Euler: 1).
    phases : tuple of float, optional
        Start phase of each replicate [crank cycles]: added to ``wear.initial_settle_cycles``,
        so replicate ``r`` starts measuring that much later in the motion; one per replicate
        (the grid runs take the first ``grid_replicates``). Default ``(0, 1, 2, ...)``.
    seed : int, optional
        Draw the phases instead, uniformly in ``[0, n)`` cycles (``n`` = the larger of
        ``replicates`` and ``grid_replicates``), from this seed: a second study with another
        seed measures how much u_num depends on the phases. Not with ``phases``.
    """

    cycles: float
    levels: tuple[int, ...]
    replicates: int = DEFAULT_REPLICATES
    grid: int = DEFAULT_GRID_FACTOR
    grid_replicates: int = DEFAULT_REPLICATES
    formal_order: float = 1.0
    phases: tuple[float, ...] | None = None
    seed: int | None = None

    def __post_init__(self) -> None:
        c = self.cycles
        if isinstance(c, bool) or not isinstance(c, (int, float)) or not (c >= 1):
            raise ParameterError(f"cycles must be a whole number >= 1, got {c!r}")
        if not float(c).is_integer():
            raise ParameterError(f"cycles = {c!r}: a wear run needs a whole number of cycles")
        levels = tuple(sorted(_whole(v, "levels", 1) for v in self.levels))
        if len(levels) < 4:
            raise ParameterError(
                f"levels = {list(self.levels)}: the least-squares procedure needs >= 4 ΔN levels"
            )
        if len(set(levels)) != len(levels):
            raise ParameterError(f"levels = {list(self.levels)} repeats a ΔN; give distinct ones")
        if levels[-1] > c:
            raise ParameterError(
                f"levels: ΔN = {levels[-1]} exceeds the {c:g} cycles of a run (one update would "
                "overshoot the target); choose ΔN <= cycles"
            )
        object.__setattr__(self, "cycles", float(c))
        object.__setattr__(self, "levels", levels)
        object.__setattr__(self, "replicates", _whole(self.replicates, "replicates", 2))
        object.__setattr__(self, "grid", _whole(self.grid, "grid", 2))
        object.__setattr__(
            self, "grid_replicates", _whole(self.grid_replicates, "grid_replicates", 2)
        )
        fo = self.formal_order
        if isinstance(fo, bool) or not isinstance(fo, (int, float)) or not fo > 0:
            raise ParameterError(f"formal_order must be > 0, got {fo!r}")
        object.__setattr__(self, "phases", self._checked_phases())

    def _checked_phases(self) -> tuple[float, ...] | None:
        """``phases`` as floats, checked against the replicates and ``seed``."""
        if self.seed is not None:
            _whole(self.seed, "seed", 0)
            if self.phases is not None:
                raise ParameterError(
                    "give either phases (the start phases themselves) or seed (draw them), not both"
                )
        if self.phases is None:
            return None
        try:
            phases = tuple(float(p) for p in self.phases)
        except (TypeError, ValueError):
            raise ParameterError(
                f"phases = {self.phases!r}: expected a list of start phases [cycles]"
            ) from None
        need = max(self.replicates, self.grid_replicates)
        if len(phases) < need:
            raise ParameterError(
                f"phases = {list(phases)}: {need} replicates need {need} start phases, one each"
            )
        if any(not math.isfinite(p) or p < 0 for p in phases):
            raise ParameterError(f"phases = {list(phases)}: every phase must be >= 0 [cycles]")
        return phases

    def start_phases(self) -> tuple[float, ...]:
        """The start phase of every replicate [crank cycles] (``phases``, drawn from ``seed``,
        or ``0, 1, 2, ...``), as many as the larger of ``replicates`` and ``grid_replicates``."""
        n = max(self.replicates, self.grid_replicates)
        if self.phases is not None:
            return self.phases[:n]
        if self.seed is None:
            return tuple(float(r) for r in range(n))
        draw = random.Random(self.seed)
        return tuple(round(draw.uniform(0.0, n), 6) for _ in range(n))

    @classmethod
    def default(cls, cycles: float, **changes: Any) -> VerifySpec:
        """The documented default study of ``cycles`` cycles (:func:`default_study`: 4 levels
        ΔN = N/80 x (1, 2, 4, 8), 4 replicates each, 4 runs on the grid refined 2x)."""
        finest = max(1, round(float(cycles) / FINEST_UPDATES))
        levels = tuple(finest * LEVEL_RATIO**k for k in range(DEFAULT_LEVELS))
        return cls(cycles=cycles, levels=changes.pop("levels", levels), **changes)

    def describe(self) -> dict[str, Any]:
        """JSON-ready record (provenance, digest)."""
        record = dataclasses.asdict(self)
        if self.phases is None and self.seed is None:  # the record of studies before phases
            del record["phases"], record["seed"]
        return json.loads(json.dumps(record))


def _whole(v: Any, name: str, lo: int) -> int:
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not float(v).is_integer():
        raise ParameterError(f"{name}: expected a whole number, got {v!r}")
    if v < lo:
        raise ParameterError(f"{name} must be >= {lo}, got {v!r}")
    return int(v)


def default_study() -> str:
    """The default study in words, as the CLI help shows it (``4 dN levels N/80 x 1, 2, 4, 8;
    4 replicates each; 4 runs on the grid refined 2x``)."""
    factors = ", ".join(str(LEVEL_RATIO**k) for k in range(DEFAULT_LEVELS))
    return (
        f"{DEFAULT_LEVELS} dN levels N/{FINEST_UPDATES} x {factors}; {DEFAULT_REPLICATES} "
        f"replicates each; {DEFAULT_REPLICATES} runs on the grid refined {DEFAULT_GRID_FACTOR}x"
    )
