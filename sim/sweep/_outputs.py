"""Scalar outputs and fields of a sweep run, computed from a wear map or a cycle record.

Wear outputs (``run = "wear"``) are taken from the wear map at the target cycle count. Force and
motion outputs are statistics over recorded crank cycles: for ``run = "cycle"`` the ``cycles``
recorded after ``settle_cycles`` discarded; for ``run = "wear"`` one cycle simulated on the final
worn bore after one settling cycle (computed only if such an output or field is asked for).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import xarray as xr

__all__ = ["WEAR_OUTPUTS", "MOTION_OUTPUTS", "FIELDS", "wear_outputs", "motion_outputs"]

#: Scalar outputs of a wear run: name -> (units, long_name).
WEAR_OUTPUTS: dict[str, tuple[str, str]] = {
    "max_wear_depth": ("m", "largest wear depth over the bore at the target cycles"),
    "worn_volume": ("m3", "volume of bearing material removed by wear at the target cycles"),
    "cylindricity": ("m", "cylindricity (minimum zone) of the worn bore at the target cycles"),
    "max_wear_theta": (
        "degree",
        "angle of the largest wear depth (canonical convention: 0 along -x, clockwise from +z; "
        "NaN if nothing wore)",
    ),
    "max_wear_z": (
        "m",
        "axial position of the largest wear depth (0 at bearing mid-width, +z; NaN if nothing wore)",
    ),
    "normal_work": ("N m", "accumulated normal work integral F_n |v_t| dt (Archard's F_n s)"),
    "cycles_simulated": ("1", "crank cycles actually simulated by the wear run"),
    "n_updates": ("1", "accepted wear-profile updates"),
}

#: Scalar outputs from recorded crank cycles: name -> (units, long_name).
MOTION_OUTPUTS: dict[str, tuple[str, str]] = {
    "mean_contact_force": ("N", "time-mean magnitude of the contact force in joint C"),
    "peak_contact_force": ("N", "largest magnitude of the contact force in joint C"),
    "rms_contact_force": ("N", "root mean square of the contact force magnitude in joint C"),
    "mean_axial_force": ("N", "time-mean normal force of the end-face (thrust) contacts"),
    "follower_velocity_rms": (
        "m s-1",
        "root mean square of the follower's centre-of-mass speed (|v|)",
    ),
    "max_penetration": ("m", "largest penetration in joint C (bore or end faces)"),
    "max_journal_tilt": ("rad", "largest angle between the journal and bearing axes"),
    "contact_fraction": ("1", "fraction of the time joint C is in contact"),
}

#: Fields a sweep can keep per run: name -> (dims besides run, units, long_name).
FIELDS: dict[str, tuple[tuple[str, ...], str, str]] = {
    "wear_depth": (("z", "theta"), "m", "wear depth at the target cycles"),
    "contact_force": (
        ("cycle_phase",),
        "N",
        "contact force magnitude over the recorded cycle(s), on a uniform grid of crank-cycle "
        "phase (linear interpolation of the solver's output samples)",
    ),
}

#: Samples per crank cycle of a kept ``contact_force`` history.
PHASE_SAMPLES = 360


def wear_outputs(ds: xr.Dataset) -> dict[str, float]:
    """Wear outputs of the last snapshot of a wear map (``jointwear.sim.simulate_wear``)."""
    last = ds.isel(cycles=-1)
    depth = last["wear_depth"]
    k = int(np.argmax(depth.values))
    iz, it = np.unravel_index(k, depth.shape)
    worn = float(depth.values.flat[k]) > 0  # an unworn bore has no location of maximum wear
    return {
        "max_wear_depth": float(last["max_wear_depth"]),
        "worn_volume": float(last["worn_volume"]),
        "cylindricity": float(last["cylindricity"]),
        "max_wear_theta": float(depth["theta"].values[it]) if worn else float("nan"),
        "max_wear_z": float(depth["z"].values[iz]) if worn else float("nan"),
        "normal_work": float(last["normal_work"]) if "normal_work" in ds else float("nan"),
        "cycles_simulated": float(ds.attrs.get("cycles_simulated", np.nan)),
        "n_updates": float(ds.attrs.get("n_updates", np.nan)),
    }


def motion_outputs(rec: xr.Dataset) -> dict[str, float]:
    """Force and motion statistics of a cycle record (``jointwear.sim.run_cycles`` dataset)."""
    f = np.asarray(rec["contact_force"].values, dtype=float)
    v = np.asarray(rec["follower_velocity"].values, dtype=float)
    speed2 = np.sum(v * v, axis=1)
    return {
        "mean_contact_force": float(np.mean(f)),
        "peak_contact_force": float(np.max(f)),
        "rms_contact_force": float(np.sqrt(np.mean(f * f))),
        "mean_axial_force": float(np.mean(rec["axial_force"].values)),
        "follower_velocity_rms": float(np.sqrt(np.mean(speed2))),
        "max_penetration": float(np.max(rec["penetration"].values)),
        "max_journal_tilt": float(np.nanmax(rec["journal_tilt"].values)),
        "contact_fraction": float(np.mean(np.asarray(rec["contact_mode"].values) != 0)),
    }


def force_history(rec: xr.Dataset, period: float, cycles: float) -> np.ndarray:
    """Contact force on ``PHASE_SAMPLES`` points per recorded cycle (phase 0 .. cycles)."""
    t = np.asarray(rec["time"].values, dtype=float)
    phase = (t - t[0]) / period
    grid = phase_grid(cycles)
    return np.interp(grid, phase, np.asarray(rec["contact_force"].values, dtype=float))


def phase_grid(cycles: float) -> np.ndarray:
    """The ``cycle_phase`` coordinate of a kept force history [cycles]."""
    n = max(2, round(PHASE_SAMPLES * cycles))
    return np.arange(n) / PHASE_SAMPLES


def available_outputs(run: str, model: Any = None) -> dict[str, tuple[str, str]]:
    """Outputs a run kind can give: name -> (units, long_name)."""
    if run == "wear":
        return {**WEAR_OUTPUTS, **MOTION_OUTPUTS}
    if run == "cycle":
        return dict(MOTION_OUTPUTS)
    return {
        k: (u, f"output {k} of the analytic function {model.name}")
        for k, u in model.outputs.items()
    }
