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

Modules
-------
This module holds the cycle loop (:class:`WearRun`'s set-up, measurements and updates) and
:func:`simulate_wear`. The interval's proposal and the noise estimate are
:mod:`._control`'s; the run's fingerprint, checkpoints and resume are
:class:`._checkpoint.RunCheckpoints`, its verdicts and wear map :class:`._output.RunOutput`
(both bases of :class:`WearRun`); the dotted parameter overrides are :mod:`._overrides`.
"""

from __future__ import annotations

import dataclasses
import logging
import math
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from jointwear.errors import BadInputError
from jointwear.io import check_writable
from jointwear.sim.wear import _control as ctl
from jointwear.sim.wear._checkpoint import RunCheckpoints
from jointwear.sim.wear._contact import CycleWear
from jointwear.sim.wear._output import RunOutput
from jointwear.sim.wear._overrides import apply_overrides, overrides_record
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


class WearRun(RunCheckpoints, RunOutput):
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
                sigma = ctl.smoothed_noise(s["noise_hist"])
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
        accepted = sum(1 for item in old["history"] if item[3] == 1)
        dn, dn_wanted = ctl.propose_interval(
            st, old["dn_next"], accepted, before.rate, stop - old["done"]
        )
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
        sigma = ctl.smoothed_noise(s["noise_hist"])
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
        ds.attrs["parameter_overrides"] = overrides_record(overrides)
    return ds
