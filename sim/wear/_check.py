"""The single-run accuracy check of a wear map: repeat it with halved intervals or a halved grid.

``tol`` sets the update control's target, but on a noise-limited rig (``accuracy_status = "not
reached"`` in every update) the controller aims at the noise's detection limit instead and a
smaller ``tol`` changes nothing (bit-identical runs). What checks the stated accuracy is the
run repeated with every update interval halved (:func:`halved_schedule`): its maximum depth
and volume must differ from the run's by less than the run's stated expanded uncertainty
(k = 2). The halved grid (spacing halved in z and theta, the same intervals) measures the
discretisation error, which the stated accuracy does not contain; it is compared with the same
figure to say whether that error is negligible. The multi-run verification study (grid and
interval refinement with replicates) is ``jointwear sim verify``.
"""

from __future__ import annotations

import dataclasses
import json
import math
from typing import Any

import numpy as np
import xarray as xr

from jointwear.errors import BadInputError

__all__ = ["CHECK_KINDS", "RESOLUTION", "check_accuracy", "describe_check"]

#: The checks: name -> what is halved.
CHECK_KINDS = {
    "interval": "every accepted update interval split in two (scheme = schedule)",
    "grid": "layer and point spacing halved (2 Nl - 1 layers, 2 Nd points), same intervals",
}

#: Relative changes below this count as consistent: the comparison's own resolution (a
#: deterministic contact model states a volume accuracy of ~1e-6 while halving its intervals
#: moves the volume by ~1e-4 through the changed trajectory, a difference of no consequence).
RESOLUTION: float = 1e-3

#: Quantities compared at the target: name -> name of its expanded uncertainty (or None).
_QUANTITIES = {
    "max_wear_depth": "max_wear_depth_u",
    "worn_volume": "worn_volume_u",
    "cylindricity": None,
}


def _accepted_intervals(ds: xr.Dataset) -> tuple[int, ...]:
    acc = np.asarray(ds["update_accepted"].values) == 1
    return tuple(int(d) for d in np.asarray(ds["update_dn"].values)[acc])


def _refined(contact: Any) -> Any:
    """The same contact model on a grid with half the spacing."""
    from jointwear.params import replace_nested
    from jointwear.sim.wearmap import BearingGrid

    nl, nd = contact.grid.shape
    if hasattr(contact, "params"):  # the dynamics
        params = replace_nested(
            contact.params, **{"joint.n_layers": 2 * nl - 1, "joint.n_points": 2 * nd}
        )
        return type(contact)(params, contact.cycle_function)
    grid = getattr(contact, "grid", None)
    fields = dataclasses.fields(contact) if dataclasses.is_dataclass(contact) else ()
    on_grid = [
        f.name
        for f in fields
        if isinstance(getattr(contact, f.name), np.ndarray)
        and getattr(contact, f.name).shape == (nl, nd)
    ]
    if fields and isinstance(grid, BearingGrid) and not on_grid:  # prescribed models
        finer = dataclasses.replace(grid, n_layers=2 * nl - 1, n_points=2 * nd)
        return dataclasses.replace(contact, grid=finer)
    if on_grid:
        raise BadInputError(
            f"the grid check cannot refine {type(contact).__name__}: its {', '.join(on_grid)} "
            "is given on the run's grid - check the intervals only"
        )
    raise BadInputError(
        f"the grid check needs a contact model with a grid it can refine; "
        f"{type(contact).__name__} has none - check the intervals only"
    )


def _compare(base: xr.Dataset, other: xr.Dataset) -> dict[str, dict[str, Any]]:
    out = {}
    for q, uname in _QUANTITIES.items():
        a = float(base[q].isel(cycles=-1))
        b = float(other[q].isel(cycles=-1))
        u = float(base[uname].isel(cycles=-1)) if uname and uname in base else math.nan
        if not math.isfinite(u):
            status = "not assessed"
        else:
            status = "consistent" if abs(b - a) <= max(u, RESOLUTION * abs(a)) else "inconsistent"
        out[q] = {
            "value": a,
            "check_value": b,
            "change": b - a,
            "relative_change": (b - a) / a if a else math.nan,
            "stated_u_k2": u if math.isfinite(u) else None,
            "status": status,
            "units": base[q].attrs.get("units", ""),
        }
    return out


def check_accuracy(
    ds: xr.Dataset,
    contact: Any,
    settings: Any,
    *,
    kinds: tuple[str, ...] = ("interval",),
) -> dict[str, Any]:
    """Repeat a finished wear run with halved intervals and/or a halved grid and compare.

    Parameters
    ----------
    ds : Dataset
        The run's wear map (:func:`simulate_wear` / ``jointwear sim wear``), complete.
    contact : ContactModel
        The contact model the run used.
    settings : WearSettings
        The run's settings.
    kinds : tuple of str
        Checks from :data:`CHECK_KINDS`.

    Returns
    -------
    dict
        Per kind: ``what``, ``quantities`` (value, check value, change, the run's expanded
        uncertainty and ``status``: "consistent" when the change is within it, "inconsistent",
        or "not assessed" without a stated uncertainty), ``status`` (worst of its quantities)
        and ``cycles_simulated``; and ``attrs`` to record in the file
        (``accuracy_check_<kind>`` as JSON, ``accuracy_check_status``).
    """
    from jointwear.sim.wear._loop import WearRun, halved_schedule

    unknown = [k for k in kinds if k not in CHECK_KINDS]
    if unknown:
        raise BadInputError(
            f"unknown accuracy check(s) {', '.join(unknown)}; choose from {', '.join(CHECK_KINDS)}"
        )
    if ds.attrs.get("status") != "complete":
        raise BadInputError("the accuracy check needs a complete wear run (status = complete)")
    cycles = float(ds["cycles"].values[-1])
    snaps = [float(c) for c in ds["cycles"].values]
    result: dict[str, Any] = {}
    for kind in kinds:
        if kind == "interval":
            model = contact
            schedule = halved_schedule(ds)
        else:
            model = _refined(contact)
            schedule = _accepted_intervals(ds)
        st = dataclasses.replace(settings, scheme="schedule", schedule=schedule)
        run = WearRun(model, st, cycles=cycles, snapshots=snaps)
        while run.step():
            pass
        other = run.to_dataset()
        quantities = _compare(ds, other)
        states = {v["status"] for v in quantities.values()} - {"not assessed"}
        status = (
            "inconsistent"
            if "inconsistent" in states
            else ("consistent" if states else "not assessed")
        )
        result[kind] = {
            "what": CHECK_KINDS[kind],
            "quantities": quantities,
            "status": status,
            "cycles_simulated": float(other.attrs["cycles_simulated"]),
        }
    overall = {r["status"] for r in result.values()}
    attrs = {f"accuracy_check_{k}": json.dumps(v, sort_keys=True) for k, v in result.items()}
    attrs["accuracy_check_status"] = (
        "inconsistent"
        if "inconsistent" in overall
        else ("consistent" if overall == {"consistent"} else "not assessed")
    )
    return {**result, "attrs": attrs}


def describe_check(kind: str, entry: dict[str, Any]) -> str:
    """One console line for a check."""
    parts = []
    for q, v in entry["quantities"].items():
        scale, unit = (1e9, "mm3") if v["units"] == "m3" else (1e6, "um")
        u = v["stated_u_k2"]
        parts.append(
            f"{q} {v['value'] * scale:.4g} -> {v['check_value'] * scale:.4g} {unit}"
            + (f" (change {v['change'] * scale:+.3g}, stated +-{u * scale:.2g})" if u else "")
        )
    return f"accuracy check, {kind} halved: {entry['status']}: " + "; ".join(parts)
