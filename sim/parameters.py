"""Parameters of the four-bar simulator: frozen dataclasses, named sets and TOML loading.

All values are SI (m, kg, kg m2, s, N, Pa) except where a name says otherwise
(``crank_speed_rpm``, ``initial_crank_angle_deg``). The default set ``"zhang2023"`` holds Tables
1-2 of the reference study (``docs/sim.md`` lists the choices jointwear adds where the study is
silent: initial crank angle, axial-stop geometry, impact-velocity floor, solver settings).
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path
from typing import Literal

from jointwear.errors import ParameterError
from jointwear.params import (
    check_fields,
    finite,
    from_mapping,
    non_negative,
    positive,
    read_toml,
    within,
)
from jointwear.sim._crank import CrankDriven, inertias
from jointwear.sim._defaults import BORE_LAYERS, BORE_POINTS, DEFAULT_PARAMETER_SET
from jointwear.sim.slider_crank import BENCHMARK_TABLES, SliderCrankParameters

__all__ = [
    "MechanismParameters",
    "JointParameters",
    "ContactParameters",
    "FrictionParameters",
    "SolverParameters",
    "SimParameters",
    "PARAMETER_SETS",
    "DEFAULT_PARAMETER_SET",
    "load_parameters",
    "parameters_from_tables",
]


@dataclasses.dataclass(frozen=True)
class MechanismParameters(CrankDriven):
    """Links, masses and drive of the spatial four-bar (Table 1 of the study).

    Crank A-B, coupler B-C, follower D-C and ground A-D; A at the origin, D at
    (``ground_length``, 0, 0); gravity along -y. Moments of inertia are about each body's centre
    of mass (mid-length). The follower's body axes are x (in-plane, normal to the link), y (along
    the link, D -> C) and z (joint axis); ``follower_inertia`` = (I3x, I3y, I3z).
    ``joint_offset`` [m]: the centre of joint C (bearing and journal) sits this far along the
    joint axis (+z) from the mid-plane of the links, which lie side by side; a non-zero offset
    lets the contact forces turn the follower out of plane about the spherical joint D.
    """

    crank_length: float = positive(0.10)
    coupler_length: float = positive(0.40)
    follower_length: float = positive(0.30)
    ground_length: float = positive(0.30)
    crank_mass: float = positive(0.46)
    coupler_mass: float = positive(1.45)
    follower_mass: float = positive(1.50)
    crank_inertia: float = positive(0.0019)
    coupler_inertia: float = positive(0.0927)
    # tuple[float, ...]: jointwear.params mis-coerces fixed-length tuple annotations
    follower_inertia: tuple[float, ...] = inertias((0.0317, 0.0004, 0.0317), "I3x, I3y, I3z")
    gravity: float = non_negative(9.81)
    joint_offset: float = finite(0.01)
    crank_speed_rpm: float = finite(120.0)
    initial_crank_angle_deg: float = finite(0.0)
    driver: bool = True
    bearing_on: Literal["follower", "coupler"] = "follower"

    def __post_init__(self) -> None:
        check_fields(self, "mechanism")
        lengths = sorted(
            [self.crank_length, self.coupler_length, self.follower_length, self.ground_length]
        )
        if lengths[0] + lengths[3] > lengths[1] + lengths[2] or (self.crank_length != lengths[0]):
            raise ParameterError(
                f"mechanism: link lengths crank={self.crank_length}, coupler={self.coupler_length}, "
                f"follower={self.follower_length}, ground={self.ground_length} m do not make a "
                "Grashof crank-rocker (the crank must be the shortest link and "
                "shortest + longest <= sum of the other two); the crank could not turn fully"
            )


@dataclasses.dataclass(frozen=True)
class JointParameters:
    """Geometry and discretisation of clearance joint C (Table 2 of the study).

    ``axial_clearance`` is the total axial play: the journal's shoulders sit at
    +-(bearing_width + axial_clearance)/2 from the journal centre along its axis, and touch the
    bearing's end faces on a circle of radius ``thrust_radius``. ``model = "ideal"`` makes joint C
    an ideal revolute (planar four-bar), for validation. ``n_layers`` x ``n_points`` is the
    bore grid; ``axial_grading`` in [0, 1) crowds the layers towards both bearing edges
    (:func:`jointwear.sim.wearmap.layer_positions`; 0 = equal spacing as in the study's eq. 2),
    where a tilted journal's contacts and their wear are shorter than an equal spacing.
    """

    model: Literal["clearance", "ideal"] = "clearance"
    journal_radius: float = positive(7.5e-3)
    journal_length: float = positive(17e-3)
    bearing_radius: float = positive(8.0e-3)
    bearing_width: float = positive(15e-3)
    axial_clearance: float = non_negative(1e-3)
    thrust_radius: float = positive(9.5e-3)
    n_layers: int = BORE_LAYERS
    n_points: int = BORE_POINTS
    axial_grading: float = 0.75
    tilt_stiffness: float = non_negative(0.0)
    tilt_damping: float = non_negative(0.0)

    def __post_init__(self) -> None:
        check_fields(self, "joint")
        if self.bearing_radius <= self.journal_radius:
            raise ParameterError(
                f"joint.journal_radius ({self.journal_radius} m) must be smaller than "
                f"joint.bearing_radius ({self.bearing_radius} m): the radial clearance "
                f"bearing_radius - journal_radius = {self.radial_clearance:g} m is not positive"
            )
        if self.journal_length < self.bearing_width + self.axial_clearance:
            raise ParameterError(
                f"joint.journal_length ({self.journal_length} m) must be at least "
                f"bearing_width + axial_clearance = {self.bearing_width + self.axial_clearance:g} m "
                "(the journal must span the bearing between its shoulders)"
            )
        if self.thrust_radius < self.bearing_radius:
            raise ParameterError(
                f"joint.thrust_radius ({self.thrust_radius} m) must be >= bearing_radius "
                f"({self.bearing_radius} m): the shoulders bear on the end faces outside the bore"
            )
        if not (math.isfinite(self.axial_grading) and 0.0 <= self.axial_grading < 1.0):
            raise ParameterError(
                f"joint.axial_grading must lie in [0, 1) (0: equally spaced layers), got "
                f"{self.axial_grading!r}"
            )
        if self.n_layers < 2 or self.n_points < 8:
            raise ParameterError(
                f"joint.n_layers must be >= 2 and joint.n_points >= 8, got {self.n_layers} and "
                f"{self.n_points}"
            )

    @property
    def radial_clearance(self) -> float:
        """Radial clearance c = Rb - Rj [m]."""
        return self.bearing_radius - self.journal_radius


@dataclasses.dataclass(frozen=True)
class ContactParameters:
    """Lankarani-Nikravesh contact law with (time-varying) stiffness, eqs. 6-10 of the study.

    ``formulation``: ``"slice"`` (default, grid-independent: each axial slice carries its width
    share of the joint-level law at its deepest point) or ``"per_point"`` (the study's literal
    sum of a full law at every penetrating point; *grid-dependent*, for comparison only).
    ``wear_projection`` (slice formulation): how a layer's contact becomes wear work at its
    points. ``"local_conserving"`` (default): the pressure follows the local law at each layer
    (line load K delta^n / wb at the layer's own penetration), scaled per contact region so
    that the worn volume is exactly kw times the normal work. ``"local"``: the local law
    unscaled - the wear work of one cycle at a point does not depend on the grid, but where a
    contact is shorter than a layer spacing (bearing edges) the worn volume exceeds kw times
    the normal work. ``"lumped"``: the layer's force spread over its whole slice area (before
    issue 16; dilutes edge contacts shorter than the slice, so edge wear grows as the grid is
    refined). ``impact_latch``: ``"region"`` (default) latches the impact velocity of eq. 6
    once per impact, at the onset, for each run of adjacent contacting layers (eq. 6 as
    defined); ``"layer"``: each layer latches its own approach rate when it enters contact
    (before issue 16).
    ``impact_velocity_floor`` [m/s]: lower bound of a latched impact velocity (an impact that
    starts slower, e.g. grazing, is damped as if it started at the floor); results do not
    depend on it (0.01 vs 0.001 m/s, docs/sim-wear.md).
    ``stiffness``: ``"time_varying"`` (eq. 9, local worn radius) or ``"constant"`` (eq. 7).
    ``worn_radius_in_denominator``: the eq. 9 variant with Rb + h also in Rb - Rj.
    ``axial_stiffness``: L-N stiffness of the end-face (thrust) contact [N/m^n]; 0 means "same
    as the radial K of eq. 7".
    ``wear_pressure`` (slice formulation): the pressure that turns a slice's force into wear
    work. ``"hertz"`` (default): spread over the points the journal overlaps, weights
    sqrt(delta). ``"conformal"``: the elastic-foundation (Winkler) pressure of the journal
    seated in the worn bore along the contact's direction, its modulus matched to Hertz's width
    on the unworn bore, so that a groove that fits the journal carries the load over a wider
    arc (docs/sim-wear.md, "Conformal contact"; ``jointwear.sim.wear.conformal_wear_work``).
    ``foundation_thickness`` [m] (``"conformal"`` only): 0 (default) matches the foundation's
    modulus to Hertz's width per load; > 0 takes it from an elastic lining of that thickness on
    a rigid base, ``(1 - nu) E / ((1 + nu)(1 - 2 nu) t)`` with the bearing's E and nu.
    """

    formulation: Literal["slice", "per_point"] = "slice"
    wear_projection: Literal["local_conserving", "local", "lumped"] = "local_conserving"
    impact_latch: Literal["region", "layer"] = "region"
    stiffness: Literal["time_varying", "constant"] = "time_varying"
    worn_radius_in_denominator: bool = False
    exponent: float = positive(1.5)
    restitution: float = within(0.9, "(0, 1]")
    journal_modulus: float = positive(207e9)
    journal_poisson: float = within(0.29, "(-1, 0.5)")
    bearing_modulus: float = positive(100e9)
    bearing_poisson: float = within(0.39, "(-1, 0.5)")
    impact_velocity_floor: float = positive(1e-2)
    axial_stiffness: float = non_negative(0.0)
    max_penetration_fraction: float = positive(0.5)
    wear_pressure: Literal["hertz", "conformal"] = "hertz"
    foundation_thickness: float = non_negative(0.0)

    def __post_init__(self) -> None:
        check_fields(self, "contact")
        if self.wear_pressure == "conformal" and self.formulation != "slice":
            raise ParameterError(
                "contact.wear_pressure = 'conformal' spreads each slice's force; the per-point "
                "formulation has no slice forces: set contact.formulation = 'slice'"
            )
        if self.foundation_thickness > 0 and self.wear_pressure != "conformal":
            raise ParameterError(
                f"contact.foundation_thickness = {self.foundation_thickness!r} has no effect with "
                f"contact.wear_pressure = {self.wear_pressure!r}: set contact.wear_pressure = "
                "'conformal' or remove contact.foundation_thickness"
            )


@dataclasses.dataclass(frozen=True)
class FrictionParameters:
    """Smoothed Coulomb friction of eq. 12 (``enabled = false`` switches friction off)."""

    enabled: bool = True
    static_coefficient: float = non_negative(0.2)
    dynamic_coefficient: float = non_negative(0.1)
    stick_velocity: float = positive(1e-3)
    slide_velocity: float = positive(1e-2)

    def __post_init__(self) -> None:
        check_fields(self, "friction")
        if self.slide_velocity <= self.stick_velocity:
            raise ParameterError(
                f"friction.slide_velocity ({self.slide_velocity}) must exceed "
                f"friction.stick_velocity ({self.stick_velocity})"
            )


#: What the local error of the rotating body's angular velocity is measured against
#: (:attr:`SolverParameters.rate_error_scale`).
RateErrorScale = Literal["auto", "component", "vector"]

#: The factor on ``solver.rtol`` that ``rate_error_scale = "auto"`` applies with the vector
#: scale (a tilt rig). The vector scale alone biases a tilt rig's normal work per cycle (the
#: wear rate) by +0.85 % at the default rtol (k = 1e3 N m/rad, on a worn bore), about the
#: expanded u of its 1.2e6-cycle worn volume (0.6-0.9 %); the bias falls as rtol^0.8 (measured
#: at 1e-6 ... 1e-7), and this factor keeps it within half that u (+0.32 % measured at 3e-7;
#: at most 12 % more u in quadrature) at 1.25 times the steps. 0.2 (a third of the u) cost
#: 1.35 times the steps: 62 s CPU at 3e3 N m/rad, over the 60-s budget
#: (benchmarks/results/tilt_speed.json, ``rtol_scan``; docs/sim-wear.md, "Tilt stiffness").
AUTO_VECTOR_RTOL_FACTOR = 0.3


@dataclasses.dataclass(frozen=True)
class SolverParameters:
    """Adaptive Dormand-Prince 5(4) integration and output sampling.

    Local error of angles [rad] is held below ``atol``; of angular rates below
    ``atol + rtol |rate|``. ``onset_penetration`` [m]: a step that starts without contact may end
    at most this deep (else it is retried shorter), so impact velocities are taken at the onset.
    ``rate_error_scale``: what the local error of the rotating body's angular velocity (the
    follower's, the slider-crank's rod's; three components in body axes) is measured against.
    ``"component"``: each component against its own magnitude, ``atol + rtol |omega_i|`` (the
    form before issue 41). ``"vector"``: every component against the vector's,
    ``atol + rtol |omega|`` (independent of the body axes). ``"auto"`` (default): ``"vector"``
    when the joint has a tilt spring or damper (``joint.tilt_stiffness`` or
    ``joint.tilt_damping`` > 0), ``"component"`` otherwise, so that the rigid rig's results
    stay bit for bit. A tilt spring makes the body vibrate about its own axis at hundreds of Hz
    about zero rate; per component, that vibration is resolved to rtol of its own small
    amplitude and sets the step (2.3 times the steps at 3e3 N m/rad; docs/sim.md, "Estimating
    the tilt stiffness of a rig"). ``"auto"`` holds the vector scale to
    :data:`AUTO_VECTOR_RTOL_FACTOR` times ``rtol``: at ``rtol`` itself the vector scale biases
    a tilt rig's wear rate by up to 0.85 % (docs/sim-wear.md, "Tilt stiffness"); an explicit
    ``"vector"`` uses ``rtol`` as given.
    """

    rtol: float = positive(1e-6)
    atol: float = positive(1e-9)
    max_step: float = positive(1e-3)
    min_step: float = positive(1e-11)
    output_interval: float = positive(1e-4)
    onset_penetration: float = positive(1e-7)
    baumgarte: float = positive(1000.0)
    rate_error_scale: RateErrorScale = "auto"

    def __post_init__(self) -> None:
        check_fields(self, "solver")
        if self.min_step >= self.max_step:
            raise ParameterError("solver.min_step must be smaller than solver.max_step")


@dataclasses.dataclass(frozen=True)
class SimParameters:
    """All parameters of a simulation (nested: mechanism, joint, contact, friction, solver).

    ``mechanism`` is the four-bar's :class:`MechanismParameters` or the slider-crank's
    :class:`~jointwear.sim.slider_crank.SliderCrankParameters` (``kind = "slider_crank"``).
    """

    name: str = DEFAULT_PARAMETER_SET
    mechanism: MechanismParameters | SliderCrankParameters = MechanismParameters()
    joint: JointParameters = JointParameters()
    contact: ContactParameters = ContactParameters()
    friction: FrictionParameters = FrictionParameters()
    solver: SolverParameters = SolverParameters()


class _ParameterSets(dict):
    def __missing__(self, key: str) -> SimParameters:
        raise KeyError(
            f"unknown parameter set {key!r}; known parameter sets: {', '.join(sorted(self))}"
        )


def _slider_crank_set() -> SimParameters:
    t = BENCHMARK_TABLES
    return SimParameters(
        name="slider_crank",
        mechanism=SliderCrankParameters(),
        joint=JointParameters(**t["joint"]),  # type: ignore[arg-type]
        contact=ContactParameters(**t["contact"]),  # type: ignore[arg-type]
        friction=FrictionParameters(**t["friction"]),  # type: ignore[arg-type]
        solver=SolverParameters(**t["solver"]),  # type: ignore[arg-type]
    )


#: Named parameter sets. :data:`DEFAULT_PARAMETER_SET` (``"zhang2023"``): Tables 1-2 of the
#: reference study (the four-bar); ``"slider_crank"``: the slider-crank benchmark of Flores et
#: al. (:mod:`jointwear.sim.slider_crank`).
PARAMETER_SETS: dict[str, SimParameters] = _ParameterSets(
    {DEFAULT_PARAMETER_SET: SimParameters(), "slider_crank": _slider_crank_set()}
)


#: Top-level TOML tables read by other parts of jointwear (ignored here).
_OTHER_TABLES = ("wear",)


def load_parameters(toml_path: str | Path, base: str = DEFAULT_PARAMETER_SET) -> SimParameters:
    """Read parameters from a TOML file, on top of a named parameter set.

    The file holds tables ``[mechanism]``, ``[joint]``, ``[contact]``, ``[friction]``,
    ``[solver]`` with any subset of their fields (SI units); a ``[wear]`` table is left to
    :mod:`jointwear.sim.wear`. Example::

        [joint]
        bearing_radius = 8.1e-3
        n_layers = 40

    Parameters
    ----------
    toml_path : path
        The TOML file.
    base : str
        Name of the parameter set in :data:`PARAMETER_SETS` whose values are overridden.

    Returns
    -------
    SimParameters
        The resolved parameters.

    Raises
    ------
    ParameterError
        Unknown names (listed with the known ones), wrong types or inconsistent values.
    """
    return parameters_from_tables(read_toml(toml_path), base, where=f"parameter file '{toml_path}'")


def parameters_from_tables(
    data: dict, base: str = DEFAULT_PARAMETER_SET, *, where: str = "parameters"
) -> SimParameters:
    """:class:`SimParameters` from TOML tables already read, on top of a named parameter set.

    What :func:`load_parameters` does after reading the file; for a caller that has read it
    for other tables too (``[wear]``), so that the file is parsed once. ``where`` names the
    source in error messages.
    """
    base_params = PARAMETER_SETS[base]
    merged = dataclasses.asdict(base_params)
    data = {k: v for k, v in data.items() if k not in _OTHER_TABLES}
    unknown = [k for k in data if k not in merged]
    if unknown:
        raise ParameterError(
            f"{where}: unknown table(s)/name(s) {', '.join(unknown)}; known: {', '.join(merged)}"
        )
    from jointwear.sim.mechanisms import check_applicable, foreign_keys, mechanism_of

    table = data.get("mechanism") if isinstance(data.get("mechanism"), dict) else {}
    kind = table.get("kind")
    base_kind = mechanism_of(base_params).name
    foreign = [f"mechanism.{k}" for k in table if k not in merged["mechanism"]]
    if foreign and foreign_keys(base_params, foreign):
        raise ParameterError(
            f"{where}: unknown parameter(s) {', '.join(foreign)} for the base set {base!r}"
            f"{foreign_keys(base_params, foreign)}; choose the mechanism with --base"
        )
    if kind is not None and kind != base_kind:
        raise ParameterError(
            f"{where}: mechanism.kind = {kind!r} does not match the base "
            f"set {base!r} ({base_kind}); choose the mechanism with the base set (e.g. "
            "--base slider_crank) and drop mechanism.kind"
        )
    for key, value in data.items():
        if isinstance(merged[key], dict):
            if not isinstance(value, dict):
                raise ParameterError(f"{where}: [{key}] must be a table, got {value!r}")
            merged[key] = {**merged[key], **value}
        else:
            merged[key] = value
    try:
        # the base set names the mechanism: no guessing between the mechanism tables
        merged["mechanism"] = from_mapping(
            type(base_params.mechanism), merged["mechanism"], where="mechanism"
        )
        params = from_mapping(SimParameters, merged)
    except ParameterError as exc:
        raise ParameterError(f"{where}: {exc}") from None
    given = {
        f"{name}.{key}": value
        for name, tab in data.items()
        if isinstance(tab, dict)
        for key, value in tab.items()
    }
    check_applicable(params, given, base_params, where=where)
    return params
