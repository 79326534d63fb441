"""Sweep specs: parsing, refusals that name the entry, designs, parameter overrides."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from scipy import stats

from jointwear.errors import ParameterError
from jointwear.sim.parameters import PARAMETER_SETS
from jointwear.sim.sweep._driver import _check_feasible
from jointwear.sim.sweep._params import apply_values, numeric_fields, parameter_units
from jointwear.sim.sweep._spec import make_design, read_spec
from jointwear.sim.wear import WearSettings

BASE = PARAMETER_SETS["zhang2023"]
WEAR = WearSettings()


def spec(method="lhs", run="wear", parameters=None, **sweep):
    sw = {"run": run, "method": method, "cycles": 1000, **sweep}
    if method != "grid":
        sw.setdefault("samples", 8)
    params = parameters or {
        "mechanism.joint_offset": {"distribution": "uniform", "bounds": [0.0, 0.01]}
    }
    return {"sweep": sw, "parameters": params}


def test_issue_example_parses_and_lhs_mixes_with_a_grid_axis():
    s = read_spec(
        spec(
            parameters={
                "mechanism.joint_offset": {"distribution": "uniform", "bounds": [0.0, 0.01]},
                "joint.bearing_radius": {"values": [7.9e-3, 8.0e-3, 8.1e-3]},
            },
            samples=32,
            seed=1,
            outputs=["max_wear_depth", "worn_volume", "cylindricity", "mean_contact_force"],
        )
    )
    d = make_design(s)
    assert d.values.shape == (96, 2)
    # every grid value gets the same Latin hypercube of joint offsets
    off = d.values[:, 0].reshape(3, 32)
    assert np.array_equal(off[0], off[1]) and np.array_equal(off[0], off[2])
    assert set(d.values[:, 1]) == {7.9e-3, 8.0e-3, 8.1e-3}
    # Latin hypercube: exactly one sample in each of the 32 equal-probability strata
    strata = np.floor(off[0] / 0.01 * 32).astype(int)
    assert sorted(strata) == list(range(32))
    assert not s.probabilistic_sample  # grid axes: the spread is not an input uncertainty
    _check_feasible(s, BASE, WEAR)


@pytest.mark.parametrize(
    ("params", "match"),
    [
        ({"mechanism.joint_ofset": {"values": [0.0]}}, r"mechanism\.joint_offset"),
        ({"bearing_radius": {"values": [8e-3]}}, r"joint\.bearing_radius"),
        ({"joint.model": {"values": [1.0]}}, "not a number"),
        ({"joint.n_layers": {"distribution": "uniform", "bounds": [4, 8]}}, "integer"),
    ],
)
def test_unknown_or_unusable_names_are_refused_with_close_matches(params, match):
    grid = all("values" in t for t in params.values())
    s = read_spec(spec(method="grid" if grid else "lhs", parameters=params))
    with pytest.raises(ParameterError, match=match):
        _check_feasible(s, BASE, WEAR)


@pytest.mark.parametrize(
    ("table", "match"),
    [
        ({"distribution": "uniform", "bounds": [0.01, 0.0]}, "impossible"),
        ({"distribution": "uniform", "bounds": [0.0]}, r"\[low, high\]"),
        ({"distribution": "normal", "mean": 0.0}, "needs std"),
        ({"distribution": "normal", "mean": 0.0, "std": 0.0}, "std must be > 0"),
        ({"distribution": "gauss", "mean": 0.0, "std": 1.0}, "unknown distribution"),
        ({"distribution": "uniform", "bounds": [0, 1], "mean": 0.5}, "takes bounds, not mean"),
        ({"values": [1.0], "bounds": [0, 1]}, "takes no bounds"),
        ({"values": [1.0, 1.0]}, "repeat"),
        ({"distribution": "lognormal", "mean": -1.0, "std": 1.0}, "mean > 0"),
        ({"distribution": "truncnormal", "mean": 2, "std": 1, "bounds": [0, 1]}, "outside"),
    ],
)
def test_bad_parameter_tables_name_the_entry(table, match):
    with pytest.raises(
        ParameterError, match=r'\[parameters\."mechanism\.joint_offset"\].*' + match
    ):
        read_spec(spec(parameters={"mechanism.joint_offset": table}))


def test_values_the_simulator_refuses_are_caught_before_running():
    # a bearing smaller than the journal (7.5 mm) cannot be built: refused at the bound
    s = read_spec(
        spec(
            parameters={"joint.bearing_radius": {"distribution": "uniform", "bounds": [7e-3, 8e-3]}}
        )
    )
    with pytest.raises(ParameterError, match=r"bearing_radius.*bound 0\.007.*journal_radius"):
        _check_feasible(s, BASE, WEAR)
    # an unbounded normal whose tail is impossible (negative kw) is refused, naming the cure
    s = read_spec(
        spec(parameters={"wear.kw": {"distribution": "normal", "mean": 9e-16, "std": 4e-16}})
    )
    with pytest.raises(ParameterError, match=r"wear\.kw.*0\.1 % quantile.*truncnormal"):
        _check_feasible(s, BASE, WEAR)


def test_grid_and_distribution_mixes_that_cannot_work():
    grid_and_dist = {
        "mechanism.joint_offset": {"distribution": "uniform", "bounds": [0.0, 0.01]},
        "joint.bearing_radius": {"values": [7.9e-3, 8.1e-3]},
    }
    with pytest.raises(ParameterError, match=r'"joint\.bearing_radius".*sobol design'):
        read_spec(spec(method="sobol", parameters=grid_and_dist))
    with pytest.raises(ParameterError, match=r'method = "grid" needs values'):
        read_spec(spec(method="grid", parameters=grid_and_dist))
    with pytest.raises(ParameterError, match="power of 2"):
        read_spec(spec(method="sobol", samples=100))
    with pytest.raises(ParameterError, match="Morris.*bounded range"):
        read_spec(
            spec(
                method="morris",
                parameters={"wear.kw": {"distribution": "lognormal", "mean": 9e-16, "std": 3e-16}},
            )
        )
    with pytest.raises(ParameterError, match="samples does not apply"):
        read_spec(spec(method="grid", samples=4, parameters={"wear.kw": {"values": [1e-15]}}))


def test_unknown_keys_outputs_and_fields_are_refused():
    with pytest.raises(ParameterError, match="did you mean samples"):
        read_spec(spec(sampels=4))
    with pytest.raises(ParameterError, match="'max_wear' is not an output.*max_wear_depth"):
        read_spec(spec(outputs=["max_wear"]))
    with pytest.raises(ParameterError, match="not an output of a 'cycle' run"):
        read_spec(spec(run="cycle", outputs=["worn_volume"]))
    with pytest.raises(ParameterError, match="keep: 'wear_depth' is not a field of a 'cycle'"):
        read_spec(spec(run="cycle", keep=["wear_depth"]))
    with pytest.raises(ParameterError, match="whole number of cycles"):
        read_spec(spec(cycles=10.5))
    with pytest.raises(ParameterError, match="unknown table"):
        read_spec({**spec(), "joint": {"n_layers": 4}})


def test_distributions_map_the_unit_design_through_their_quantiles():
    s = read_spec(
        spec(
            samples=2000,
            parameters={
                "wear.kw": {"distribution": "lognormal", "mean": 9e-16, "std": 3e-16},
                "friction.dynamic_coefficient": {
                    "distribution": "truncnormal",
                    "mean": 0.1,
                    "std": 0.05,
                    "bounds": [0.05, 0.2],
                },
                "mechanism.joint_offset": {"distribution": "normal", "mean": 0.01, "std": 1e-3},
            },
        )
    )
    v = make_design(s).values
    # lognormal given by the mean and std of the quantity itself (not of its logarithm)
    assert v[:, 0].mean() == pytest.approx(9e-16, rel=0.01)
    assert v[:, 0].std() == pytest.approx(3e-16, rel=0.05)
    assert v[:, 1].min() >= 0.05 and v[:, 1].max() <= 0.2
    ref = stats.truncnorm((0.05 - 0.1) / 0.05, (0.2 - 0.1) / 0.05, loc=0.1, scale=0.05)
    assert stats.kstest(v[:, 1], ref.cdf).pvalue > 0.5  # LHS: far better than random
    assert v[:, 2].mean() == pytest.approx(0.01, abs=1e-5)
    assert v[:, 2].std() == pytest.approx(1e-3, rel=0.02)


def test_designs_are_deterministic_and_seeds_depend_on_the_run_only():
    s = read_spec(spec(samples=16, seed=5))
    a, b = make_design(s), make_design(s)
    assert np.array_equal(a.values, b.values) and np.array_equal(a.seeds, b.seeds)
    assert len(set(a.seeds.tolist())) == 16
    c = make_design(dataclasses.replace(s, samples=32))
    assert np.array_equal(c.seeds[:16], a.seeds)  # seed of run i: (spec seed, i) only


def test_overrides_rebuild_the_nested_parameters():
    p, w = apply_values(
        BASE,
        WEAR,
        {
            "mechanism.joint_offset": 0.004,
            "friction.dynamic_coefficient": 0.15,
            "wear.kw": 1.5e-15,
            "joint.radial_clearance": 0.7e-3,
            "joint.journal_radius": 7.0e-3,
            "joint.n_layers": 6.0,
        },
    )
    assert p.mechanism.joint_offset == 0.004
    assert p.friction.dynamic_coefficient == 0.15
    assert w.kw == 1.5e-15
    # the clearance applies on top of the swept journal radius, whatever the order
    assert p.joint.bearing_radius == pytest.approx(7.7e-3, abs=1e-15)
    assert p.joint.n_layers == 6 and isinstance(p.joint.n_layers, int)
    assert BASE.mechanism.joint_offset == 0.01  # the base is untouched (frozen)
    with pytest.raises(ParameterError, match="journal_radius"):
        apply_values(BASE, WEAR, {"joint.bearing_radius": 7e-3})


def test_every_numeric_parameter_has_units():
    for name in numeric_fields(BASE, WEAR):
        units = parameter_units(name)
        assert units
    assert parameter_units("joint.bearing_radius") == "m"
    assert parameter_units("wear.kw") == "m2 N-1"
    assert parameter_units("friction.dynamic_coefficient") == "1"
    assert parameter_units("mechanism.follower_mass") == "kg"


def test_function_runs_check_their_inputs():
    with pytest.raises(ParameterError, match="has no input 'x4'"):
        read_spec(
            {
                "sweep": {"run": "function", "function": "ishigami", "method": "lhs", "samples": 4},
                "parameters": {"x4": {"distribution": "uniform", "bounds": [0, 1]}},
            }
        )
    with pytest.raises(ParameterError, match="needs input"):
        read_spec(
            {
                "sweep": {"run": "function", "function": "ishigami", "method": "lhs", "samples": 4},
                "parameters": {"x1": {"distribution": "uniform", "bounds": [0, math.pi]}},
            }
        )
    with pytest.raises(ParameterError, match="unknown option"):
        read_spec(
            {
                "sweep": {
                    "run": "function",
                    "function": "linear",
                    "method": "lhs",
                    "samples": 4,
                    "function_args": {"dealy": 1},
                },
                "parameters": {"x1": {"distribution": "uniform", "bounds": [0, 1]}},
            }
        )


def test_an_unworn_bore_has_no_location_of_maximum_wear():
    from jointwear.sim.sweep._outputs import wear_outputs
    from jointwear.sim.wearmap import BearingGrid, wear_map_dataset

    grid = BearingGrid(4, 24)
    maps = np.zeros((2, *grid.shape))
    maps[1, 2, 5] = 1e-6  # layer 2 (from +z), point 5
    ds = wear_map_dataset(maps, np.array([10.0, 20.0]), grid)
    out = wear_outputs(ds)
    assert out["max_wear_theta"] == pytest.approx(5 * 360 / 24)
    assert out["max_wear_z"] == pytest.approx(grid.z[2])
    out = wear_outputs(ds.isel(cycles=[0]))
    assert out["max_wear_depth"] == 0 and math.isnan(out["max_wear_theta"])
    assert math.isnan(out["max_wear_z"])


def test_the_specs_in_the_guide_are_valid():
    import re
    import tomllib
    from pathlib import Path

    guide = Path(__file__).resolve().parents[2] / "docs" / "sweeps.md"
    blocks = re.findall(r"```toml\n(.*?)```", guide.read_text(encoding="utf-8"), re.S)
    assert len(blocks) >= 2
    for block in blocks:
        s = read_spec(tomllib.loads(block))
        _check_feasible(s, BASE, WEAR)
        assert make_design(s).n_runs >= 32


@pytest.mark.parametrize(
    "name, values",
    [
        ("joint.n_layers", [10, 20]),
        ("joint.axial_grading", [0.0, 0.5]),
        ("joint.bearing_width", [0.01, 0.015]),
    ],
)
def test_kept_wear_maps_refuse_a_swept_grid_parameter_naming_it(name, values):
    # the maps of such runs lie on different grids (z or theta) and cannot be stacked
    with pytest.raises(ParameterError, match=rf"with {name} swept: .* drop wear_depth from keep"):
        read_spec(spec(method="grid", keep=["wear_depth"], parameters={name: {"values": values}}))
    read_spec(spec(method="grid", keep=["contact_force"], parameters={name: {"values": values}}))
