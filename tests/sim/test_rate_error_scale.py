"""``solver.rate_error_scale``: the rotating body's angular velocity measured as one vector.

Truths: ``"auto"`` leaves the rigid rig (no tilt spring or damper) on the per-component form,
so its kernels stay those of ``test_kernels_split.py``; with a tilt spring the three components
are measured against the vector's magnitude, which must still meet the independent truths of
``test_tilt_spring.py`` (the closed-form oscillator, energy conserved with impacts) while taking
fewer steps; an unknown choice is refused, not read as one of the others.
"""

from __future__ import annotations

import numpy as np
import pytest
from test_tilt_spring import _free_rig  # noqa: I001

from jointwear.errors import ParameterError
from jointwear.params import replace_nested
from jointwear.sim import PARAMETER_SETS, run_cycles
from jointwear.sim.dynamics import _effective_rtol, _error_flags
from jointwear.sim.kernels import _layout as kn
from jointwear.sim.parameters import AUTO_VECTOR_RTOL_FACTOR

BASE = PARAMETER_SETS["zhang2023"]
OMEGA = slice(kn.Y_OMEGA, kn.Y_OMEGA + 3)


def _flags(**changes):
    return _error_flags(replace_nested(BASE, **changes))


def test_auto_keeps_the_rigid_rig_per_component_and_a_tilt_spring_per_vector():
    plain = _flags()
    assert not np.any(plain == kn.ERR_VECTOR)
    np.testing.assert_array_equal(plain, _flags(**{"solver.rate_error_scale": "component"}))
    for key in ("joint.tilt_stiffness", "joint.tilt_damping"):
        spring = _flags(**{key: 1.0})
        assert np.all(spring[OMEGA] == kn.ERR_VECTOR)
        # everything else as before: angles absolute, the other rates relative
        np.testing.assert_array_equal(
            np.delete(spring, np.r_[OMEGA]), np.delete(plain, np.r_[OMEGA])
        )
        stiff_component = _flags(**{key: 1.0, "solver.rate_error_scale": "component"})
        np.testing.assert_array_equal(stiff_component, plain)
    assert np.all(_flags(**{"solver.rate_error_scale": "vector"})[OMEGA] == kn.ERR_VECTOR)
    ideal = _flags(**{"joint.model": "ideal", "solver.rate_error_scale": "vector"})
    assert not np.any(ideal == kn.ERR_VECTOR)  # the ideal model has no rotating body state


def test_auto_tightens_rtol_only_where_it_chose_the_vector_scale():
    def rtol(**changes):
        return _effective_rtol(replace_nested(BASE, **{"solver.rtol": 2e-6, **changes}))

    assert 0 < AUTO_VECTOR_RTOL_FACTOR < 1
    assert rtol() == 2e-6  # the rigid rig: bit for bit as before
    assert rtol(**{"joint.tilt_stiffness": 1e3}) == 2e-6 * AUTO_VECTOR_RTOL_FACTOR
    assert rtol(**{"joint.tilt_damping": 1.0}) == 2e-6 * AUTO_VECTOR_RTOL_FACTOR
    # an explicit choice keeps the given rtol
    for scale in ("vector", "component"):
        assert rtol(**{"joint.tilt_stiffness": 1e3, "solver.rate_error_scale": scale}) == 2e-6
    ideal = {"joint.tilt_stiffness": 1e3, "joint.model": "ideal"}
    assert rtol(**ideal) == 2e-6  # no rotating body state: nothing chosen


def test_an_unknown_scale_is_refused_by_construction_override_and_toml():
    import dataclasses

    from jointwear.params import from_mapping
    from jointwear.sim.parameters import SimParameters, SolverParameters

    # one check (params.check_fields' Literal check), one message naming the field and choices
    said = r"^solver\.rate_error_scale: expected one of \['auto', 'component', 'vector'\], got 'x'$"
    with pytest.raises(ParameterError, match=said):
        SolverParameters(rate_error_scale="x")
    with pytest.raises(ParameterError, match=said):
        dataclasses.replace(BASE.solver, rate_error_scale="x")
    with pytest.raises(ParameterError, match=said):
        replace_nested(BASE, **{"solver.rate_error_scale": "x"})
    with pytest.raises(ParameterError, match=said):
        from_mapping(SimParameters, {"solver": {"rate_error_scale": "x"}})
    assert SolverParameters(rate_error_scale="vector").rate_error_scale == "vector"


@pytest.mark.parametrize("scale", ["component", "vector"])
def test_both_scales_conserve_the_energy_with_a_tilt_spring_and_impacts(scale):
    p = replace_nested(_free_rig(0.0), **{"solver.rate_error_scale": scale})
    ds = run_cycles(p, cycles=0.5).dataset
    e = ds["mechanical_energy"].values
    assert ds["contact_force"].max() > 100.0  # impacts happened
    assert np.abs(e - e[0]).max() / abs(e[0]) < 1e-4


def test_the_vector_scale_takes_fewer_steps_on_a_stiff_tilt_spring():
    p = replace_nested(BASE, **{"joint.tilt_stiffness": 3e3})
    start = run_cycles(p, cycles=1.0, record=False).state  # in contact, vibrating
    steps = {}
    for scale in ("component", "vector"):
        q = replace_nested(p, **{"solver.rate_error_scale": scale})
        steps[scale] = run_cycles(q, cycles=0.2, state=start, record=False).n_steps
    # benchmarks/results/tilt_profile.json: 2.3x over whole cycles
    assert steps["vector"] < 0.7 * steps["component"]
