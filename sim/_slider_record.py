"""The slider-crank's side of the simulator: packing its parameters, initial state, record.

:mod:`jointwear.sim.dynamics` drives the integrator; :mod:`jointwear.sim._record` builds the
clearance joint's part of the record for every mechanism. This module adds what is particular
to the slider-crank (its kernel is :mod:`jointwear.sim.kernels._slider_crank`; the four-bar's
counterpart: :mod:`jointwear.sim._four_bar_record`).
"""

from __future__ import annotations

import math

import numpy as np

import jointwear.sim.kernels._slider_crank as ks
from jointwear.sim._record import AXIS, body_motion, crank_angle, variable, vector
from jointwear.sim.kernels import _layout as kn
from jointwear.sim.parameters import SimParameters
from jointwear.sim.slider_crank import SliderCrankParameters, slider_crank_kinematics

__all__ = ["pack_mechanism", "initial_vector", "INITIAL_STEP", "ANGLE_FLAGS", "variables"]

#: State components integrated with absolute tolerance only (positions and angles).
ANGLE_FLAGS = {
    "clearance": np.array([1, 1, 0, 0, 1, 1, 1, 1, 0, 0, 0], dtype=np.int64),
    "ideal": np.array([1, 0], dtype=np.int64),
}


def pack_mechanism(params: SimParameters, P: np.ndarray, IP: np.ndarray) -> None:
    """Write the slider-crank's slots of the kernel parameter arrays."""
    m: SliderCrankParameters = params.mechanism  # type: ignore[assignment]
    P[kn.L1], P[kn.L2] = m.crank_length, m.rod_length
    P[kn.M1], P[kn.M2], P[kn.M3] = m.crank_mass, m.rod_mass, m.slider_mass
    P[kn.I1] = m.crank_inertia
    P[kn.I3X], P[kn.I3Y], P[kn.I3Z] = m.rod_inertia
    P[kn.GRAV] = m.gravity
    P[kn.JOFF] = m.joint_offset
    P[kn.OMEGA] = m.crank_speed
    IP[kn.DRIVER] = 1
    IP[ks.SC_CASE] = 1 if m.clearance_at == "crank_rod" else 0
    IP[ks.SC_BEARING_ROD] = 1 if m.bearing_on == "rod" else 0
    IP[ks.SC_PLANAR] = 1 if m.planar else 0


#: First step size of the integrator from the initial state [s], per joint model.
INITIAL_STEP = {"clearance": 1e-6, "ideal": 1e-6}


def initial_vector(params: SimParameters) -> np.ndarray:
    """State at the documented initial configuration.

    Crank at ``initial_crank_angle_deg`` turning at the nominal speed; rod and slider at the
    ideal slider-crank's closed-form position and velocity; the journal centred in the bearing
    and aligned with it (rod in plane).
    """
    m: SliderCrankParameters = params.mechanism  # type: ignore[assignment]
    th1 = math.radians(m.initial_crank_angle_deg)
    if params.joint.model == "ideal":
        return np.array([th1, m.crank_speed])
    k = slider_crank_kinematics(th1, m.crank_length, m.rod_length, m.crank_speed)
    phi = float(k["rod_angle"])
    # rod body y from the pivot to the clearance joint: B -> C, or C -> B
    direction = phi if m.clearance_at == "rod_slider" else phi + math.pi
    a = direction - 0.5 * math.pi
    q = [math.cos(a / 2), 0.0, 0.0, math.sin(a / 2)]
    x, v = float(k["slider_position"]), float(k["slider_velocity"])
    w = float(k["rod_angular_velocity"])
    return np.array([th1, x, m.crank_speed, v, *q, 0.0, 0.0, w])


def _along_x(values: np.ndarray) -> np.ndarray:
    out = np.zeros((values.shape[0], 3))
    out[:, 0] = values
    return out


def variables(params: SimParameters, diag: np.ndarray) -> dict:
    """The slider-crank's record variables (name -> (dims, values, attrs))."""
    m: SliderCrankParameters = params.mechanism  # type: ignore[assignment]
    th1 = diag[:, kn.D_TH1]
    rod = diag[:, ks.D_ROD_ANGLE]
    if m.clearance_at == "crank_rod" and params.joint.model != "ideal":
        rod = rod + math.pi  # the kernel's rod axis runs C -> B
    rod = np.angle(np.exp(1j * rod))
    crank_pos = np.stack([0.5 * m.crank_length * np.cos(th1), 0.5 * m.crank_length * np.sin(th1)])
    crank_pos = np.column_stack([crank_pos.T, np.zeros_like(th1)])
    w1 = m.crank_speed
    crank_vel = np.column_stack([-w1 * crank_pos[:, 1], w1 * crank_pos[:, 0], np.zeros_like(th1)])
    return {
        "crank_angle": crank_angle(th1),
        "rod_angle": variable(
            "time", rod, "rad", "connecting rod angle (B to C) from +x, counter-clockwise"
        ),
        "slider_position": variable(
            AXIS,
            _along_x(diag[:, ks.D_SLIDER_POS]),
            "m",
            "position of the slider pin C (guide along x)",
        ),
        "slider_velocity": variable(
            AXIS, _along_x(diag[:, ks.D_SLIDER_VEL]), "m s-1", "velocity of the slider"
        ),
        "slider_acceleration": variable(
            AXIS, _along_x(diag[:, ks.D_SLIDER_ACC]), "m s-2", "acceleration of the slider"
        ),
        **body_motion("crank", "crank", crank_pos, crank_vel),
        **body_motion(
            "rod", "connecting rod", vector(diag, ks.D_ROD_POS), vector(diag, ks.D_ROD_VEL)
        ),
        "rod_angular_velocity": variable(
            AXIS,
            vector(diag, ks.D_ROD_OMEGA),
            "rad s-1",
            "angular velocity of the connecting rod, global",
        ),
        "driver_torque": variable(
            "time",
            diag[:, ks.D_DRIVER_TORQUE],
            "N m",
            "torque that keeps the crank at constant speed",
        ),
    }
