"""The slider-crank with a revolute clearance joint: parameters, named set, closed-form kinematics.

Crank pivot A at the origin, crank A-B turning counter-clockwise about +z at constant speed, the
connecting rod B-C, the slider C on an ideal prismatic guide along the x axis through A (no
offset), gravity along -y. The clearance joint is either rod-slider (C, the benchmark of Flores
et al.) or crank-rod (B); the other revolute joints are ideal. The equations of motion are in
:mod:`jointwear.sim.kernels._slider_crank`; ``docs/sim.md`` ("The slider-crank") has the model.
``PARAMETER_SETS["slider_crank"]`` (:mod:`jointwear.sim.parameters`) holds the benchmark: the
mechanism table below and :data:`BENCHMARK_TABLES`.

Sources of the benchmark values:

[F04] P. Flores, J. Ambrosio, J.C.P. Claro, H.M. Lankarani, C.S. Koshy, "A study on dynamics of
      mechanical systems including joints with clearance and lubrication", Mech. Mach. Theory
      41 (2006) 247-261, doi:10.1016/j.mechmachtheory.2005.10.002 (as listed in the survey of
      Q. Tian, P. Flores, H.M. Lankarani, Mech. Mach. Theory 2018, doi:10.1016/
      j.mechmachtheory.2017.12.002), and P. Flores, J. Ambrosio, "Revolute joints with clearance
      in multibody systems", Computers & Structures 82 (2004) (pages not verified): the
      slider-crank with a dry revolute clearance joint between connecting rod and slider.
[F08] P. Flores, J. Ambrosio, J.C.P. Claro, H.M. Lankarani, "Kinematics and Dynamics of
      Multibody Systems with Imperfect Joints", Springer (2008), the same benchmark.

The issue that asked for this set (jointwear issue 26) states the lengths (crank 0.05 m, rod
0.12 m) as tabulated there. The other tabulated values below (masses, inertias, radii, E, nu,
restitution, crank speed) are the ones these publications are known for, but **they could not be
checked against the tables in this work**: the searchable text available when the set was written
(web pages, code, documentation) did not reach them. Every such value is marked
"[F04/F08, not verified]"; values the publications do not give are marked "jointwear choice".
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING, Literal

from jointwear.errors import ParameterError
from jointwear.params import check_fields, finite, non_negative, positive
from jointwear.sim._crank import CrankDriven, inertias

if TYPE_CHECKING:  # numpy is imported where the kinematics are computed: 'jointwear --help'
    import numpy as np  # lists the sim options without it

__all__ = ["SliderCrankParameters", "BENCHMARK_TABLES", "slider_crank_kinematics"]

#: Which revolute joint of the slider-crank has the clearance.
CLEARANCE_JOINTS = ("rod_slider", "crank_rod")
#: Bodies that may carry the bearing, per clearance joint.
BEARING_BODIES = {"rod_slider": ("slider", "rod"), "crank_rod": ("crank", "rod")}


@dataclasses.dataclass(frozen=True)
class SliderCrankParameters(CrankDriven):
    """Links, masses and drive of the slider-crank (``[mechanism]`` of the ``slider_crank`` set).

    Each link's centre of mass is at mid-length (uniform links, jointwear choice: the benchmark
    tabulates masses and inertias only); moments of inertia are about the centre of mass.

    Attributes
    ----------
    kind : "slider_crank"
        Names the mechanism (the four-bar's table has no ``kind``).
    crank_length, rod_length : float
        0.05 m and 0.12 m [F04, F08; the values given in issue 26].
    crank_mass, rod_mass, slider_mass : float
        0.30, 0.21, 0.14 kg [F04/F08, not verified].
    crank_inertia : float
        1.0e-4 kg m2 about the crank's centre of mass, axis z [F04/F08, not verified].
    rod_inertia : tuple of 3 floats
        (Ix, Iy, Iz) about the rod's centre of mass in its body axes (x in-plane normal to the
        rod, y along the rod from the pivot to the joint end, z the joint axis). Iz = 2.5e-4
        kg m2 [F04/F08, not verified]; Ix = Iz and Iy = 2.5e-6 kg m2 are a jointwear choice for
        a slender rod (the planar benchmark does not need them; they act only with
        ``planar = false``).
    gravity : float
        9.81 m/s2 along -y (jointwear choice; negligible at the benchmark speed).
    joint_offset : float
        0 m: the clearance joint in the links' plane (jointwear choice; a non-zero value moves
        the joint centre along +z, so the contact forces tilt the rod out of plane: only with
        ``planar = false``, and a non-zero value with ``planar = true`` is refused,
        :mod:`jointwear.sim.mechanisms`).
    crank_speed_rpm : float
        5000 rpm, counter-clockwise [F04/F08, not verified].
    initial_crank_angle_deg : float
        0 (jointwear choice: slider at its outer dead centre).
    driver : bool
        Must be true: the crank turns at constant speed (the driver torque is recorded).
    clearance_at : {"rod_slider", "crank_rod"}
        The joint with clearance; "rod_slider" is the benchmark's.
    bearing_on : {"slider", "rod", "crank"}
        Body that carries the bearing (the worn part): "slider" or "rod" for the rod-slider
        joint, "crank" or "rod" for the crank-rod joint.
    planar : bool
        True (default, the benchmark's planar model): the rod turns about z only, so the journal
        stays parallel to the bearing; false: the rod hangs on a spherical joint at its other
        end and the 3D joint lets the journal tilt and slide axially between the shoulders.
    """

    kind: Literal["slider_crank"] = "slider_crank"
    crank_length: float = positive(0.05)
    rod_length: float = positive(0.12)
    crank_mass: float = positive(0.30)
    rod_mass: float = positive(0.21)
    slider_mass: float = positive(0.14)
    crank_inertia: float = positive(1.0e-4)
    # tuple[float, ...]: jointwear.params mis-coerces fixed-length tuple annotations
    rod_inertia: tuple[float, ...] = inertias((2.5e-4, 2.5e-6, 2.5e-4), "Ix, Iy, Iz")
    gravity: float = non_negative(9.81)
    joint_offset: float = finite(0.0)
    crank_speed_rpm: float = finite(5000.0)
    initial_crank_angle_deg: float = finite(0.0)
    driver: bool = True
    clearance_at: Literal["rod_slider", "crank_rod"] = "rod_slider"
    bearing_on: Literal["slider", "rod", "crank"] = "slider"
    planar: bool = True

    def __post_init__(self) -> None:
        check_fields(self, "mechanism")
        if self.rod_length <= self.crank_length:
            raise ParameterError(
                f"mechanism.rod_length ({self.rod_length} m) must exceed mechanism.crank_length "
                f"({self.crank_length} m): otherwise the crank cannot turn fully"
            )
        if not self.driver:
            raise ParameterError(
                "mechanism.driver = false is not available for the slider-crank: its crank "
                "turns at constant speed (mechanism.crank_speed_rpm)"
            )
        allowed = BEARING_BODIES.get(self.clearance_at)
        if allowed is None:
            raise ParameterError(
                f"mechanism.clearance_at must be one of {list(CLEARANCE_JOINTS)}, got "
                f"{self.clearance_at!r}"
            )
        if self.bearing_on not in allowed:
            raise ParameterError(
                f"mechanism.bearing_on = {self.bearing_on!r} is not a body of the "
                f"{self.clearance_at} joint; set it to {allowed[0]!r} or {allowed[1]!r}"
            )

    @property
    def stroke(self) -> float:
        """Slider stroke 2 L1 [m]."""
        return 2.0 * self.crank_length


def slider_crank_kinematics(
    theta: np.ndarray | float,
    crank_length: float,
    rod_length: float,
    omega: float,
    alpha: float = 0.0,
) -> dict[str, np.ndarray]:
    """Closed-form kinematics of the ideal in-line slider-crank.

    B = L1 (cos theta, sin theta), slider C = (x, 0) with x = L1 cos theta + S,
    S = sqrt(L2^2 - L1^2 sin^2 theta) (slider on the +x side), rod angle phi from +x with
    sin phi = -L1 sin theta / L2.

    Parameters
    ----------
    theta : array_like
        Crank angle [rad] from +x, counter-clockwise.
    crank_length, rod_length : float
        L1, L2 [m] (L2 > L1).
    omega, alpha : float
        Crank angular velocity [rad/s] and acceleration [rad/s2].

    Returns
    -------
    dict of ndarray
        ``slider_position`` x [m], ``slider_velocity`` [m/s], ``slider_acceleration`` [m/s2],
        ``rod_angle`` phi [rad], ``rod_angular_velocity`` [rad/s], ``rod_angular_acceleration``
        [rad/s2].
    """
    l1, l2 = float(crank_length), float(rod_length)
    if not l2 > l1 > 0:
        raise ParameterError(
            f"slider-crank needs rod_length > crank_length > 0, got {l2!r} and {l1!r}"
        )
    import numpy as np

    from jointwear.sim.kernels._slider_kinematics import closed_form  # numba: loaded on first use

    th = np.asarray(theta, dtype=float)
    x, dx, ddx, phi, dphi, ddphi = closed_form(th, l1, l2)
    return {
        "slider_position": x,
        "slider_velocity": dx * omega,
        "slider_acceleration": ddx * omega * omega + dx * alpha,
        "rod_angle": phi,
        "rod_angular_velocity": dphi * omega,
        "rod_angular_acceleration": ddphi * omega * omega + dphi * alpha,
    }


#: The benchmark's joint, contact, friction and solver values as overrides of the four-bar's
#: tables (``PARAMETER_SETS["slider_crank"]`` is built from them; sources in the module
#: docstring).
BENCHMARK_TABLES: dict[str, dict[str, object]] = {
    "joint": {
        "journal_radius": 9.5e-3,  # [F04/F08, not verified]
        "bearing_radius": 10.0e-3,  # [F04/F08, not verified]: radial clearance 0.5 mm
        # the dry planar benchmark has no bearing length: jointwear choice (it sets the contact
        # pressure, hence the wear depth per cycle, not the joint force of the planar model)
        "bearing_width": 20e-3,
        "journal_length": 22e-3,
        "axial_clearance": 1e-3,  # jointwear choice (3D model only)
        "thrust_radius": 11.5e-3,  # jointwear choice (3D model only)
        "n_layers": 8,  # jointwear choice: enough for the planar line contact
        "axial_grading": 0.0,
    },
    "contact": {
        "restitution": 0.9,  # [F04/F08, not verified]
        "journal_modulus": 207e9,  # [F04/F08, not verified]
        "journal_poisson": 0.3,  # [F04/F08, not verified]
        "bearing_modulus": 207e9,  # [F04/F08, not verified]
        "bearing_poisson": 0.3,  # [F04/F08, not verified]
    },
    # friction: not verified for the benchmark; off (frictionless dry contact), set [friction]
    "friction": {"enabled": False},
    # one revolution lasts 12 ms at 5000 rpm: sample every 10 us to resolve the impacts
    "solver": {"max_step": 1e-4, "output_interval": 1e-5},
}
