"""Wear runs finish for rigs off the default parameter set (issue 16), at reduced size.

Each rig changes one parameter of the study's mechanism; with the old controller each of them
stalled with dN collapsing to 1-2 cycles. Reduced size: 6 x 60 grid, kw x 100 and 4000 cycles
(the study-equivalent 4e5 cycles, since the profile depends on kw N only). Full size (1.2e6
cycles at 20 x 200) with timings: benchmarks/bench_sim_rigs.py.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from _rigs import OFF_DEFAULT_RIGS

from jointwear.errors import ParameterError
from jointwear.params import replace_nested
from jointwear.sim import DEFAULT_KW, PARAMETER_SETS, WearSettings, simulate_wear

PARAMS = replace_nested(PARAMETER_SETS["zhang2023"], **{"joint.n_layers": 6, "joint.n_points": 60})
CYCLES = 4000
SETTINGS = WearSettings(kw=DEFAULT_KW * 100, tol=0.2, dn=50)


@pytest.mark.parametrize("rig", list(OFF_DEFAULT_RIGS))
def test_rig_finishes_with_its_accuracy_stated(rig):
    ds = simulate_wear(
        PARAMS, cycles=CYCLES, snapshots=[], settings=SETTINGS, overrides=OFF_DEFAULT_RIGS[rig]
    )
    assert ds.attrs["status"] == "complete" and ds.attrs["cycles_done"] == CYCLES
    # the old controller needed thousands of 1-2 cycle updates here
    assert ds.attrs["n_updates"] <= 20
    assert ds.attrs["cycles_simulated"] <= 120
    assert int(ds["update_dn"].values[ds["update_accepted"].values == 1].max()) >= 500
    depth, u = float(ds["max_wear_depth"][-1]), float(ds["max_wear_depth_u"][-1])
    assert depth > 1e-6
    assert 0 < u < 0.5 * depth
    assert 0 < float(ds["worn_volume_u"][-1]) < 0.5 * float(ds["worn_volume"][-1])
    assert ds.attrs["accuracy_status"] in ("reached", "not reached")
    assert ("accuracy_warning" in ds.attrs) == (ds.attrs["accuracy_status"] == "not reached")
    for name, units in (("wear_depth_u", "m"), ("max_wear_depth_u", "m"), ("worn_volume_u", "m3")):
        assert ds[name].attrs["units"] == units
        assert "expanded uncertainty" in ds[name].attrs["long_name"]


def test_overrides_reach_the_simulator():
    fixed = WearSettings(kw=DEFAULT_KW, scheme="fixed", dn=100, settle_cycles=0)
    base = simulate_wear(PARAMS, cycles=100, snapshots=[], settings=fixed)
    for name, value in (
        ("mechanism.joint_offset", 0.004),
        ("joint.thrust_radius", 9.0e-3),
        ("mechanism.initial_crank_angle_deg", 90.0),
        ("friction.dynamic_coefficient", 0.15),
    ):
        ds = simulate_wear(
            PARAMS,
            cycles=100,
            snapshots=[],
            settings=fixed,
            overrides={name: value, "wear.kw": 2 * DEFAULT_KW},
        )
        assert ds.attrs["kw_m2_per_N"] == 2 * DEFAULT_KW
        assert json.loads(ds.attrs["parameter_overrides"])[name] == value
        # the parameter changed the simulation (not only kw, which scales the depth by 2)
        h0, h1 = base["wear_depth"].values[-1], ds["wear_depth"].values[-1]
        assert np.max(np.abs(h1 - 2.0 * h0)) > 0.01 * np.max(2.0 * h0), name
    with pytest.raises(ParameterError, match="unknown parameter 'joint_ofset'"):
        simulate_wear(PARAMS, cycles=10, overrides={"mechanism.joint_ofset": 0.0})
    with pytest.raises(ParameterError, match="unknown wear setting"):
        simulate_wear(PARAMS, cycles=10, overrides={"wear.kww": 1e-15})


def test_a_string_override_reaches_the_simulator_and_its_provenance():
    fixed = WearSettings(kw=DEFAULT_KW, scheme="fixed", dn=100, settle_cycles=0)
    base = simulate_wear(PARAMS, cycles=100, snapshots=[], settings=fixed)
    ds = simulate_wear(
        PARAMS,
        cycles=100,
        snapshots=[],
        settings=fixed,
        overrides={"contact.formulation": "per_point", "wear.kw": DEFAULT_KW},
    )
    assert json.loads(ds.attrs["parameter_overrides"]) == {
        "contact.formulation": "per_point",
        "wear.kw": DEFAULT_KW,
    }
    assert not np.array_equal(base["wear_depth"].values, ds["wear_depth"].values)
    with pytest.raises(ParameterError, match=r"contact.formulation: expected one of"):
        simulate_wear(PARAMS, cycles=100, snapshots=[], overrides={"contact.formulation": "x"})


def test_halving_tol_moves_the_max_depth_less_than_the_reported_accuracy():
    out = []
    for tol in (0.2, 0.1):
        ds = simulate_wear(
            PARAMS, cycles=CYCLES, snapshots=[], settings=WearSettings(kw=DEFAULT_KW * 100, tol=tol)
        )
        out.append((float(ds["max_wear_depth"][-1]), float(ds["max_wear_depth_u"][-1])))
    (d1, u1), (d2, u2) = out
    assert u2 < u1
    assert abs(d1 - d2) < u1
    assert abs(d1 - d2) < np.hypot(u1, u2)


def test_offset_zero_is_planar_with_friction_only():
    """docs/sim.md: offset 0 admits a planar motion; without friction it is unstable."""
    from jointwear.sim import run_cycles

    flat = replace_nested(PARAMS, **{"mechanism.joint_offset": 0.0})
    tilt = {}
    for friction in (True, False):
        res = run_cycles(replace_nested(flat, **{"friction.enabled": friction}), cycles=3)
        tilt[friction] = float(np.degrees(res.dataset["journal_tilt"].max()))
        axial = res.dataset["journal_offset"].sel(axis="z")
        if not friction:
            assert float(np.abs(axial).max()) > 0.3e-3  # travels in its axial play
    assert tilt[True] < 1e-6
    assert tilt[False] > 1.0
