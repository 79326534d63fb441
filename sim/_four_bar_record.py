"""The four-bar's side of the simulator: packing its parameters, initial state, record variables.

:mod:`jointwear.sim.dynamics` drives the integrator; :mod:`jointwear.sim._record` builds the
clearance joint's part of the record for every mechanism. This module adds what is particular
to the four-bar (the slider-crank's counterpart: :mod:`jointwear.sim._slider_record`).
"""

from __future__ import annotations

import math

import numpy as np

from jointwear import conventions
from jointwear.errors import ParameterError
from jointwear.sim._record import AXIS, body_motion, crank_angle, variable, vector
from jointwear.sim.kernels import _layout as kn
from jointwear.sim.mechanism import loop_closure, quaternion_to_matrix, rotation_xzy_angles
from jointwear.sim.parameters import SimParameters

__all__ = ["pack_mechanism", "initial_vector", "INITIAL_STEP", "ANGLE_FLAGS", "variables"]

#: State components integrated with absolute tolerance only (positions and angles).
ANGLE_FLAGS = {
    "clearance": np.array([1, 1, 0, 0, 1, 1, 1, 1, 0, 0, 0], dtype=np.int64),
    "ideal": np.array([1, 1, 1, 0, 0, 0], dtype=np.int64),
}


#: First step size of the integrator from the initial state [s], per joint model.
INITIAL_STEP = {"clearance": 1e-5, "ideal": 1e-4}


def initial_vector(params: SimParameters) -> np.ndarray:
    """State at the documented initial configuration.

    Crank at ``initial_crank_angle_deg`` turning at the nominal speed; coupler and follower at
    the ideal four-bar's loop-closure angles and rates (joint C above the ground line); the
    journal centred in the bearing and aligned with it; follower not rotated out of plane.
    """
    m = params.mechanism
    th1 = math.radians(m.initial_crank_angle_deg)
    th2, th3, w2, w3 = (float(v) for v in loop_closure(th1, m))
    if params.joint.model == "ideal":
        if not m.driver:
            raise ParameterError(
                "joint.model = 'ideal' needs mechanism.driver = true (the ideal four-bar is "
                "kinematically driven); use the clearance model for a free crank"
            )
        return np.array([th1, th2, th3, m.crank_speed, w2, w3])
    # follower in the x-y plane at the ideal angle: bearing and journal centres coincide
    a = th3 - math.pi / 2
    q = np.array([math.cos(a / 2), 0.0, 0.0, math.sin(a / 2)])
    return np.array([th1, th2, m.crank_speed, w2, *q, 0.0, 0.0, w3])


def pack_mechanism(params: SimParameters, P: np.ndarray, IP: np.ndarray) -> None:
    """Write the four-bar's slots of the kernel parameter arrays."""
    m = params.mechanism
    P[kn.L1], P[kn.L2], P[kn.L3], P[kn.L4] = (
        m.crank_length,
        m.coupler_length,
        m.follower_length,
        m.ground_length,
    )
    P[kn.M1], P[kn.M2], P[kn.M3] = m.crank_mass, m.coupler_mass, m.follower_mass
    P[kn.I1], P[kn.I2] = m.crank_inertia, m.coupler_inertia
    P[kn.I3X], P[kn.I3Y], P[kn.I3Z] = m.follower_inertia
    P[kn.GRAV] = m.gravity
    P[kn.JOFF] = m.joint_offset
    P[kn.OMEGA] = m.crank_speed
    IP[kn.DRIVER] = 1 if m.driver else 0
    IP[kn.ON_COUPLER] = 1 if m.bearing_on == "coupler" else 0


def variables(params: SimParameters, diag: np.ndarray) -> dict:
    """The four-bar's record variables (name -> (dims, values, attrs))."""
    v = conventions.variable_attrs
    quat = diag[:, kn.D_QUAT : kn.D_QUAT + 4]
    ok = np.all(np.isfinite(quat), axis=1) & (np.linalg.norm(quat, axis=1) > 0)
    rot = np.full((len(diag), 3), np.nan)
    if ok.any():
        rot[ok] = rotation_xzy_angles(quaternion_to_matrix(quat[ok]))
    return {
        "crank_angle": crank_angle(diag[:, kn.D_TH1]),
        "coupler_angle": variable(
            "time", diag[:, kn.D_TH2], "rad", "coupler angle from +x, counter-clockwise"
        ),
        "follower_angle": variable(
            "time",
            diag[:, kn.D_TH3],
            "rad",
            "angle of the follower (D to C) projected on the x-y plane, from +x",
        ),
        "follower_rotation": variable(
            AXIS,
            rot,
            "rad",
            "follower rotations about x, y, z from the vertical reference, "
            "R = Rx Rz Ry (eq. 4 order)",
        ),
        **body_motion("crank", "crank", vector(diag, kn.D_CRANK_POS), vector(diag, kn.D_CRANK_VEL)),
        **body_motion(
            "coupler", "coupler", vector(diag, kn.D_COUP_POS), vector(diag, kn.D_COUP_VEL)
        ),
        "follower_position": (AXIS, vector(diag, kn.D_FOLL_POS), v("follower_position")),
        "follower_velocity": (AXIS, vector(diag, kn.D_FOLL_VEL), v("follower_velocity")),
        "follower_angular_velocity": variable(
            AXIS,
            vector(diag, kn.D_FOLL_OMEGA),
            "rad s-1",
            "angular velocity of the follower, global frame",
        ),
    }
