"""Archard wear of the bearing with cycle updates, adaptive update interval and checkpoints.

Model (reference study, notes section 4)
-----------------------------------------
Archard's law per bearing point, ``dh = kw p ds`` (eq. 19): a crank cycle simulated on the current
profile gives each point's *wear work* ``w = integral p |ds|`` [Pa m]; its wear rate is
``r = kw w`` [m per cycle]. The cycle-update strategy (Fig. 3 of the study) advances the profile by
``dN`` cycles at a time, ``h <- h + dN r(h)`` (explicit Euler in the cycle count), and re-simulates
on the new profile, so the contact geometry and the time-varying stiffness K(t) follow the wear.

Settling: after every profile update the simulation first runs ``settle_cycles`` cycles whose
wear is discarded (the journal re-seats on the new profile; start-up transients are not wear),
then measures the wear rate. The very first measurement is preceded by
``initial_settle_cycles``.

Update interval
---------------
``scheme="fixed"`` uses ``dN`` cycles per update and measures the rate on one cycle. Because
local pressure falls where the bore has worn, an explicit update with a too-large ``dN``
overshoots: points that wore too much lose contact, the load moves elsewhere, and the profile
oscillates and roughens (unstable).

``scheme="adaptive"`` (default) controls the relative change of the wear-rate field between two
updates, ``eta = ||r_new - r_old|| / ||r_old||`` (area-weighted L2 norm); for explicit Euler the
local error of an update, relative to its depth increment, is ``eta / 2``. Impacts make the
dynamics non-periodic, so every rate measurement averages several single cycles and their scatter
re-estimates the cycle-to-cycle variability on the current profile; the noise part of ``eta`` is
removed in quadrature, the controller aims at ``max(tol, detection limit)`` and averages more
cycles when the noise hides changes of ``tol`` (details in :mod:`jointwear.sim.wear._control`).
The next interval is ``dN * 0.9 tol_eff / eta`` (at most doubled, at least 0.2x); an update whose
``eta`` exceeds ``reject_factor * tol_eff`` is rejected and redone with a smaller interval. The
run always finishes; its accuracy (expanded, k = 2) is reported per point (``wear_depth_u``), for
the maximum depth and the volume, and ``accuracy_status`` says whether ``tol`` could be held.
``scheme="schedule"`` replays a list of intervals (:func:`halved_schedule` for convergence
checks). Accepted updates whose rate-field change exceeds both 50 % (noise removed) and the
detection limit of the run's own rate noise, in a quarter of the updates or more, set the
``convergence_warning`` attribute (:func:`._control.convergence_notes`); the fixed and schedule schemes,
which measure one cycle per update, measure that noise with one more cycle on the final
profile (:meth:`WearRun.step`).

kw
--
``kw`` is the dimensional wear coefficient [m³/(N m) = m²/N]; see :data:`DEFAULT_KW` and
docs/sim-wear.md for how the default was obtained.
"""

from __future__ import annotations

import dataclasses
import json
import logging
import math
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from jointwear.errors import BadInputError, ParameterError
from jointwear.io import check_writable
from jointwear.params import to_jsonable
from jointwear.sim.validity import contact_validity
from jointwear.sim.wear import _control as ctl
from jointwear.sim.wear._checkpoint import read_checkpoint, write_checkpoint
from jointwear.sim.wear._contact import CycleWear, describe_any
from jointwear.sim.wear._output import build_dataset
from jointwear.sim.wear._settings import (
    DEFAULT_CYCLES,
    DEFAULT_KW,
    KW_RANGE,
    WearSettings,
    default_snapshots,
)
from jointwear.sim.wearmap import BearingGrid

__all__ = [
    "DEFAULT_KW",
    "KW_RANGE",
    "WearSettings",
    "WearRun",
    "simulate_wear",
    "default_snapshots",
    "halved_schedule",
    "apply_overrides",
]

_log = logging.getLogger("jointwear.sim.wear")


#: Columns of the update history.
HISTORY = ("start", "dn", "rate_change", "accepted", "cycles_averaged", "rate_change_noise")


def _flatten(obj: Any, prefix: str = "") -> dict[str, Any]:
    out: dict[str, Any] = {}
    if isinstance(obj, Mapping):
        for k, v in obj.items():
            out.update(_flatten(v, f"{prefix}{k}."))
        return out
    out[prefix[:-1]] = obj
    return out


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
        File written atomically after every accepted update (safe versioned format, see
        :mod:`jointwear.sim.wear._checkpoint`).
    initial_wear : ndarray (Nl, Nd), optional
        Initial wear profile [m] (default unworn).
    on_update : callable, optional
        Called after every update with a dict (``cycles_done``, ``target``, ``dn``,
        ``max_depth``, ``accepted``, ``rate_change``, ``cycles_simulated``,
        ``cycles_averaged``).
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
        st = self.settings
        adaptive = st.scheme == "adaptive"
        self._s: dict[str, Any] = {
            "h": h0,
            "initial_wear": h0.copy(),
            "state": None,
            "sample": None,  # RateSample on the current profile
            "done": 0,
            "dn_next": int(st.dn),
            # the first measurement averages more cycles: it starts the noise estimate
            "m_next": min(st.max_average_cycles, max(st.average_cycles, 4)) if adaptive else 1,
            "noise_hist": [],  # relative single-cycle variability of recent measurements
            "budget": ctl.ErrorBudget.zero(self.grid.shape),
            "normal_work": 0.0,
            "cycles_simulated": 0.0,
            # accepted updates whose detection limit exceeded tol with max_average_cycles averaged
            "noise_limited": 0,
            "max_penetration": -math.inf,  # largest contact penetration simulated [m]
            "worst_detection": 0.0,
            "history": [],  # tuples, columns HISTORY
            "snapshots": [],  # (cycles, h, normal_work, depth_u, volume_u)
            # single-cycle rate noise on the final profile (fixed/schedule schemes), NaN: not yet
            "probe_noise": math.nan,
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
        taken = {snap[0] for snap in self._s["snapshots"]}
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
        fp = {
            "contact": to_jsonable(describe_any(self.contact)),
            "wear": to_jsonable(self.settings),
            "initial_wear_max": float(np.max(self._s["initial_wear"])),
            "initial_wear_sum": float(np.sum(self._s["initial_wear"])),
        }
        return json.loads(json.dumps(fp))  # as a checkpoint stores it (tuples become lists)

    # --- checkpoints ------------------------------------------------------------------------
    def save_checkpoint(self, path: str | Path | None = None) -> Path:
        """Write the complete state atomically to ``path`` or :attr:`checkpoint` (npz + JSON)."""
        path = Path(path) if path is not None else self.checkpoint
        if path is None:
            raise BadInputError("no checkpoint path given")
        return write_checkpoint(path, self.fingerprint(), self._s)

    @classmethod
    def start(
        cls,
        contact: Any,
        settings: WearSettings | None = None,
        *,
        resume: bool = False,
        **run: Any,
    ) -> WearRun:
        """A new run, ``WearRun(contact, settings, **run)``, or with ``resume`` the run of
        ``run["checkpoint"]`` continued (:meth:`resume`; the initial wear is the checkpoint's)."""
        if not resume:
            return cls(contact, settings, **run)
        checkpoint = run.pop("checkpoint", None)
        if checkpoint is None:
            raise BadInputError("resume=True needs the checkpoint path")
        run.pop("initial_wear", None)
        return cls.resume(checkpoint, contact, settings, **run)

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
            The checkpoint is missing, unreadable, of another format version, was written with
            different parameters (the message names them), or the target is below the cycles
            already done.
        """
        path = Path(checkpoint)
        old_fp, state = read_checkpoint(path)
        run = cls(
            contact,
            settings,
            cycles=max(float(cycles), 1.0),
            snapshots=None,
            checkpoint=path,
            on_update=on_update,
        )
        if isinstance(state, dict):  # checkpoints written before the noise probe existed
            state.setdefault("probe_noise", math.nan)
        if not isinstance(state, dict) or set(state) != set(run._s):
            raise BadInputError(
                f"checkpoint '{path}' does not hold a wear-run state this version understands; "
                "start over without --resume (the old checkpoint is then replaced)"
            )
        if np.shape(state["initial_wear"]) == run.grid.shape:
            run._s["initial_wear"] = state["initial_wear"]
        old = _flatten(old_fp)
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
                "Resume with the original parameters, or start over without --resume (the old "
                "checkpoint is then replaced)"
            )
        run._s = state
        run._set_target(cycles, snapshots)
        return run

    # --- the loop ---------------------------------------------------------------------------
    def _measure(
        self, h: np.ndarray, state: Any, settle: float, n: int
    ) -> tuple[ctl.RateSample, Any, float, float]:
        """Settle on profile ``h``, then measure ``n`` single cycles.

        Returns (rate sample, contact state, cycles simulated, largest penetration [m]).
        """
        simulated = 0.0
        pen = -math.inf
        if settle > 0:
            res = self.contact.run(h, cycles=settle, state=state)
            state = res.state
            simulated += res.cycles
            pen = _max_known(pen, getattr(res, "max_penetration", math.nan))
        rates, works = [], []
        for _ in range(n):
            res: CycleWear = self.contact.run(h, cycles=1.0, state=state)
            state = res.state
            simulated += res.cycles
            pen = _max_known(pen, getattr(res, "max_penetration", math.nan))
            rate = self.settings.kw * np.asarray(res.wear_work, dtype=float) / res.cycles
            if np.any(rate < 0):
                raise BadInputError("the contact model returned negative wear work")
            rates.append(rate)
            works.append(res.normal_work / res.cycles)
        return ctl.sample_rates(rates, works, self.grid.point_area), state, simulated, pen

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

    def _sigma(self, noise_hist: list[float]) -> float:
        """Smoothed relative single-cycle variability (RMS of the last four estimates)."""
        vals = [v for v in noise_hist[-4:] if np.isfinite(v)]
        return math.sqrt(float(np.mean(np.square(vals)))) if vals else math.nan

    def step(self) -> bool:
        """Advance by one update (or one rejected attempt). Returns False at the target.

        The new state is assembled aside and swapped in with one assignment, so an interrupt
        (Ctrl-C) at any moment leaves a consistent state in memory and on disk.
        """
        st = self.settings
        adaptive = st.scheme == "adaptive"
        if self._s["sample"] is None:
            s = dict(self._s)
            s["sample"], s["state"], n_sim, pen = self._measure(
                s["h"], s["state"], st.initial_settle_cycles, s["m_next"]
            )
            s["max_penetration"] = _max_known(s.get("max_penetration", -math.inf), pen)
            s["noise_hist"] = [s["sample"].rel_noise]
            if adaptive:
                sigma = self._sigma(s["noise_hist"])
                s["m_next"] = ctl.cycles_to_average(
                    sigma, st.tol, st.average_cycles, st.max_average_cycles
                )
            s["cycles_simulated"] += n_sim
            self._s = s
            self._save()
        old = self._s
        if old["done"] >= self.target:
            return False
        stop = next(c for c in self._stops if c > old["done"])
        before: ctl.RateSample = old["sample"]
        dn, dn_wanted = self._propose(before.rate, stop)
        h_new = old["h"] + dn * before.rate
        new, state_new, n_sim, pen = self._measure(
            h_new, old["state"], st.settle_cycles, old["m_next"]
        )
        area = self.grid.point_area
        eta_raw = ctl.rate_change(new.rate, before.rate, area)
        s = dict(old)
        s["cycles_simulated"] = old["cycles_simulated"] + n_sim
        s["max_penetration"] = _max_known(old.get("max_penetration", -math.inf), pen)
        s["noise_hist"] = [*old["noise_hist"][-3:], new.rel_noise]
        sigma = self._sigma(s["noise_hist"])
        sig_eta = ctl.change_noise(sigma, new.n, before.n) if adaptive else 0.0
        eta = ctl.systematic_change(eta_raw, sig_eta)
        tol_eff = ctl.effective_tolerance(st.tol, sig_eta)
        if adaptive:
            s["m_next"] = ctl.cycles_to_average(
                sigma, st.tol, st.average_cycles, st.max_average_cycles
            )
        row = (old["done"], dn, eta_raw, 1, new.n, sig_eta)
        if adaptive and eta > st.reject_factor * tol_eff and dn > st.dn_min:
            fac = max(0.2, 0.9 * tol_eff / eta)
            s["dn_next"] = max(st.dn_min, int(dn * fac))
            s["history"] = [*old["history"], (*row[:3], 0, *row[4:])]
            self._s = s
            self._notify(dn, eta, new.n, accepted=False)
            return True
        s["history"] = [*old["history"], row]
        s["budget"] = old["budget"].add(dn, before, new)
        s["normal_work"] = old["normal_work"] + dn * before.work_rate
        s["h"], s["sample"], s["state"] = h_new, new, state_new
        s["done"] = old["done"] + dn
        if adaptive:
            if _noise_limited(tol_eff, st.tol) and new.n >= st.max_average_cycles:
                s["noise_limited"] = old["noise_limited"] + 1
                s["worst_detection"] = max(old["worst_detection"], tol_eff)
            nxt = ctl.next_interval(dn, eta, tol_eff, st.dn_min, st.dn_max)
            if dn < dn_wanted and nxt >= dn:  # clipped to a stop: do not lose the proposal
                nxt = max(nxt, min(dn_wanted, st.dn_max))
            s["dn_next"] = nxt
        if s["done"] >= self.target and not adaptive:
            s["probe_noise"], n_probe, pen = self._probe_noise(h_new, new, state_new)
            s["cycles_simulated"] += n_probe
            s["max_penetration"] = _max_known(s["max_penetration"], pen)
        if s["done"] in self._stops:
            b: ctl.ErrorBudget = s["budget"]
            s["snapshots"] = [
                *old["snapshots"],
                (s["done"], h_new.copy(), s["normal_work"], b.depth_u(), b.volume_u()),
            ]
        self._s = s
        self._save()
        self._notify(dn, eta, new.n, accepted=True)
        return s["done"] < self.target

    def _probe_noise(
        self, h: np.ndarray, last: ctl.RateSample, state: Any
    ) -> tuple[float, float, float]:
        """The single-cycle rate noise on the final profile (fixed and schedule schemes).

        Those schemes measure one cycle per update, so a run knows nothing of its own
        cycle-to-cycle variability; one more cycle on the final profile, continuing from
        ``state`` (which is left as it was: the run's result and any continuation do not
        change), paired with the last measured cycle, estimates it.

        Returns (relative noise of one cycle's rate field [1], cycles simulated, largest
        penetration [m]).
        """
        res: CycleWear = self.contact.run(h, cycles=1.0, state=state)
        rate = self.settings.kw * np.asarray(res.wear_work, dtype=float) / res.cycles
        pair = ctl.sample_rates(
            [last.rate, rate], [last.work_rate, res.normal_work / res.cycles], self.grid.point_area
        )
        return pair.rel_noise, res.cycles, getattr(res, "max_penetration", math.nan)

    def rate_noise(self) -> float:
        """The run's relative single-cycle rate noise [1]: the adaptive scheme's last estimate,
        or the fixed/schedule schemes' probe on the final profile (NaN: not measured yet)."""
        if self.settings.scheme == "adaptive":
            return self._sigma(self._s["noise_hist"])
        return float(self._s.get("probe_noise", math.nan))

    def _save(self) -> None:
        if self.checkpoint is not None:
            self.save_checkpoint()

    def _notify(self, dn: int, eta: float, m: int, *, accepted: bool) -> None:
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
                    "cycles_averaged": m,
                }
            )

    def run(self) -> xr.Dataset:
        """Advance to the target; return the wear map (:meth:`to_dataset`).

        A run whose accuracy could not reach ``tol`` still finishes; it logs a warning (logger
        ``jointwear.sim.wear``) and says so in the ``accuracy_warning`` attribute.
        """
        while self.step():
            pass
        ds = self.to_dataset()
        for key in ("accuracy_warning", "contact_validity_warning"):
            if key in ds.attrs:
                _log.warning("%s", ds.attrs[key])
        return ds

    # --- verdicts ---------------------------------------------------------------------------
    def contact_validity(self) -> dict[str, Any]:
        """The run's contact model against its validity limits (:mod:`jointwear.sim.validity`).

        Only the dynamics know their parameters and penetration; other contact models give
        an empty record.
        """
        params = getattr(self.contact, "params", None)
        if params is None:
            return {"status": "not assessed", "warning": None, "attrs": {}}
        pen = float(self._s.get("max_penetration", math.nan))
        return contact_validity(params, pen if pen > -math.inf else math.nan, kw=self.settings.kw)

    def _convergence_notes(self) -> tuple[str | None, str | None]:
        hist = self.history()
        acc = hist[hist[:, 3] == 1]
        adaptive = self.settings.scheme == "adaptive"
        sigma = self.rate_noise()
        # the adaptive scheme's noise per update; one cycle per measurement otherwise
        noise = acc[:, 5] if adaptive else np.full(len(acc), ctl.change_noise(sigma, 1, 1))
        return ctl.convergence_notes(acc, noise, sigma, measured=adaptive or np.isfinite(sigma))

    def convergence_warning(self) -> str | None:
        """A message if the update interval did not resolve the profile feedback, else None
        (:func:`~jointwear.sim.wear._control.convergence_notes`)."""
        return self._convergence_notes()[0]

    def rate_outliers(self) -> str | None:
        """A note on isolated updates whose rate change the noise does not explain, else None
        (:func:`~jointwear.sim.wear._control.convergence_notes`)."""
        return self._convergence_notes()[1]

    def history(self) -> np.ndarray:
        """The update history, one row per update, columns :data:`HISTORY`."""
        return np.array(self._s["history"], dtype=float).reshape(-1, len(HISTORY))

    def accuracy(self) -> tuple[str, str | None]:
        """(``accuracy_status``, warning or None): whether ``tol`` could be held throughout."""
        st = self.settings
        if st.scheme != "adaptive" or not np.isfinite(self._sigma(self._s["noise_hist"])):
            return "not assessed", None
        n = int(self._s["noise_limited"])
        if n == 0:
            return "reached", None
        sigma = self._sigma(self._s["noise_hist"])
        n_acc = int(np.sum(self.history()[:, 3] == 1))
        worst = float(self._s["worst_detection"])
        # what would hold tol: a tol above the noise's detection limit, or averaging enough
        # cycles to bring that limit under tol (it falls as 1/sqrt(cycles averaged))
        tol_ok = math.ceil(worst * 20.0 - 1e-9) / 20.0
        cycles_ok = math.ceil(st.max_average_cycles * (worst / st.tol) ** 2)
        return "not reached", (
            f"tol = {st.tol:g} not held in {n} of {n_acc} updates: the wear rate's "
            f"cycle-to-cycle noise ({100 * sigma:.0f} % per cycle) hid changes below "
            f"{100 * worst:.0f} %; the stated accuracy (the *_u, k = 2) includes it; to hold "
            f"tol, set tol = {tol_ok:g} or wear.max_average_cycles = {cycles_ok}."
        )

    # --- output -----------------------------------------------------------------------------
    def to_dataset(self, *, cylindricity: bool = True) -> xr.Dataset:
        """The wear map so far: snapshots with their accuracy, the update history.

        If the target has not been reached (interrupted run), the current profile is added as a
        last snapshot and the attribute ``status`` says ``"partial"``.
        """
        s = self._s
        snaps = list(s["snapshots"])
        complete = s["done"] >= self.target
        if not complete and (not snaps or snaps[-1][0] != s["done"]):
            b: ctl.ErrorBudget = s["budget"]
            snaps.append((s["done"], s["h"].copy(), s["normal_work"], b.depth_u(), b.volume_u()))
        status, warning = self.accuracy()
        st = self.settings
        attrs = {
            "kw_m2_per_N": st.kw,
            "wear_scheme": st.scheme,
            "wear_settings": json.dumps(to_jsonable(st), sort_keys=True),
            "cycles_target": self.target,
            "cycles_done": s["done"],
            "cycles_simulated": s["cycles_simulated"],
            "rate_noise": self.rate_noise(),
            "status": "complete" if complete else "partial",
            "accuracy_status": status,
            "wear_note": "Archard dh = kw p ds per point; explicit cycle updates of dN cycles, "
            f"each preceded by {st.settle_cycles:g} settling cycle(s) whose wear is discarded",
            "contact_model": str(describe_any(self.contact).get("model", "?")),
        }
        if warning:
            attrs["accuracy_warning"] = warning
        params = getattr(self.contact, "params", None)
        if params is not None:  # the dynamics: how a slice's force became wear work
            attrs["wear_pressure"] = params.contact.wear_pressure
        attrs.update(self.contact_validity()["attrs"])
        conv = self.convergence_warning()
        if conv:
            attrs["convergence_warning"] = conv
        outliers = self.rate_outliers()
        if outliers:
            attrs["rate_change_outliers"] = outliers
        return build_dataset(
            snaps, self.history(), self.grid, kw=st.kw, attrs=attrs, cylindricity=cylindricity
        )


def _max_known(a: float, b: float) -> float:
    """The larger of two penetrations; NaN (unknown) wins, -inf is "none measured yet"."""
    if math.isnan(a) or math.isnan(b):
        return math.nan
    return max(a, b)


def _noise_limited(tol_eff: float, tol: float) -> bool:
    """Whether the detection limit, not ``tol``, set the tolerance of an update."""
    return tol_eff > tol * (1 + 1e-12)


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
    cycles: float = DEFAULT_CYCLES,
    kw: float | None = None,
    settings: WearSettings | None = None,
    contact: Any = None,
    cycle_function: Callable[..., Any] | None = None,
    snapshots: Sequence[float] | None = None,
    checkpoint: str | Path | None = None,
    resume: bool = False,
    initial_wear: np.ndarray | None = None,
    on_update: Callable[[dict[str, Any]], None] | None = None,
    overrides: Mapping[str, float | str] | None = None,
) -> xr.Dataset:
    """Simulate Archard wear of the bearing over ``cycles`` crank cycles.

    Parameters
    ----------
    params : SimParameters, optional
        Mechanism and joint parameters (default ``PARAMETER_SETS[DEFAULT_PARAMETER_SET]``, the reference study); ignored when
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
    overrides : mapping of str to float or str, optional
        Dotted parameter names and values applied on top of ``params`` and ``settings``, e.g.
        ``{"mechanism.joint_offset": 0.005, "friction.dynamic_coefficient": 0.15,
        "wear.kw": 1e-15, "contact.formulation": "per_point"}`` (what a sensitivity sweep varies); see :func:`apply_overrides`.

    Returns
    -------
    Dataset
        Wear map: ``wear_depth(cycles, z, theta)`` [m], ``worn_volume``, ``max_wear_depth``,
        ``cylindricity``, ``normal_work``, their expanded uncertainties ``wear_depth_u``,
        ``max_wear_depth_u``, ``worn_volume_u`` (adaptive scheme; NaN = not assessed), and the
        update history ``update_*``.

    Examples
    --------
    A prescribed 20 N load sliding 0.02 m per cycle on a Winkler lining (no multibody
    dynamics, so it runs in a second); the worn volume follows Archard's law, kw F s N:

    >>> from jointwear.sim import BearingGrid, WearSettings, WinklerContact, simulate_wear
    >>> sim = simulate_wear(
    ...     contact=WinklerContact(BearingGrid(4, 36), load=20.0, sliding=0.02),
    ...     cycles=2000,
    ...     snapshots=[1000, 2000],
    ...     settings=WearSettings(scheme="fixed", dn=500),
    ... )
    >>> from jointwear.sim import DEFAULT_KW
    >>> print(
    ...     f"{float(sim['worn_volume'][-1]):.3g} m³, Archard {DEFAULT_KW * 20.0 * 0.02 * 2000:.3g} m³"
    ... )
    7.2e-13 m³, Archard 7.2e-13 m³
    >>> sim["wear_depth"].dims
    ('cycles', 'z', 'theta')
    """
    settings = settings or WearSettings()
    if kw is not None:
        settings = dataclasses.replace(settings, kw=kw)
    if contact is None:
        from jointwear.sim.wear._contact import DynamicContact

        if params is None:
            from jointwear.sim.parameters import DEFAULT_PARAMETER_SET, PARAMETER_SETS

            params = PARAMETER_SETS[DEFAULT_PARAMETER_SET]
        params, settings = apply_overrides(params, settings, overrides)
        contact = DynamicContact(params, cycle_function)
    elif overrides:
        _, settings = apply_overrides(None, settings, overrides)
    run = WearRun.start(
        contact,
        settings,
        cycles=cycles,
        snapshots=snapshots,
        checkpoint=checkpoint,
        resume=resume,
        initial_wear=initial_wear,
        on_update=on_update,
    )
    ds = run.run()
    if overrides:
        ds.attrs["parameter_overrides"] = json.dumps(
            {k: _provenance_value(v) for k, v in overrides.items()}, sort_keys=True
        )
    return ds


def _provenance_value(value: Any) -> Any:
    """An override's value as the provenance record keeps it: a number as float, a string
    (``contact.formulation``) or a boolean as given."""
    if isinstance(value, (str, bool, np.bool_)):
        return value if isinstance(value, str) else bool(value)
    return float(value)


def apply_overrides(
    params: Any, settings: WearSettings, overrides: Mapping[str, float | str] | None
) -> tuple[Any, WearSettings]:
    """Apply dotted overrides: ``"wear.<field>"`` to the settings, the rest to the parameters.

    Parameters
    ----------
    params : SimParameters or None
        Simulator parameters (None: only ``wear.*`` overrides are allowed, e.g. with a
        prescribed contact model).
    settings : WearSettings
        Wear settings.
    overrides : mapping
        ``{"mechanism.joint_offset": 0.0, "joint.thrust_radius": 9.0e-3, "wear.kw": 1e-15}``;
        SI values, as in the parameter file.

    Raises
    ------
    ParameterError
        An unknown name (the message lists the known ones) or an invalid value.
    """
    from jointwear.sim.mechanisms import replace_checked

    if not overrides:
        return params, settings
    wear = {k[5:]: v for k, v in overrides.items() if k.startswith("wear.")}
    sim = {k: v for k, v in overrides.items() if not k.startswith("wear.")}
    if wear:
        names = {f.name for f in dataclasses.fields(WearSettings)}
        unknown = sorted(set(wear) - names)
        if unknown:
            raise ParameterError(
                f"unknown wear setting(s) {', '.join('wear.' + u for u in unknown)}; known: "
                f"{', '.join(sorted(names))}"
            )
        settings = dataclasses.replace(settings, **wear)
    if sim:
        if params is None:
            raise ParameterError(
                f"override(s) {', '.join(sorted(sim))} need the multibody dynamics; a prescribed "
                "contact model takes only wear.* overrides"
            )
        if any("." not in k for k in sim):
            bad = sorted(k for k in sim if "." not in k)
            raise ParameterError(
                f"override(s) {', '.join(bad)} must be dotted names such as "
                "'mechanism.joint_offset' or 'wear.kw'"
            )
        params = replace_checked(params, sim, where="overrides")
    return params, settings
