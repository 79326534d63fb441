"""Archard wear of the bearing with cycle updates, adaptive update interval, checkpoints, kw calibration.

Model (reference study, notes section 4)
-----------------------------------------
Archard's law per bearing point, ``dh = kw p ds`` (eq. 19): a crank cycle simulated on the current
profile gives each point's *wear work* ``w = integral p |ds|`` [Pa m]; its wear rate is
``r = kw w`` [m per cycle]. The cycle-update strategy (Fig. 3 of the study) advances the profile by
``dN`` cycles at a time, ``h <- h + dN r(h)`` (explicit Euler in the cycle count), and re-simulates
on the new profile, so the contact geometry and the time-varying stiffness K(t) follow the wear.

Settling: after every profile update the simulation first runs ``settle_cycles`` cycles whose
wear is discarded (the journal re-seats on the new profile; start-up transients are not wear),
then accumulates the wear of one further cycle. The very first cycle from the initial
conditions is preceded by ``initial_settle_cycles``.

Update interval
---------------
``scheme="fixed"`` uses ``dN`` cycles per update. Because local pressure falls where the bore
has worn, an explicit update with a too-large ``dN`` overshoots: points that wore too much lose
contact, the load moves elsewhere, and the profile oscillates and roughens (unstable).
``scheme="adaptive"`` (default) controls the relative change of the wear-rate field between two
updates, ``eta = ||r_new - r_old|| / ||r_old||`` (area-weighted L2 norm). For explicit Euler the
local error of an update, relative to its depth increment, is ``eta / 2``; the next interval is
``dN * 0.9 tol / eta`` (at most doubled, at least 0.2x), and an update whose ``eta`` exceeds
``reject_factor * tol`` is rejected and redone with a smaller interval. Impacts make the dynamics
slightly non-periodic: the cycle-to-cycle variability of the rate field is measured on the initial
profile and removed from ``eta`` in quadrature. ``scheme="schedule"`` replays a list of intervals
(:func:`halved_schedule` for convergence checks). The interval sequence is reported in the output
(``update_*`` variables); accepted updates that changed the rate field by more than
:data:`UNRESOLVED_RATE_CHANGE` set the ``convergence_warning`` attribute.

kw
--
``kw`` is the dimensional wear coefficient [m³/(N m) = m²/N]; see :data:`DEFAULT_KW` and
docs/sim-wear.md for how the default was obtained.
"""

from __future__ import annotations

import dataclasses
import json
import math
import pickle
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import numpy as np
import xarray as xr

from jointwear import conventions
from jointwear.errors import BadInputError, ParameterError
from jointwear.io import atomic_path, check_writable
from jointwear.params import to_jsonable
from jointwear.sim._wear_contact import CycleWear, describe_any
from jointwear.sim.wearmap import BearingGrid, wear_map_dataset

__all__ = [
    "DEFAULT_KW",
    "KW_RANGE",
    "WearSettings",
    "WearRun",
    "simulate_wear",
    "default_snapshots",
    "KwCalibration",
    "calibrate_kw",
    "halved_schedule",
    "resimulator",
]

#: Default Archard wear coefficient [m²/N = m³/(N m)]; derivation in docs/sim-wear.md.
DEFAULT_KW: float = 9.0e-16

#: Accepted range of kw [m²/N]. Above 1e-11 (1e-2 mm³/(N m), beyond severe dry wear) the bore of
#: the study would wear through in hours; below 1e-20 nothing measurable wears in any lifetime.
KW_RANGE: tuple[float, float] = (1.0e-20, 1.0e-11)

#: Relative change of the wear-rate field over one accepted update above which the result is
#: flagged as not converged in dN (``convergence_warning`` attribute).
UNRESOLVED_RATE_CHANGE: float = 0.5

_CHECKPOINT_FORMAT = "jointwear.sim.wear checkpoint v1"


def _check_kw(kw: float, *, name: str = "kw") -> float:
    try:
        kw = float(kw)
    except (TypeError, ValueError):
        raise ParameterError(f"{name} must be a number [m²/N], got {kw!r}") from None
    if not np.isfinite(kw) or kw <= 0:
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


@dataclass(frozen=True)
class WearSettings:
    """Settings of the wear computation.

    Parameters
    ----------
    kw : float
        Archard wear coefficient [m²/N]; default :data:`DEFAULT_KW`.
    scheme : {"adaptive", "fixed", "schedule"}
        Update-interval control (see module docstring); ``"schedule"`` uses the intervals of
        ``schedule`` in order (e.g. an adaptive run's ``update_dn`` with every interval halved,
        to check its convergence).
    dn : int
        Cycles per update for ``"fixed"``; the first interval for ``"adaptive"``.
    tol : float
        Adaptive: allowed relative change of the wear-rate field per update.
    schedule : tuple of int
        ``"schedule"``: the update intervals [cycles], the last one repeated.
    dn_min, dn_max : int
        Adaptive: bounds of the interval [cycles].
    max_increment : float or None
        Cap on the largest depth increment of one update [m] (both schemes); None = no cap.
    settle_cycles : float
        Cycles simulated and discarded after each update before wear is accumulated.
    initial_settle_cycles : float
        Cycles discarded at the very start (from the initial conditions).
    reject_factor : float
        Adaptive: reject an update whose rate change exceeds ``reject_factor * tol``.
    estimate_noise : bool
        Adaptive: measure the cycle-to-cycle variability of the wear-rate field on the initial
        profile (two extra cycles) and remove it (in quadrature) from the rate change, so that
        non-periodic dynamics (impacts) do not force the interval down to ``dn_min``.
    noise_floor : float
        Adaptive: a further relative rate change to be ignored (added to the estimate).
    """

    kw: float = DEFAULT_KW
    scheme: Literal["adaptive", "fixed", "schedule"] = "adaptive"
    dn: int = 200
    schedule: tuple[int, ...] = ()
    tol: float = 0.1
    dn_min: int = 1
    dn_max: int = 200_000
    max_increment: float | None = None
    settle_cycles: float = 1.0
    initial_settle_cycles: float = 2.0
    reject_factor: float = 3.0
    estimate_noise: bool = True
    noise_floor: float = 0.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "kw", _check_kw(self.kw))
        if self.scheme not in ("adaptive", "fixed", "schedule"):
            raise ParameterError(
                f"wear scheme must be 'adaptive', 'fixed' or 'schedule', got {self.scheme!r}"
            )
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
        for name in ("dn", "dn_min", "dn_max"):
            v = getattr(self, name)
            if isinstance(v, float) and v.is_integer():
                object.__setattr__(self, name, int(v))
                v = int(v)
            if not isinstance(v, (int, np.integer)) or v < 1:
                raise ParameterError(f"wear.{name} must be an integer >= 1 [cycles], got {v!r}")
        if self.dn_min > self.dn_max:
            raise ParameterError(f"wear.dn_min = {self.dn_min} exceeds wear.dn_max = {self.dn_max}")
        if not (0 < self.tol < 1):
            raise ParameterError(f"wear.tol must be in (0, 1), got {self.tol!r}")
        if self.max_increment is not None and not (
            np.isfinite(self.max_increment) and self.max_increment > 0
        ):
            raise ParameterError(
                f"wear.max_increment must be a positive depth [m] or None, got {self.max_increment!r}"
            )
        for name in ("settle_cycles", "initial_settle_cycles"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v >= 0):
                raise ParameterError(f"wear.{name} must be >= 0 cycles, got {v!r}")
        if not (np.isfinite(self.noise_floor) and 0 <= self.noise_floor < 1):
            raise ParameterError(f"wear.noise_floor must be in [0, 1), got {self.noise_floor!r}")
        if not self.reject_factor > 1:
            raise ParameterError(f"wear.reject_factor must be > 1, got {self.reject_factor!r}")


def default_snapshots(target: float) -> list[float]:
    """Snapshot cycle counts: 1, 2, 5 x 10^k from target/1000 up to the target (included)."""
    lo = max(1.0, float(target) / 1000.0)
    out = [
        m * 10.0**k for k in range(0, 13) for m in (1, 2, 5) if lo <= m * 10.0**k < float(target)
    ]
    return [*out, float(target)]


def _flatten(obj: Any, prefix: str = "") -> dict[str, Any]:
    out: dict[str, Any] = {}
    if isinstance(obj, Mapping):
        for k, v in obj.items():
            out.update(_flatten(v, f"{prefix}{k}."))
        return out
    out[prefix[:-1]] = obj
    return out


def _weighted_norm(x: np.ndarray, w: np.ndarray) -> float:
    return float(np.sqrt(np.sum(w * x * x)))


class WearRun:
    """A wear computation that can be advanced, checkpointed, interrupted and resumed.

    Parameters
    ----------
    contact : ContactModel
        Gives one cycle's wear work on a profile (:class:`~jointwear.sim.DynamicContact`,
        :class:`~jointwear.sim.WinklerContact`, ...).
    settings : WearSettings
        kw and update-interval control.
    cycles : float
        Target number of cycles.
    snapshots : sequence of float, optional
        Cycle counts at which the wear map is stored (the target is always added); default
        :func:`default_snapshots`.
    checkpoint : path, optional
        File written atomically after every accepted update.
    initial_wear : ndarray (Nl, Nd), optional
        Initial wear profile [m] (default unworn).
    on_update : callable, optional
        Called after every update with a dict (``cycles_done``, ``target``, ``dn``,
        ``max_depth``, ``accepted``, ``rate_change``).
    """

    def __init__(
        self,
        contact: Any,
        settings: WearSettings | None = None,
        *,
        cycles: float,
        snapshots: Sequence[float] | None = None,
        checkpoint: str | Path | None = None,
        initial_wear: np.ndarray | None = None,
        on_update: Callable[[dict[str, Any]], None] | None = None,
    ) -> None:
        self.contact = contact
        self.grid: BearingGrid = contact.grid
        self.settings = settings or WearSettings()
        self.checkpoint = Path(checkpoint) if checkpoint is not None else None
        self.on_update = on_update
        h0 = (
            np.zeros(self.grid.shape)
            if initial_wear is None
            else self.grid.check(initial_wear, "initial_wear").copy()
        )
        if np.any(h0 < 0):
            raise BadInputError("initial_wear must be >= 0 [m] everywhere")
        self._s: dict[str, Any] = {
            "h": h0,
            "initial_wear": h0.copy(),
            "state": None,
            "rate": None,
            "work_rate": None,
            "done": 0,
            "dn_next": int(self.settings.dn),
            "noise": 0.0,
            "normal_work": 0.0,
            "cycles_simulated": 0.0,
            "history": [],  # (start, dn, rate_change, accepted)
            "snapshots": [],  # (cycles, h, normal_work)
        }
        self._set_target(cycles, snapshots)
        if self.checkpoint is not None:
            check_writable(self.checkpoint, what="checkpoint")

    # --- set-up ----------------------------------------------------------------------------
    def _set_target(self, cycles: float, snapshots: Sequence[float] | None) -> None:
        try:
            target = float(cycles)
        except (TypeError, ValueError):
            raise BadInputError(f"cycles must be a number, got {cycles!r}") from None
        if not np.isfinite(target) or target < 1 or not float(target).is_integer():
            raise BadInputError(f"cycles must be a whole number >= 1, got {cycles!r}")
        done = self._s["done"]
        if target < done:
            raise BadInputError(
                f"target of {target:.6g} cycles is below the {done:.6g} cycles already done in "
                "the checkpoint; give --cycles >= the cycles done (or start over without --resume)"
            )
        snaps = default_snapshots(target) if snapshots is None else [float(s) for s in snapshots]
        for s in snaps:
            if not np.isfinite(s) or s <= 0 or not float(s).is_integer() or s > target:
                raise BadInputError(
                    f"snapshot {s!r} must be a whole number of cycles in [1, {target:.6g}]"
                )
        taken = {c for c, _, _ in self._s["snapshots"]}
        self.target = int(target)
        self._stops = sorted({int(s) for s in snaps if s > done} | {int(target)} - taken)

    @property
    def cycles_done(self) -> int:
        """Cycles completed so far."""
        return int(self._s["done"])

    @property
    def wear_depth(self) -> np.ndarray:
        """Current wear profile (Nl, Nd) [m] (a copy)."""
        return self._s["h"].copy()

    @property
    def cycles_simulated(self) -> float:
        """Cycles actually simulated by the contact model so far (settling included)."""
        return float(self._s["cycles_simulated"])

    def fingerprint(self) -> dict[str, Any]:
        """Everything that determines the result (JSON-ready): model and wear settings."""
        return {
            "contact": to_jsonable(describe_any(self.contact)),
            "wear": to_jsonable(self.settings),
            "initial_wear_max": float(np.max(self._s["initial_wear"])),
            "initial_wear_sum": float(np.sum(self._s["initial_wear"])),
        }

    # --- checkpoints ------------------------------------------------------------------------
    def save_checkpoint(self, path: str | Path | None = None) -> Path:
        """Write the complete state atomically (pickle) to ``path`` or :attr:`checkpoint`."""
        path = Path(path) if path is not None else self.checkpoint
        if path is None:
            raise BadInputError("no checkpoint path given")
        payload = {
            "format": _CHECKPOINT_FORMAT,
            "fingerprint": self.fingerprint(),
            "state": self._s,
        }
        with atomic_path(path) as tmp:
            with open(tmp, "wb") as fh:
                pickle.dump(payload, fh, protocol=pickle.HIGHEST_PROTOCOL)
        return path

    @classmethod
    def resume(
        cls,
        checkpoint: str | Path,
        contact: Any,
        settings: WearSettings | None = None,
        *,
        cycles: float,
        snapshots: Sequence[float] | None = None,
        on_update: Callable[[dict[str, Any]], None] | None = None,
    ) -> WearRun:
        """Continue a run from its checkpoint; refuse if the parameters differ.

        Raises
        ------
        BadInputError
            The checkpoint is missing or unreadable, was written with different parameters
            (the message names them), or the target is below the cycles already done.
        """
        path = Path(checkpoint)
        if not path.exists():
            raise BadInputError(
                f"checkpoint '{path}' does not exist; run without --resume to start a new run"
            )
        try:
            with open(path, "rb") as fh:
                payload = pickle.load(fh)
        except (
            OSError,
            pickle.UnpicklingError,
            EOFError,
            AttributeError,
            ImportError,
            TypeError,
            ValueError,
        ) as exc:
            raise BadInputError(
                f"checkpoint '{path}' could not be read ({exc}); start over without --resume"
            ) from None
        if not isinstance(payload, dict) or payload.get("format") != _CHECKPOINT_FORMAT:
            raise BadInputError(f"'{path}' is not a jointwear wear checkpoint")
        state = payload["state"]
        run = cls(
            contact,
            settings,
            cycles=max(float(cycles), 1.0),
            snapshots=None,
            checkpoint=path,
            on_update=on_update,
        )
        if np.shape(state["initial_wear"]) == run.grid.shape:
            run._s["initial_wear"] = state["initial_wear"]
        old = _flatten(payload["fingerprint"])
        new = _flatten(run.fingerprint())
        differing = sorted(k for k in set(old) | set(new) if old.get(k) != new.get(k))
        if differing:
            shown = "; ".join(
                f"{k}: {old.get(k, '<absent>')!r} in the checkpoint, {new.get(k, '<absent>')!r} now"
                for k in differing[:5]
            )
            more = f" (and {len(differing) - 5} more)" if len(differing) > 5 else ""
            raise BadInputError(
                f"checkpoint '{path}' was written with different parameters - {shown}{more}. "
                "Resume with the original parameters, or start over without --resume"
            )
        run._s = state
        run._set_target(cycles, snapshots)
        return run

    # --- the loop ---------------------------------------------------------------------------
    def _measure(
        self, h: np.ndarray, state: Any, settle: float
    ) -> tuple[np.ndarray, float, Any, float]:
        """Settle on profile ``h``, then accumulate one cycle.

        Returns (wear rate [m/cycle] per point, normal work per cycle [N m], state, cycles
        simulated).
        """
        simulated = 0.0
        if settle > 0:
            res = self.contact.run(h, cycles=settle, state=state)
            state = res.state
            simulated += res.cycles
        res: CycleWear = self.contact.run(h, cycles=1.0, state=state)
        simulated += res.cycles
        rate = self.settings.kw * np.asarray(res.wear_work, dtype=float) / res.cycles
        if np.any(rate < 0):
            raise BadInputError("the contact model returned negative wear work")
        return rate, res.normal_work / res.cycles, res.state, simulated

    def _rate_change(self, new: np.ndarray, old: np.ndarray) -> float:
        w = self.grid.point_area
        ref = _weighted_norm(old, w)
        diff = _weighted_norm(new - old, w)
        if ref == 0:
            return 0.0 if diff == 0 else math.inf
        return diff / ref

    def _propose(self, rate: np.ndarray, stop: int) -> tuple[int, int]:
        """(dn to use now, dn proposed before clipping to the next stop)."""
        st = self.settings
        dn = int(self._s["dn_next"])
        if st.scheme == "schedule":
            k = sum(1 for item in self._s["history"] if item[3] == 1)
            dn = st.schedule[min(k, len(st.schedule) - 1)]
        if st.max_increment is not None:
            rmax = float(np.max(rate))
            if rmax > 0:  # cap the deepest increment (never below dn_min in the adaptive scheme)
                floor = st.dn_min if st.scheme == "adaptive" else 1
                dn = min(dn, max(floor, int(st.max_increment / rmax)))
        dn = max(1, dn)
        return min(dn, stop - self._s["done"]), dn

    def step(self) -> bool:
        """Advance by one update (or one rejected attempt). Returns False at the target.

        The new state is assembled aside and swapped in with one assignment, so an interrupt
        (Ctrl-C) at any moment leaves a consistent state in memory and on disk.
        """
        st = self.settings
        adaptive = st.scheme == "adaptive"
        if self._s["rate"] is None:
            s = dict(self._s)
            s["rate"], s["work_rate"], s["state"], n_sim = self._measure(
                s["h"], s["state"], st.initial_settle_cycles
            )
            if adaptive and st.estimate_noise:
                # two more cycles on the same profile: their rate fields differ only by the
                # cycle-to-cycle variability of the dynamics (rms of the three pair changes)
                rates, works = [s["rate"]], [s["work_rate"]]
                for _ in range(2):
                    r, w, s["state"], n2 = self._measure(s["h"], s["state"], 0.0)
                    rates.append(r)
                    works.append(w)
                    n_sim += n2
                pairs = [(0, 1), (1, 2), (0, 2)]
                s["noise"] = float(
                    np.sqrt(np.mean([self._rate_change(rates[j], rates[i]) ** 2 for i, j in pairs]))
                )
                s["rate"], s["work_rate"] = rates[-1], works[-1]
            s["cycles_simulated"] += n_sim
            self._s = s
            self._save()
        old = self._s
        if old["done"] >= self.target:
            return False
        stop = next(c for c in self._stops if c > old["done"])
        dn, dn_wanted = self._propose(old["rate"], stop)
        h_new = old["h"] + dn * old["rate"]
        rate_new, work_new, state_new, n_sim = self._measure(h_new, old["state"], st.settle_cycles)
        eta_raw = self._rate_change(rate_new, old["rate"])
        # variability adds in quadrature to the change caused by the profile update
        eta = math.sqrt(max(0.0, eta_raw**2 - old["noise"] ** 2)) - st.noise_floor
        eta = max(0.0, eta)
        s = dict(old)
        s["cycles_simulated"] = old["cycles_simulated"] + n_sim
        if adaptive and eta > st.reject_factor * st.tol and dn > st.dn_min:
            fac = max(0.2, 0.9 * st.tol / eta)
            s["dn_next"] = max(st.dn_min, int(dn * fac))
            s["history"] = [*old["history"], (old["done"], dn, eta_raw, 0)]
            self._s = s
            self._notify(dn, eta, accepted=False)
            return True
        s["history"] = [*old["history"], (old["done"], dn, eta_raw, 1)]
        s["normal_work"] = old["normal_work"] + dn * old["work_rate"]
        s["h"], s["rate"], s["work_rate"], s["state"] = h_new, rate_new, work_new, state_new
        s["done"] = old["done"] + dn
        if adaptive:
            fac = 2.0 if eta == 0 else min(2.0, max(0.2, 0.9 * st.tol / eta))
            nxt = int(dn * fac)
            if dn < dn_wanted and fac >= 1.0:  # clipped to a stop: do not lose the proposal
                nxt = max(nxt, dn_wanted)
            s["dn_next"] = int(min(st.dn_max, max(st.dn_min, nxt)))
        if s["done"] in self._stops:
            s["snapshots"] = [*old["snapshots"], (s["done"], h_new.copy(), s["normal_work"])]
        self._s = s
        self._save()
        self._notify(dn, eta, accepted=True)
        return s["done"] < self.target

    def _save(self) -> None:
        if self.checkpoint is not None:
            self.save_checkpoint()

    def _notify(self, dn: int, eta: float, *, accepted: bool) -> None:
        if self.on_update is not None:
            self.on_update(
                {
                    "cycles_done": self.cycles_done,
                    "target": self.target,
                    "dn": dn,
                    "max_depth": float(np.max(self._s["h"])),
                    "accepted": accepted,
                    "rate_change": eta,
                    "cycles_simulated": self.cycles_simulated,
                }
            )

    def run(self) -> xr.Dataset:
        """Advance to the target; return the wear map (:meth:`to_dataset`)."""
        while self.step():
            pass
        return self.to_dataset()

    def convergence_warning(self) -> str | None:
        """A message if an accepted update changed the wear-rate field too much, else None.

        A rate change beyond :data:`UNRESOLVED_RATE_CHANGE` (noise removed) means the update
        interval was too large for the profile feedback: the explicit update overshoots and the
        result is not converged in dN (the adaptive scheme rejects such updates).
        """
        hist = np.array(self._s["history"], dtype=float).reshape(-1, 4)
        acc = hist[hist[:, 3] == 1]
        if not len(acc):
            return None
        noise = float(self._s.get("noise", 0.0))
        eta = np.sqrt(np.maximum(acc[:, 2] ** 2 - noise**2, 0.0))
        worst = int(np.argmax(eta))
        if eta[worst] <= UNRESOLVED_RATE_CHANGE:
            return None
        return (
            f"the wear-rate field changed by {100 * eta[worst]:.0f} % over the update of "
            f"{int(acc[worst, 1])} cycles starting at {int(acc[worst, 0])} cycles: the update "
            "interval is too large to resolve the profile feedback and the result is not "
            "converged; use the adaptive scheme or a smaller dN"
        )

    # --- output -----------------------------------------------------------------------------
    def to_dataset(self, *, cylindricity: bool = True) -> xr.Dataset:
        """The wear map so far: snapshots, worn volume, cylindricity, the update history.

        If the target has not been reached (interrupted run), the current profile is added as a
        last snapshot and the attribute ``status`` says ``"partial"``.
        """
        s = self._s
        snaps = list(s["snapshots"])
        complete = s["done"] >= self.target
        if not complete and (not snaps or snaps[-1][0] != s["done"]):
            snaps.append((s["done"], s["h"].copy(), s["normal_work"]))
        cyc = np.array([c for c, _, _ in snaps], dtype=float)
        maps = np.stack([h for _, h, _ in snaps]) if snaps else np.zeros((0, *self.grid.shape))
        work = np.array([w for _, _, w in snaps], dtype=float)
        hist = np.array(s["history"], dtype=float).reshape(-1, 4)
        kw = self.settings.kw
        extra = {
            "normal_work": xr.DataArray(
                work,
                dims="cycles",
                attrs={
                    "units": "N m",
                    "long_name": "accumulated normal work integral F_n |v_t| dt (Archard's F_n s)",
                },
            ),
            "archard_volume": xr.DataArray(
                kw * work,
                dims="cycles",
                attrs={"units": "m3", "long_name": "kw times accumulated normal work"},
            ),
            "update_start": xr.DataArray(
                hist[:, 0],
                dims="update",
                attrs={"units": "1", "long_name": "cycles done before the update"},
            ),
            "update_dn": xr.DataArray(
                hist[:, 1],
                dims="update",
                attrs={"units": "1", "long_name": "cycles per update (dN)"},
            ),
            "update_rate_change": xr.DataArray(
                hist[:, 2],
                dims="update",
                attrs={
                    "units": "1",
                    "long_name": "relative change of the wear-rate field over the update",
                    "comment": "area-weighted L2 norm; the adaptive control uses it minus "
                    "the attribute rate_noise (cycle-to-cycle variability) and noise_floor",
                },
            ),
            "update_accepted": xr.DataArray(
                hist[:, 3].astype(np.int8),
                dims="update",
                attrs={
                    "units": "1",
                    "long_name": "update accepted (1) or rejected and redone (0)",
                    "flag_values": np.array([0, 1], dtype=np.int8),
                    "flag_meanings": "rejected accepted",
                },
            ),
        }
        st = self.settings
        attrs = {
            "kw_m2_per_N": kw,
            "wear_scheme": st.scheme,
            "wear_settings": json.dumps(to_jsonable(st), sort_keys=True),
            "cycles_target": self.target,
            "cycles_done": s["done"],
            "cycles_simulated": s["cycles_simulated"],
            "n_updates": int(np.sum(hist[:, 3])) if len(hist) else 0,
            "n_rejected": int(np.sum(hist[:, 3] == 0)) if len(hist) else 0,
            "rate_noise": s.get("noise", 0.0),
            "status": "complete" if complete else "partial",
            "wear_note": "Archard dh = kw p ds per point; explicit cycle updates of dN cycles, "
            f"each preceded by {st.settle_cycles:g} settling cycle(s) whose wear is discarded",
            "contact_model": str(describe_any(self.contact).get("model", "?")),
        }
        warning = self.convergence_warning()
        if warning:
            attrs["convergence_warning"] = warning
        return wear_map_dataset(
            maps, cyc, self.grid, cylindricity=cylindricity, extra=extra, attrs=attrs
        )


def resimulator(ds: xr.Dataset) -> Callable[[float], xr.Dataset]:
    """A function ``f(kw) -> Dataset`` that repeats the run of the wear map ``ds`` with another kw.

    The contact model and wear settings are rebuilt from the provenance ``ds`` carries (as
    written by ``jointwear sim wear`` or :func:`jointwear.io.save` with
    ``parameters={"contact": model.describe(), "wear": settings}``); the re-run stores the same
    snapshots. Use it as ``calibrate_kw(..., resimulate=resimulator(ds))``.
    """
    from jointwear.io import parse_provenance
    from jointwear.params import from_mapping
    from jointwear.sim._wear_contact import contact_from_description

    params = parse_provenance(ds).get("parameters") or {}
    if "contact" not in params or "wear" not in params:
        raise BadInputError(
            "the wear map does not record its contact model and wear settings in its provenance "
            "(written by 'jointwear sim wear'?); pass a resimulate function instead"
        )
    contact = contact_from_description(params["contact"])
    settings = from_mapping(WearSettings, params["wear"], where="wear")
    snaps = [float(c) for c in np.asarray(ds["cycles"].values)]
    target = max(snaps)

    def run(kw: float) -> xr.Dataset:
        return simulate_wear(
            contact=contact,
            cycles=target,
            settings=dataclasses.replace(settings, kw=kw),
            snapshots=snaps,
        )

    return run


def halved_schedule(ds: xr.Dataset) -> tuple[int, ...]:
    """The accepted update intervals of a wear map with each one split in two halves.

    ``WearSettings(scheme="schedule", schedule=halved_schedule(ds))`` repeats the run of ``ds``
    with half the update interval everywhere (the snapshots fall on the same cycles): the
    difference of the two results measures the convergence in dN.
    """
    acc = np.asarray(ds["update_accepted"].values) == 1
    seq = np.asarray(ds["update_dn"].values)[acc].astype(int)
    return tuple(int(x) for d in seq for x in (d // 2, d - d // 2) if x > 0)


def simulate_wear(
    params: Any = None,
    *,
    cycles: float = 1e6,
    kw: float | None = None,
    settings: WearSettings | None = None,
    contact: Any = None,
    cycle_function: Callable[..., Any] | None = None,
    snapshots: Sequence[float] | None = None,
    checkpoint: str | Path | None = None,
    resume: bool = False,
    initial_wear: np.ndarray | None = None,
    on_update: Callable[[dict[str, Any]], None] | None = None,
) -> xr.Dataset:
    """Simulate Archard wear of the bearing over ``cycles`` crank cycles.

    Parameters
    ----------
    params : SimParameters, optional
        Mechanism and joint parameters (default ``PARAMETER_SETS["zhang2023"]``); ignored when
        ``contact`` is given.
    cycles : float
        Target number of cycles.
    kw : float, optional
        Wear coefficient [m²/N]; overrides ``settings.kw``.
    settings : WearSettings, optional
        Update scheme and kw.
    contact : ContactModel, optional
        A contact model (e.g. :class:`~jointwear.sim.WinklerContact`); default the dynamics.
    cycle_function : callable, optional
        Replacement for :func:`jointwear.sim.run_cycles` (same signature).
    snapshots : sequence of float, optional
        Cycle counts to store (default 1, 2, 5 x 10^k and the target).
    checkpoint : path, optional
        Checkpoint file, written atomically after every update.
    resume : bool
        Continue from ``checkpoint`` (must exist and match the parameters).
    initial_wear : ndarray (Nl, Nd), optional
        Initial profile [m].
    on_update : callable, optional
        Progress callback (see :class:`WearRun`).

    Returns
    -------
    Dataset
        Wear map: ``wear_depth(cycles, z, theta)`` [m], ``worn_volume``, ``max_wear_depth``,
        ``cylindricity``, ``normal_work``, and the update history ``update_*``.
    """
    settings = settings or WearSettings()
    if kw is not None:
        settings = dataclasses.replace(settings, kw=kw)
    if contact is None:
        from jointwear.sim._wear_contact import DynamicContact

        if params is None:
            from jointwear.sim import PARAMETER_SETS

            params = PARAMETER_SETS["zhang2023"]
        contact = DynamicContact(params, cycle_function)
    if resume:
        if checkpoint is None:
            raise BadInputError("resume=True needs the checkpoint path")
        run = WearRun.resume(
            checkpoint, contact, settings, cycles=cycles, snapshots=snapshots, on_update=on_update
        )
    else:
        run = WearRun(
            contact,
            settings,
            cycles=cycles,
            snapshots=snapshots,
            checkpoint=checkpoint,
            initial_wear=initial_wear,
            on_update=on_update,
        )
    return run.run()


# --- calibration ------------------------------------------------------------------------------


@dataclass(frozen=True)
class KwCalibration:
    """Result of :func:`calibrate_kw`.

    Attributes
    ----------
    kw : float
        Calibrated wear coefficient [m²/N].
    kw_linear : float
        The linear estimate ``kw_sim * measured / simulated`` [m²/N].
    quantity : str
        What was matched: ``"max_depth"`` [m], ``"volume"`` [m³], ``"cylindricity"`` [m] or
        ``"map"`` (least-squares scale).
    cycles : float
        Cycle count at which the measurement was compared.
    measured : float
        The measured value (``"map"``: measured max depth) [m or m³].
    iterations : tuple of (kw, simulated value)
        Every simulation used: the given one and each re-simulation.
    linearity_error : float or None
        Relative mismatch of the first re-simulation with ``kw_linear`` (how far wear is from
        linear in kw); None if not re-simulated.
    converged : bool
        Whether the last re-simulation matched the measurement within ``rtol`` (True without
        re-simulation only means "linear estimate, unchecked").
    """

    kw: float
    kw_linear: float
    quantity: str
    cycles: float
    measured: float
    iterations: tuple[tuple[float, float], ...]
    linearity_error: float | None
    converged: bool


def _at_cycles(da: xr.DataArray, cycles: float) -> xr.DataArray:
    """Value of a snapshot variable at ``cycles`` (linear interpolation between snapshots)."""
    c = np.asarray(da["cycles"].values, dtype=float)
    if cycles < 0 or cycles > c.max() * (1 + 1e-12):
        raise BadInputError(
            f"the simulated wear map covers 0 .. {c.max():.6g} cycles; the measurement is at "
            f"{cycles:.6g} cycles - simulate at least that many"
        )
    if np.any(np.isclose(c, cycles, rtol=1e-9, atol=0)):
        return da.isel(cycles=int(np.argmin(np.abs(c - cycles))))
    if cycles < c.min():  # wear is zero at 0 cycles: interpolate from the origin
        return da.isel(cycles=0) * (cycles / c.min())
    return da.interp(cycles=cycles)


def _map_on(measured: xr.DataArray, sim: xr.DataArray) -> tuple[np.ndarray, np.ndarray]:
    """Simulated map interpolated at the measured (z, theta) points, both as flat arrays."""
    meas = conventions.to_canonical(measured)
    sim = conventions.to_canonical(sim)
    # periodic padding in theta
    th = sim["theta"].values
    padded = xr.concat(
        [
            sim.isel(theta=[-1]).assign_coords(theta=[th[-1] - 360.0]),
            sim,
            sim.isel(theta=[0]).assign_coords(theta=[th[0] + 360.0]),
        ],
        dim="theta",
    )
    zmin, zmax = float(sim["z"].min()), float(sim["z"].max())
    mz = meas["z"].values
    if mz.min() < zmin - 1e-9 or mz.max() > zmax + 1e-9:
        raise BadInputError(
            f"the measured map spans z = {mz.min():.4g} .. {mz.max():.4g} m, beyond the simulated "
            f"bearing ({zmin:.4g} .. {zmax:.4g} m); check the axial origin (z = 0 at mid-width)"
        )
    s = padded.interp(z=meas["z"], theta=meas["theta"]).transpose("z", "theta").values
    m = meas.transpose("z", "theta").values
    ok = np.isfinite(m) & np.isfinite(s)
    return m[ok], s[ok]


def _quantity(sim: xr.Dataset, quantity: str, cycles: float, measured: Any) -> tuple[float, float]:
    """(measured value, simulated value) for the calibration quantity."""
    if quantity == "max_depth":
        return float(measured), float(_at_cycles(sim["max_wear_depth"], cycles))
    if quantity == "volume":
        return float(measured), float(_at_cycles(sim["worn_volume"], cycles))
    if quantity == "cylindricity":
        value = float(_at_cycles(sim["cylindricity"], cycles))
        if not np.isfinite(value):
            raise BadInputError(
                "the simulated map has no cylindricity (jointwear.metrology is not available)"
            )
        return float(measured), value
    m, s = _map_on(measured, _at_cycles(sim["wear_depth"], cycles))
    if not np.any(s > 0):
        raise BadInputError("the simulated map shows no wear where the measurement has data")
    scale = float(np.dot(m, s) / np.dot(s, s))  # least squares m ~ scale * s
    # express as (target, simulated) so that target / simulated = scale
    return scale * float(np.max(s)), float(np.max(s))


def calibrate_kw(
    simulated: xr.Dataset,
    measured: float | xr.DataArray | xr.Dataset,
    *,
    quantity: Literal["max_depth", "volume", "cylindricity", "map"] | None = None,
    cycles: float | None = None,
    resimulate: Callable[[float], xr.Dataset] | None = None,
    rtol: float = 0.02,
    max_iter: int = 6,
) -> KwCalibration:
    """Estimate kw so that the simulated wear matches a measurement.

    Archard wear is linear in kw only while the profile feedback is weak (the pressure
    distribution does not change much as the bore wears). The first estimate assumes that
    linearity, ``kw1 = kw_sim * measured / simulated``. If ``resimulate`` is given, the
    assumption is checked by simulating again with ``kw1``; the mismatch is reported as
    ``linearity_error`` and the estimate refined with a power-law (secant in log-log) update
    until the re-simulation matches within ``rtol``.

    Parameters
    ----------
    simulated : Dataset
        A wear map from :func:`simulate_wear` (carries ``kw_m2_per_N``).
    measured : float or DataArray or Dataset
        Measured maximum depth [m] (``quantity="max_depth"``), worn volume [m³]
        (``"volume"``), growth of the bore's cylindricity [m] (``"cylindricity"``: measured
        after minus before, the simulated bore starting as a perfect cylinder), or a measured
        wear map ``wear_depth(z, theta)`` [m] with a stated angle
        convention (``"map"``: least-squares scale of the simulated map onto it).
    quantity : {"max_depth", "volume", "cylindricity", "map"}, optional
        Default ``"map"`` for a map, else ``"max_depth"``.
    cycles : float, optional
        Cycle count of the measurement; default the map's ``cycles`` coordinate/attribute, or
        the last simulated snapshot.
    resimulate : callable, optional
        ``f(kw) -> Dataset``: re-runs the simulation with another kw (same snapshots).
    rtol : float
        Relative tolerance of the match after re-simulation.
    max_iter : int
        Maximum number of re-simulations.
    """
    if isinstance(measured, xr.Dataset):
        if "wear_depth" not in measured:
            raise BadInputError("the measured dataset has no 'wear_depth' variable")
        measured = measured["wear_depth"]
    is_map = isinstance(measured, xr.DataArray)
    quantity = quantity or ("map" if is_map else "max_depth")
    if quantity not in ("max_depth", "volume", "cylindricity", "map"):
        raise BadInputError(
            f"quantity must be 'max_depth', 'volume', 'cylindricity' or 'map', got {quantity!r}"
        )
    if is_map:
        if quantity != "map":
            raise BadInputError(f"a measured map needs quantity='map', got {quantity!r}")
        if "cycles" in measured.dims:
            if measured.sizes["cycles"] != 1:
                raise BadInputError("give one measured map (select one cycles value)")
            measured = measured.isel(cycles=0)
        if cycles is None and "cycles" in measured.coords:
            cycles = float(measured["cycles"].values)
        measured = measured.drop_vars("cycles", errors="ignore")
    elif quantity == "map":
        raise BadInputError("quantity='map' needs a measured wear map (DataArray or Dataset)")
    else:
        value = float(measured)
        if not (np.isfinite(value) and value > 0):
            raise BadInputError(f"measured {quantity} must be positive, got {measured!r}")
    if cycles is None:
        cycles = float(simulated["cycles"].values[-1])
    kw0 = _check_kw(simulated.attrs.get("kw_m2_per_N", np.nan), name="kw of the simulated map")
    target, value = _quantity(simulated, quantity, cycles, measured)
    if not value > 0:
        raise BadInputError(f"the simulated {quantity} at {cycles:.6g} cycles is zero")
    if target <= 0:
        raise BadInputError("the measured wear is not positive; kw cannot be calibrated")
    kw_lin = _check_kw(kw0 * target / value, name="calibrated kw")
    iters = [(kw0, value)]
    if resimulate is None:
        return KwCalibration(kw_lin, kw_lin, quantity, cycles, target, tuple(iters), None, False)
    kw = kw_lin
    lin_err = None
    converged = False
    for _ in range(max_iter):
        ds = resimulate(kw)
        t, v = _quantity(ds, quantity, cycles, measured)
        iters.append((kw, v))
        err = v / target - 1.0
        if lin_err is None:
            lin_err = err
        if abs(err) <= rtol:
            converged = True
            break
        (k1, v1), (k2, v2) = iters[-2], iters[-1]
        beta = 1.0
        if k1 != k2 and v1 > 0 and v2 > 0:
            beta = math.log(v2 / v1) / math.log(k2 / k1)
            beta = min(max(beta, 0.2), 2.0)
        kw = _check_kw(kw * (target / v) ** (1.0 / beta), name="calibrated kw")
    return KwCalibration(kw, kw_lin, quantity, cycles, target, tuple(iters), lin_err, converged)
