"""The simulator's record: the kernel's diagnostics rows as a contract Dataset.

Every mechanism records the same clearance-joint variables (:func:`joint_variables`) and the
per-point wear maps (:func:`add_maps`); its own bodies' variables come from its side module
(:mod:`jointwear.sim._four_bar_record`, :mod:`jointwear.sim._slider_record`), written with the
helpers here (:func:`variable`, :func:`body_motion`, :func:`crank_angle`).
"""

from __future__ import annotations

import json
import math

import numpy as np
import xarray as xr

from jointwear import conventions
from jointwear.params import to_jsonable
from jointwear.sim.kernels import _layout as kn
from jointwear.sim.mechanisms import mechanism_of
from jointwear.sim.parameters import SimParameters
from jointwear.sim.wearmap import layer_positions

__all__ = [
    "AXIS",
    "CONTACT_MODES",
    "variable",
    "vector",
    "body_motion",
    "crank_angle",
    "joint_variables",
    "dataset",
    "add_maps",
    "layers",
]

#: Dimensions of a vector variable of the record.
AXIS = ("time", "axis")

#: Contact modes recorded in ``contact_mode`` (flag value -> meaning).
CONTACT_MODES: dict[int, str] = {
    kn.MODE_FREE: "free_flight",
    kn.MODE_POINT: "single_point",
    kn.MODE_LINE: "line",
    kn.MODE_TWO: "two_point",
    kn.MODE_AXIAL: "axial",
    kn.MODE_AXIAL_RADIAL: "axial_and_radial",
    kn.MODE_IDEAL: "ideal_joint",
}


def variable(dims: str | tuple[str, ...], values: np.ndarray, units: str, long_name: str, **attrs):
    """One record variable: ``(dims, values, attrs)`` with ``units`` and ``long_name`` first."""
    return dims, values, {"units": units, "long_name": long_name, **attrs}


def vector(diag: np.ndarray, k: int) -> np.ndarray:
    """The 3-vector that starts at column ``k`` of the diagnostics rows, (time, axis)."""
    return diag[:, k : k + 3]


def body_motion(body: str, label: str, position: np.ndarray, velocity: np.ndarray) -> dict:
    """``<body>_position`` [m] and ``<body>_velocity`` [m/s] of a body's centre of mass."""
    return {
        f"{body}_position": variable(
            AXIS, position, "m", f"position of the {label} centre of mass"
        ),
        f"{body}_velocity": variable(
            AXIS, velocity, "m s-1", f"velocity of the {label} centre of mass"
        ),
    }


def crank_angle(th1: np.ndarray) -> tuple:
    """The ``crank_angle`` variable, wrapped to [0, 2 pi)."""
    return (
        "time",
        np.mod(th1, 2 * math.pi),
        conventions.variable_attrs("crank_angle", note="wrapped to [0, 2 pi)"),
    )


def joint_variables(diag: np.ndarray, joint: str = "C") -> dict:
    """The clearance joint's record variables, the same for every mechanism (``joint``: its
    name in the long names)."""
    v = conventions.variable_attrs
    mode = np.where(np.isfinite(diag[:, kn.D_MODE]), diag[:, kn.D_MODE], 0).astype(np.int8)
    pen = np.maximum(np.maximum(diag[:, kn.D_PEN], diag[:, kn.D_PENAX]), 0.0)
    at = f"of joint {joint}, global frame"
    return {
        "journal_offset": (
            AXIS,
            vector(diag, kn.D_OFFSET),
            v(
                "journal_offset",
                frame="bearing frame: z along the bearing axis, -x = theta 0 direction",
            ),
        ),
        "bearing_centre_position": variable(
            AXIS, vector(diag, kn.D_BEAR_POS), "m", f"position of the bearing centre {at}"
        ),
        "journal_centre_position": variable(
            AXIS, vector(diag, kn.D_JOUR_POS), "m", f"position of the journal centre {at}"
        ),
        "eccentricity": variable(
            "time",
            np.hypot(diag[:, kn.D_OFFSET], diag[:, kn.D_OFFSET + 1]),
            "m",
            "radial eccentricity of the journal centre in the bearing "
            "(|journal_offset| in the bearing's x-y plane)",
        ),
        "journal_axis": variable(
            AXIS, vector(diag, kn.D_AXIS), "1", "unit vector of the journal axis, bearing frame"
        ),
        "journal_tilt": variable(
            "time", diag[:, kn.D_TILT], "rad", "angle between the journal and bearing axes"
        ),
        "bearing_force": variable(
            AXIS,
            vector(diag, kn.D_FORCE),
            "N",
            "resultant contact force on the bearing, global frame",
        ),
        "contact_force": ("time", diag[:, kn.D_FMAG], v("contact_force")),
        "contact_force_normal": variable(
            "time", diag[:, kn.D_FN], "N", "magnitude of the resultant normal contact force"
        ),
        "contact_force_tangential": variable(
            "time", diag[:, kn.D_FT], "N", "magnitude of the resultant friction force"
        ),
        "axial_force": variable(
            "time", diag[:, kn.D_FAX], "N", "normal force of the end-face (thrust) contacts"
        ),
        "contact_mode": variable(
            "time",
            mode,
            "1",
            f"contact mode of joint {joint}",
            flag_values=np.array(sorted(CONTACT_MODES), dtype=np.int8),
            flag_meanings=" ".join(CONTACT_MODES[k] for k in sorted(CONTACT_MODES)),
        ),
        "penetration": variable(
            "time", pen, "m", f"largest penetration in joint {joint} (bore or end faces)"
        ),
        "contact_stiffness": variable(
            "time",
            diag[:, kn.D_K],
            "N m-1.5",
            "contact stiffness K(t) at the deepest contacting slice (0 if none)",
        ),
        "mechanical_energy": variable(
            "time", diag[:, kn.D_ENERGY], "J", "kinetic + gravitational + elastic contact energy"
        ),
    }


def dataset(
    params: SimParameters, mechanism_variables: dict, diag: np.ndarray, t_rel: np.ndarray, t0: float
) -> xr.Dataset:
    """The contract Dataset from the mechanism's variables and the recorded diagnostics.

    ``t_rel`` is the time since the start of the run [s], which began at ``t0`` [s] of
    simulated time.
    """
    mech = mechanism_of(params)
    data = dict(mechanism_variables)
    data.update(joint_variables(diag, mech.joint(params)))
    time = xr.DataArray(
        t_rel,
        dims="time",
        attrs={
            "units": "s",
            "long_name": conventions.COORDINATES["time"][1],
            "simulation_time_at_start": float(t0),
        },
    )
    axis_c = xr.DataArray(
        np.array(["x", "y", "z"]), dims="axis", attrs={"long_name": "vector component"}
    )
    ds = xr.Dataset(
        {k: xr.Variable(d, np.asarray(val), attrs=a) for k, (d, val, a) in data.items()},
        coords={"time": time, "axis": axis_c},
    )
    ds.attrs["title"] = f"jointwear {mech.title} simulation with a 3D revolute clearance joint"
    ds.attrs["data_origin"] = "simulated"
    ds.attrs["source"] = "jointwear (sim.dynamics)"
    ds.attrs["parameter_set"] = params.name
    ds.attrs["joint_model"] = params.joint.model
    ds.attrs["contact_formulation"] = params.contact.formulation
    if params.contact.formulation == "per_point":
        ds.attrs["contact_formulation_note"] = (
            "the study's literal per-point sum: forces and wear work depend on the grid"
        )
    ds.attrs["wear_projection"] = params.contact.wear_projection
    ds.attrs["wear_pressure"] = params.contact.wear_pressure
    ds.attrs["impact_latch"] = params.contact.impact_latch
    ds.attrs["contact_stiffness_model"] = params.contact.stiffness
    ds.attrs["bearing_on"] = params.mechanism.bearing_on
    ds.attrs.update(mech.attrs(params))
    ds.attrs["parameters_json"] = json.dumps(to_jsonable(params))
    return ds


def layers(params: SimParameters) -> tuple[np.ndarray, np.ndarray]:
    """Axial positions [m] and trapezoidal weights of the bearing's layers."""
    j = params.joint
    return layer_positions(j.n_layers, j.bearing_width, j.axial_grading)


def add_maps(ds: xr.Dataset, params: SimParameters, ww: np.ndarray, area: np.ndarray) -> xr.Dataset:
    """Add the accumulated per-point maps over (z, theta) in the canonical angle convention."""
    z, _ = layers(params)
    nd = params.joint.n_points
    coords = {
        "z": conventions.z_coord(z, note="layer n = 0 at z = +wb/2 (eq. 2)"),
        "theta": conventions.theta_coord(np.arange(nd) * 360.0 / nd),
    }
    maps = xr.Dataset(
        {
            "wear_work": variable(
                ("z", "theta"),
                ww[0],
                "Pa m",
                "integral of contact pressure times sliding distance over the run",
            ),
            "sliding_distance": variable(
                ("z", "theta"), ww[1], "m", "sliding distance while in contact over the run"
            ),
            "point_area": variable(
                ("z", "theta"), area, "m2", "bearing surface area represented by each point"
            ),
        },
        coords=coords,
    )
    return xr.merge([ds, maps], combine_attrs="override")
