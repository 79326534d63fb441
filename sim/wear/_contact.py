"""Contact models that feed the wear loop: one cycle's per-point wear work on a given worn profile.

The wear loop (:mod:`jointwear.sim.wear`) only needs, for the current wear profile ``h`` (Nl, Nd),
one crank cycle's *wear work* per bearing point, ``w = integral p |ds|`` [Pa m] (so that Archard's
law gives the depth increment ``dh = kw w``), the patch area of each point and the normal work
``integral F_n |v_t| dt`` [N m]. Three models provide it:

* :class:`DynamicContact` - the multibody simulation (``jointwear.sim.run_cycles``, the default);
  any function with that signature can be injected instead.
* :class:`ConstantContact` - prescribed, profile-independent pressure and sliding distance:
  after N cycles the depth is exactly ``N kw p s``, whatever the update interval.
* :class:`WinklerContact` - a prescribed load pressed onto an elastic (Winkler) foundation lining
  the bore: the local pressure ``kf * max(e cos(theta - psi) - c - h, 0)`` falls where the bore has
  worn, which is the feedback that makes too-large explicit update intervals unstable.

All models are deterministic; their ``state`` is opaque and picklable.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np
from scipy.optimize import brentq

from jointwear.errors import ParameterError, SimulationError
from jointwear.params import check_fields, positive, to_jsonable
from jointwear.sim.wearmap import BearingGrid

__all__ = ["CycleWear", "ContactModel", "ConstantContact", "WinklerContact", "DynamicContact"]


@dataclass
class CycleWear:
    """Wear-relevant output of simulating ``cycles`` crank cycles on a fixed profile.

    Attributes
    ----------
    wear_work : ndarray (Nl, Nd)
        ``integral p |ds|`` per bearing point over the simulated interval [Pa m].
    point_area : ndarray (Nl, Nd)
        Bore area each point stands for [m²].
    normal_work : float
        ``integral F_n |v_t| dt`` over the interval [N m] (= ``sum(wear_work * point_area)``).
    state : object
        Opaque, picklable state to continue from.
    cycles : float
        Number of cycles simulated.
    max_penetration : float
        Largest contact penetration over the interval [m] (NaN: the model does not know it).
    """

    wear_work: np.ndarray
    point_area: np.ndarray
    normal_work: float
    state: Any
    cycles: float
    max_penetration: float = math.nan


class ContactModel(Protocol):
    """What the wear loop needs from a contact model."""

    grid: BearingGrid

    def describe(self) -> dict[str, Any]:
        """All parameters that determine the result (JSON-ready), for provenance and resume."""
        ...

    def run(
        self, wear_depth: np.ndarray, *, cycles: float, state: Any, progress: Any = None
    ) -> CycleWear:
        """Simulate ``cycles`` cycles on the profile ``wear_depth`` [m], continuing ``state``."""
        ...


@dataclass(frozen=True)
class ConstantContact:
    """Prescribed, profile-independent contact: pressure ``p`` and sliding ``s`` per cycle.

    Parameters
    ----------
    grid : BearingGrid
        The discretisation.
    pressure : float or ndarray (Nl, Nd)
        Contact pressure [Pa] at each point while sliding (0 = no contact).
    sliding : float
        Sliding distance per cycle [m].
    """

    grid: BearingGrid = field(default_factory=BearingGrid)
    pressure: float | np.ndarray = 1.0e6
    sliding: float = positive(0.02)

    def __post_init__(self) -> None:
        p = np.broadcast_to(np.asarray(self.pressure, dtype=float), self.grid.shape).copy()
        if not np.all(np.isfinite(p)) or np.any(p < 0):
            raise ParameterError("pressure must be finite and >= 0 [Pa] at every point")
        object.__setattr__(self, "pressure", p)
        check_fields(self, "ConstantContact")

    def describe(self) -> dict[str, Any]:
        return {
            "model": "constant",
            "grid": to_jsonable(self.grid),
            "pressure": to_jsonable(self.pressure),
            "sliding": self.sliding,
        }

    def run(
        self, wear_depth: np.ndarray, *, cycles: float, state: Any, progress: Any = None
    ) -> CycleWear:
        self.grid.check(wear_depth, "wear_depth")
        w = self.pressure * self.sliding * cycles
        area = self.grid.point_area
        return CycleWear(w, area, float(np.sum(w * area)), state, cycles)


@dataclass(frozen=True)
class WinklerContact:
    """Prescribed load on an elastic (Winkler) lining: local pressure falls where the bore wore.

    During a cycle the journal is pressed with the load ``F(t)`` in the direction ``psi(t)``
    (sampled at ``n_steps`` equal time steps). At each step the journal's displacement ``e`` along
    ``psi`` is solved so that the foundation carries the load,
    ``sum_points kf * max((e + tilt z) cos(theta - psi) - c - h, 0) * A = F``, and every
    point in contact slides ``sliding / n_steps``.

    With a constant load and direction, a shape perturbation of the worn profile decays like
    ``(1 - dN kw s kf)`` per explicit update of ``dN`` cycles: the explicit scheme oscillates for
    ``dN > 1 / (kw s kf)`` and is unstable for ``dN > 2 / (kw s kf)``.

    Parameters
    ----------
    grid : BearingGrid
        The discretisation.
    load : float or sequence
        Normal load [N], constant or one value per step.
    load_angle_deg : float or sequence
        Direction of the load on the bearing [degree], canonical convention; constant or one
        value per step.
    clearance : float
        Radial clearance ``c`` [m].
    foundation_modulus : float
        Winkler modulus ``kf`` [Pa/m] (pressure per unit interference).
    sliding : float
        Sliding distance per cycle [m].
    tilt : float
        Misalignment of the journal in the load plane [rad]: the interference grows by
        ``tilt * z`` (z in [-wb/2, wb/2]), giving an axially asymmetric contact.
    n_steps : int
        Time steps per cycle (used when load or direction vary).
    """

    grid: BearingGrid = field(default_factory=BearingGrid)
    load: float | tuple[float, ...] = 20.0
    load_angle_deg: float | tuple[float, ...] = 90.0
    clearance: float = positive(0.5e-3)
    foundation_modulus: float = positive(1.0e11)
    sliding: float = positive(0.02)
    tilt: float = 0.0
    n_steps: int = 1

    def __post_init__(self) -> None:
        load = np.atleast_1d(np.asarray(self.load, dtype=float))
        angle = np.atleast_1d(np.asarray(self.load_angle_deg, dtype=float))
        n = max(int(self.n_steps), load.size, angle.size)
        for name, arr in (("load", load), ("load_angle_deg", angle)):
            if arr.size not in (1, n):
                raise ParameterError(f"{name} must have 1 or n_steps = {n} values, got {arr.size}")
            if not np.all(np.isfinite(arr)):
                raise ParameterError(f"{name} must be finite")
        if np.any(load < 0):
            raise ParameterError("load must be >= 0 [N]")
        object.__setattr__(self, "load", tuple(np.broadcast_to(load, n).tolist()))
        object.__setattr__(self, "load_angle_deg", tuple(np.broadcast_to(angle, n).tolist()))
        object.__setattr__(self, "n_steps", n)
        check_fields(self, "WinklerContact")
        if not np.isfinite(self.tilt):
            raise ParameterError("tilt must be finite [rad]")

    def describe(self) -> dict[str, Any]:
        out = to_jsonable(self)
        out["model"] = "winkler"
        return out

    def critical_cycles(self, kw: float) -> float:
        """``1 / (kw s kf)`` [cycles]: explicit updates oscillate above it, diverge above twice it."""
        return 1.0 / (kw * self.sliding * self.foundation_modulus)

    def pressure(self, wear_depth: np.ndarray, step: int = 0) -> np.ndarray:
        """Contact pressure [Pa] per point at time step ``step`` on the profile ``wear_depth``."""
        g = self.grid
        h = g.check(wear_depth, "wear_depth")
        area = g.point_area
        load = self.load[step]
        if load == 0:
            return np.zeros(g.shape)
        cosd = np.cos(np.deg2rad(g.theta_deg - self.load_angle_deg[step]))[None, :]
        tilt = self.tilt * g.z[:, None]
        kf, c = self.foundation_modulus, self.clearance

        def excess(e: float) -> float:
            return float(np.sum(np.maximum((e + tilt) * cosd - c - h, 0.0) * area)) * kf - load

        hi = c + float(np.max(h)) + abs(self.tilt) * g.width + 1e-9
        while excess(hi) < 0:
            hi *= 2
            if hi > 1.0:
                raise SimulationError("Winkler contact: no journal position carries the load")
        e = brentq(excess, 0.0, hi, xtol=1e-16, rtol=4 * np.finfo(float).eps, maxiter=500)
        return kf * np.maximum((e + tilt) * cosd - c - h, 0.0)

    def run(
        self, wear_depth: np.ndarray, *, cycles: float, state: Any, progress: Any = None
    ) -> CycleWear:
        ds = self.sliding / self.n_steps
        w = np.zeros(self.grid.shape)
        for k in range(self.n_steps):
            w += self.pressure(wear_depth, k) * ds
        w *= cycles
        area = self.grid.point_area
        return CycleWear(w, area, float(np.sum(w * area)), state, cycles)


class DynamicContact:
    """The multibody simulation as contact model: wraps ``run_cycles(params, ...)``.

    Parameters
    ----------
    params : SimParameters
        Parameters of the mechanism and joint (``jointwear.sim.SimParameters``).
    cycle_function : callable, optional
        ``f(params, *, cycles, wear_depth, state, record, progress) -> CycleResult`` with
        ``wear_work``, ``point_area``, ``normal_work``, ``state`` and ``cycles``; default
        :func:`jointwear.sim.run_cycles`.
    """

    def __init__(self, params: Any, cycle_function: Any = None) -> None:
        self.params = params
        self.grid = BearingGrid.from_params(params)
        self._fn = cycle_function

    def describe(self) -> dict[str, Any]:
        return {"model": "dynamics", "parameters": to_jsonable(self.params)}

    @property
    def cycle_function(self) -> Any:
        if self._fn is None:
            try:
                from jointwear.sim.dynamics import run_cycles
            except ImportError:
                raise SimulationError(
                    "the multibody dynamics (jointwear.sim.run_cycles) are not available in this "
                    "installation; use a prescribed contact model"
                ) from None
            self._fn = run_cycles
        return self._fn

    def _run_cycles(
        self, wear_depth: np.ndarray, *, cycles: float, state: Any, progress: Any = None
    ) -> Any:
        """The cycle function's result for these cycles over ``wear_depth`` (unrecorded)."""
        return self.cycle_function(
            self.params,
            cycles=cycles,
            wear_depth=wear_depth,
            state=state,
            record=False,
            progress=progress,
        )

    @staticmethod
    def _cycle_wear(res: Any, wear_work: np.ndarray) -> CycleWear:
        """A :class:`CycleWear` of ``wear_work`` [Pa m], the rest taken from the result ``res``."""
        return CycleWear(
            wear_work=wear_work,
            point_area=np.asarray(res.point_area, dtype=float),
            normal_work=float(res.normal_work),
            state=res.state,
            cycles=float(res.cycles),
            max_penetration=float(getattr(res, "max_penetration", math.nan)),
        )

    def run(
        self, wear_depth: np.ndarray, *, cycles: float, state: Any, progress: Any = None
    ) -> CycleWear:
        res = self._run_cycles(wear_depth, cycles=cycles, state=state, progress=progress)
        work = np.asarray(res.wear_work, dtype=float)
        if work.shape != self.grid.shape or not np.all(np.isfinite(work)):
            raise SimulationError(
                f"the dynamics returned a wear-work field of shape {work.shape} with "
                f"{int(np.sum(~np.isfinite(work)))} non-finite values; expected finite {self.grid.shape}"
            )
        return self._cycle_wear(res, work)


def describe_any(model: Any) -> dict[str, Any]:
    """``model.describe()`` if it exists, else a generic record (type name)."""
    if hasattr(model, "describe"):
        return model.describe()
    return {"model": type(model).__name__}


def contact_from_description(desc: dict[str, Any]) -> Any:
    """Rebuild a contact model from its ``describe()`` record (as stored in provenance)."""
    from jointwear.params import from_mapping

    model = desc.get("model")
    if model == "dynamics":
        from jointwear.sim.parameters import SimParameters

        return DynamicContact(from_mapping(SimParameters, desc["parameters"], where="parameters"))
    if model in ("winkler", "constant"):
        args = {k: v for k, v in desc.items() if k != "model"}
        args["grid"] = BearingGrid(**args["grid"])
        if model == "winkler":
            args["load"] = tuple(args["load"])
            args["load_angle_deg"] = tuple(args["load_angle_deg"])
            return WinklerContact(**args)
        args["pressure"] = np.asarray(args["pressure"], dtype=float)
        return ConstantContact(**args)
    raise ParameterError(
        f"contact model {model!r} cannot be rebuilt from its description; "
        "pass the model (or a resimulate function) explicitly"
    )
