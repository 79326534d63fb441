"""The mechanism registry: every mechanism switch reads it, and a parameter the chosen mechanism
and mode cannot use is refused (naming it and what would make it apply), per key and mechanism.

Truth: a planar slider-crank ignores the 3D-only keys (a run with them is bit-identical, issue
41), so they are refused there; with ``planar = false`` (the fix the refusal prints) they act,
so the same values are accepted and change the run.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from jointwear.cli import main
from jointwear.errors import ParameterError
from jointwear.params import replace_nested
from jointwear.sim import PARAMETER_SETS, run_cycles
from jointwear.sim.mechanisms import (
    MECHANISMS,
    PARAMETER_NEEDS,
    Mechanism,
    mechanism_of,
    register_mechanism,
)
from jointwear.sim.parameters import MechanismParameters, parameters_from_tables
from jointwear.sim.slider_crank import SliderCrankParameters
from jointwear.sim.sweep._params import apply_values
from jointwear.sim.wear import WearSettings
from jointwear.sim.wear._loop import apply_overrides

SLIDER = PARAMETER_SETS["slider_crank"]
FOUR_BAR = PARAMETER_SETS["zhang2023"]

#: a value of each 3D-only key that differs from the slider-crank set's
SPATIAL = {
    "mechanism.joint_offset": 0.004,
    "joint.tilt_stiffness": 50.0,
    "joint.tilt_damping": 0.01,
    "joint.axial_clearance": 2e-4,
    "joint.thrust_radius": 0.0105,
    "contact.axial_stiffness": 1e9,
}


def _tables(name: str, value, **extra) -> dict:
    table, key = name.split(".")
    data = {table: {key: value}}
    for dotted, v in extra.items():
        t, k = dotted.split(".")
        data.setdefault(t, {})[k] = v
    return data


def test_every_3d_only_key_is_declared():
    assert set(SPATIAL) == set(PARAMETER_NEEDS)
    assert {need for need, _ in PARAMETER_NEEDS.values()} == {"spatial"}


@pytest.mark.parametrize("name", sorted(SPATIAL))
def test_3d_only_key_on_the_planar_slider_crank_is_refused(name):
    value = SPATIAL[name]
    with pytest.raises(ParameterError) as exc:
        parameters_from_tables(_tables(name, value), "slider_crank")
    msg = str(exc.value)
    assert name in msg and "no effect on the slider-crank" in msg
    assert "set mechanism.planar = false" in msg
    # through the wear module's overrides and a sweep's run values as well
    with pytest.raises(ParameterError, match="mechanism.planar = false"):
        apply_overrides(SLIDER, WearSettings(), {name: value})
    with pytest.raises(ParameterError, match=name.replace(".", r"\.")):
        apply_values(SLIDER, WearSettings(), {name: value})
    # the fix as printed: the same value with planar = false is accepted
    p = parameters_from_tables(_tables(name, value, **{"mechanism.planar": False}), "slider_crank")
    table, key = name.split(".")
    assert getattr(getattr(p, table), key) == value


@pytest.mark.parametrize("name", sorted(SPATIAL))
def test_the_base_sets_own_value_written_out_is_harmless(name):
    table, key = name.split(".")
    base = getattr(getattr(SLIDER, table), key)
    assert parameters_from_tables(_tables(name, base), "slider_crank") == SLIDER
    assert apply_overrides(SLIDER, WearSettings(), {name: base})[0] == SLIDER


def test_3d_only_keys_act_once_the_slider_crank_is_spatial():
    """The fix the refusal prints gives a run the key changes (it was not a dead key)."""
    spatial = replace_nested(SLIDER, **{"mechanism.planar": False, "mechanism.joint_offset": 0.005})
    base = run_cycles(spatial, cycles=1.0, record=False)
    stiff = run_cycles(
        replace_nested(spatial, **{"joint.tilt_stiffness": 200.0}), cycles=1.0, record=False
    )
    assert not np.array_equal(base.state.y, stiff.state.y)


def test_four_bar_keys_on_the_four_bar_are_all_accepted():
    for name, value in SPATIAL.items():
        p = parameters_from_tables(_tables(name, value), "zhang2023")
        table, key = name.split(".")
        assert getattr(getattr(p, table), key) == value


def _own(cls, other) -> list[str]:
    mine = {f.name for f in dataclasses.fields(cls)}
    return sorted(mine - {f.name for f in dataclasses.fields(other)})


@pytest.mark.parametrize("key", _own(SliderCrankParameters, MechanismParameters))
def test_slider_crank_keys_on_the_four_bar_name_the_base(key):
    value = getattr(SLIDER.mechanism, key)
    with pytest.raises(ParameterError, match="--base slider_crank"):
        parameters_from_tables({"mechanism": {key: value}}, "zhang2023")
    with pytest.raises(ParameterError, match="--base slider_crank"):
        apply_overrides(FOUR_BAR, WearSettings(), {f"mechanism.{key}": 1.0})


@pytest.mark.parametrize("key", _own(MechanismParameters, SliderCrankParameters))
def test_four_bar_keys_on_the_slider_crank_name_the_base(key):
    value = getattr(FOUR_BAR.mechanism, key)
    with pytest.raises(ParameterError, match="--base zhang2023"):
        parameters_from_tables({"mechanism": {key: value}}, "slider_crank")


def test_cli_refuses_with_exit_3_and_the_printed_fix_runs(tmp_path, capsys):
    toml = tmp_path / "p.toml"
    toml.write_text("[joint]\ntilt_stiffness = 100.0\n")
    out = tmp_path / "c.nc"
    args = ["sim", "cycle", "--base", "slider_crank", "--cycles", "0.5", "--params", str(toml)]
    assert main([*args, "--out", str(out)]) == 3
    err = capsys.readouterr().err
    assert "joint.tilt_stiffness" in err and "mechanism.planar = false" in err
    assert not out.exists()
    toml.write_text("[joint]\ntilt_stiffness = 100.0\n\n[mechanism]\nplanar = false\n")
    assert main([*args, "--out", str(out)]) == 0


@dataclasses.dataclass(frozen=True)
class ToyParameters(MechanismParameters):
    """A toy mechanism: the four-bar's links, declared planar-only."""


def test_a_registered_toy_mechanism_is_what_every_switch_reads():
    toy = Mechanism(
        name="toy",
        title="toy linkage",
        parameters=ToyParameters,
        parameter_set="zhang2023",
        record="jointwear.sim._four_bar_record",
        kernel_flag=MECHANISMS["four_bar"].kernel_flag,
        capabilities=lambda p: frozenset(),
    )
    register_mechanism(toy)
    try:
        with pytest.raises(ValueError, match="already registered"):
            register_mechanism(toy)
        params = dataclasses.replace(
            FOUR_BAR,
            mechanism=ToyParameters(joint_offset=0.0),
            joint=dataclasses.replace(FOUR_BAR.joint, model="ideal"),
        )
        assert mechanism_of(params) is toy
        res = run_cycles(params, cycles=0.05)
        assert res.state.mechanism == "toy"
        assert "toy linkage" in res.dataset.attrs["title"]
        # its declared capabilities refuse the 3D-only keys, with no setting to offer
        with pytest.raises(ParameterError, match="the toy linkage cannot model it"):
            apply_overrides(params, WearSettings(), {"joint.tilt_stiffness": 10.0})
    finally:
        MECHANISMS.pop("toy")
    with pytest.raises(ParameterError, match="no registered mechanism"):
        mechanism_of(params)


def test_base_help_lists_every_registered_parameter_set():
    # --base's help is written out (jointwear --help does not import the registry): it must
    # list the registry's sets and titles, and its default must be one of them
    from jointwear.sim._cli_options import BASE_SETS, Base, base_sets
    from jointwear.sim._defaults import DEFAULT_PARAMETER_SET

    assert base_sets(MECHANISMS) == BASE_SETS
    assert {m.parameter_set for m in MECHANISMS.values()} == set(PARAMETER_SETS)
    assert DEFAULT_PARAMETER_SET in PARAMETER_SETS
    help_text = Base.__metadata__[0].help
    assert f"mechanism: {BASE_SETS}; default {DEFAULT_PARAMETER_SET}." in help_text
