"""The wear map Dataset of a wear run: snapshots, their accuracy and the update history; and the
run's verdicts on itself (:class:`RunOutput`, a base of :class:`~jointwear.sim.wear.WearRun`:
rate noise, contact validity, convergence and accuracy notes)."""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from typing import Any

import numpy as np
import xarray as xr

from jointwear.params import to_jsonable
from jointwear.sim.validity import contact_validity
from jointwear.sim.wear import _control as ctl
from jointwear.sim.wear._contact import describe_any
from jointwear.sim.wear._control import COVERAGE
from jointwear.sim.wearmap import BearingGrid, wear_map_dataset

__all__ = ["HISTORY", "build_dataset", "RunOutput"]

_U_NOTE = (
    f"expanded uncertainty (coverage factor k = {COVERAGE:g}) from the update control: "
    "explicit-Euler truncation dN (r_new - r_old) / 2 summed over the updates, and the "
    "statistical error of each averaged wear rate added in quadrature; NaN = not assessed "
    "(fixed or schedule scheme, one cycle per measurement). It covers the time integration "
    "and the cycle-to-cycle variability of the dynamics, not the model or its parameters"
)


def _u_attrs(units: str, of: str) -> dict[str, Any]:
    return {
        "units": units,
        "long_name": f"expanded uncertainty of {of}",
        "coverage_factor": COVERAGE,  # the data contract: readers divide by it for a standard u
        "comment": _U_NOTE,
    }


def build_dataset(
    snaps: Sequence[tuple],
    hist: np.ndarray,
    grid: BearingGrid,
    *,
    kw: float,
    attrs: dict[str, Any],
    cylindricity: bool = True,
) -> xr.Dataset:
    """Contract wear map from the snapshots ``(cycles, h, normal_work, depth_u, volume_u)``.

    ``hist`` holds one row per update: start, dN, rate change, accepted, cycles averaged,
    noise of the rate change.
    """
    n = len(snaps)
    shape = (0, *grid.shape)
    cyc = np.array([sn[0] for sn in snaps], dtype=float)
    maps = np.stack([sn[1] for sn in snaps]) if n else np.zeros(shape)
    work = np.array([sn[2] for sn in snaps], dtype=float)
    u_maps = np.stack([sn[3] for sn in snaps]) if n else np.zeros(shape)
    u_vol = np.array([sn[4] for sn in snaps], dtype=float)
    # u of the maximum depth: the u of the point holding it
    flat = maps.reshape(n, -1)
    imax = np.argmax(flat, axis=1) if n else np.zeros(0, dtype=int)
    u_max = u_maps.reshape(n, -1)[np.arange(n), imax] if n else np.zeros(0)
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
        "max_wear_depth_u": xr.DataArray(
            u_max, dims="cycles", attrs=_u_attrs("m", "the largest wear depth")
        ),
        "worn_volume_u": xr.DataArray(
            u_vol, dims="cycles", attrs=_u_attrs("m3", "the worn volume")
        ),
        "update_start": xr.DataArray(
            hist[:, 0],
            dims="update",
            attrs={"units": "1", "long_name": "cycles done before the update"},
        ),
        "update_dn": xr.DataArray(
            hist[:, 1], dims="update", attrs={"units": "1", "long_name": "cycles per update (dN)"}
        ),
        "update_rate_change": xr.DataArray(
            hist[:, 2],
            dims="update",
            attrs={
                "units": "1",
                "long_name": "relative change of the wear-rate field over the update",
                "comment": "area-weighted L2 norm of the change of the averaged rate; the "
                "adaptive control removes update_rate_change_noise from it in quadrature",
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
        "update_cycles_averaged": xr.DataArray(
            hist[:, 4].astype(np.int32),
            dims="update",
            attrs={"units": "1", "long_name": "single cycles averaged in the rate measurement"},
        ),
        "update_rate_change_noise": xr.DataArray(
            hist[:, 5],
            dims="update",
            attrs={
                "units": "1",
                "long_name": "standard deviation of the rate change due to cycle-to-cycle "
                "variability (0 = not measured)",
            },
        ),
    }
    acc = hist[:, 3] == 1
    attrs = {
        **attrs,
        "n_updates": int(np.sum(acc)),
        "n_rejected": int(np.sum(~acc)),
        "accuracy_note": _U_NOTE,
    }
    ds = wear_map_dataset(maps, cyc, grid, cylindricity=cylindricity, extra=extra, attrs=attrs)
    ds["wear_depth_u"] = (
        ("cycles", "z", "theta"),
        u_maps[:, ::-1, :],  # layer order -> z ascending, as wear_depth
        _u_attrs("m", "the wear depth"),
    )
    return ds


#: Columns of the update history.
HISTORY = ("start", "dn", "rate_change", "accepted", "cycles_averaged", "rate_change_noise")


class RunOutput:
    """The verdicts and the result of :class:`~jointwear.sim.wear.WearRun` (a base of it): its
    rate noise, contact validity, convergence and accuracy notes, update history and wear map."""

    def rate_noise(self) -> float:
        """The run's relative single-cycle rate noise [1]: the adaptive scheme's last estimate,
        or the fixed/schedule schemes' probe on the final profile (NaN: not measured yet)."""
        if self.settings.scheme == "adaptive":
            return ctl.smoothed_noise(self._s["noise_hist"])
        return float(self._s.get("probe_noise", math.nan))

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
        if st.scheme != "adaptive" or not np.isfinite(ctl.smoothed_noise(self._s["noise_hist"])):
            return "not assessed", None
        n = int(self._s["noise_limited"])
        if n == 0:
            return "reached", None
        sigma = ctl.smoothed_noise(self._s["noise_hist"])
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
