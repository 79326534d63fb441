"""Public names of the dynamics part of jointwear.sim (mechanism, contact, friction, integrator)."""

from jointwear.sim.contact import contact_constant, contact_stiffness, lankarani_nikravesh_force
from jointwear.sim.dynamics import (
    CONTACT_MODES,
    CycleResult,
    SimState,
    initial_state,
    point_area,
    run_cycles,
    wear_depth_on_grid,
)
from jointwear.sim.friction import friction_coefficient
from jointwear.sim.mechanism import loop_closure
from jointwear.sim.parameters import (
    DEFAULT_PARAMETER_SET,
    PARAMETER_SETS,
    ContactParameters,
    FrictionParameters,
    JointParameters,
    MechanismParameters,
    SimParameters,
    SolverParameters,
    load_parameters,
)
from jointwear.sim.plot import plot_cycle

__all__ = [
    "SimParameters",
    "MechanismParameters",
    "JointParameters",
    "ContactParameters",
    "FrictionParameters",
    "SolverParameters",
    "PARAMETER_SETS",
    "DEFAULT_PARAMETER_SET",
    "load_parameters",
    "run_cycles",
    "CycleResult",
    "SimState",
    "initial_state",
    "point_area",
    "wear_depth_on_grid",
    "CONTACT_MODES",
    "contact_constant",
    "contact_stiffness",
    "lankarani_nikravesh_force",
    "friction_coefficient",
    "loop_closure",
    "plot_cycle",
]
