"""Parameters of the simulator: the study's tables, TOML overrides, clear errors."""

from __future__ import annotations

import math

import pytest

from jointwear.errors import ParameterError
from jointwear.params import replace_nested
from jointwear.sim import PARAMETER_SETS, contact_constant, load_parameters


def test_default_set_holds_tables_1_and_2():
    p = PARAMETER_SETS["zhang2023"]
    m, j, c, f = p.mechanism, p.joint, p.contact, p.friction
    assert (m.crank_length, m.coupler_length, m.follower_length, m.ground_length) == (
        0.10,
        0.40,
        0.30,
        0.30,
    )
    assert (m.crank_mass, m.coupler_mass, m.follower_mass) == (0.46, 1.45, 1.50)
    assert (m.crank_inertia, m.coupler_inertia) == (0.0019, 0.0927)
    assert m.follower_inertia == (0.0317, 0.0004, 0.0317)
    assert m.period == pytest.approx(0.5)
    assert 2 * j.journal_radius == pytest.approx(15e-3)
    assert 2 * j.bearing_radius == pytest.approx(16e-3)
    assert (j.journal_length, j.bearing_width) == (17e-3, 15e-3)
    assert j.radial_clearance == pytest.approx(0.5e-3)
    assert j.axial_clearance == 1e-3
    assert (j.n_layers, j.n_points) == (20, 200)
    assert c.restitution == 0.9
    assert (f.static_coefficient, f.dynamic_coefficient) == (0.2, 0.1)
    assert (f.stick_velocity, f.slide_velocity) == (1e-3, 1e-2)


def test_constant_stiffness_eq7():
    # notes: "with Table 2 values K ~ 3.6e10 N/m^1.5"; recompute eq. 7 by hand
    hj = (1 - 0.29**2) / (math.pi * 207e9)
    hb = (1 - 0.39**2) / (math.pi * 100e9)
    k = 4 / (3 * math.pi * (hj + hb)) * math.sqrt(7.5e-3 * 8e-3 / 0.5e-3)
    assert contact_constant(PARAMETER_SETS["zhang2023"])[1] == pytest.approx(k, rel=1e-12)
    assert k == pytest.approx(3.6e10, rel=0.01)


def test_unknown_set_lists_names():
    with pytest.raises(KeyError, match="unknown parameter set 'nope'.*zhang2023"):
        PARAMETER_SETS["nope"]


def test_toml_overrides(tmp_path):
    f = tmp_path / "p.toml"
    f.write_text(
        "[joint]\nbearing_radius = 8.1e-3\nn_layers = 40\n[contact]\nstiffness = 'constant'\n"
        "[wear]\ncycles = 1000\n"
    )
    p = load_parameters(f)
    assert p.joint.bearing_radius == 8.1e-3
    assert p.joint.n_layers == 40
    assert p.joint.n_points == 200
    assert p.contact.stiffness == "constant"
    assert p.mechanism == PARAMETER_SETS["zhang2023"].mechanism


def test_toml_unknown_names(tmp_path):
    f = tmp_path / "p.toml"
    f.write_text("[joint]\nbearing_radus = 8.1e-3\n")
    with pytest.raises(ParameterError, match=r"p.toml.*joint.bearing_radus.*known names"):
        load_parameters(f)
    f.write_text("[joints]\nbearing_radius = 8.1e-3\n")
    with pytest.raises(ParameterError, match=r"unknown table\(s\)/name\(s\) joints"):
        load_parameters(f)
    f.write_text("[contact]\nformulation = 'paper'\n")
    with pytest.raises(ParameterError, match=r"contact.formulation: expected one of"):
        load_parameters(f)


@pytest.mark.parametrize(
    ("change", "match"),
    [
        ({"joint.journal_radius": 8.0e-3}, r"joint.journal_radius .* must be smaller than"),
        ({"joint.journal_radius": 8.5e-3}, r"radial clearance .* is not positive"),
        ({"joint.axial_clearance": -1e-3}, r"joint.axial_clearance must be >= 0"),
        ({"mechanism.coupler_mass": 0.0}, r"mechanism.coupler_mass must be a positive"),
        ({"mechanism.follower_inertia": (0.03, 0.0, 0.03)}, r"follower_inertia\[1\]"),
        ({"mechanism.crank_length": 0.35}, r"Grashof crank-rocker"),
        ({"joint.journal_length": 10e-3}, r"joint.journal_length"),
        ({"contact.restitution": 1.5}, r"contact.restitution must be in"),
        ({"friction.slide_velocity": 1e-4}, r"friction.slide_velocity"),
    ],
)
def test_bad_geometry_names_the_parameter(change, match):
    with pytest.raises(ParameterError, match=match):
        replace_nested(PARAMETER_SETS["zhang2023"], **change)


@pytest.mark.parametrize("base", ["zhang2023", "slider_crank"])
@pytest.mark.parametrize("name", ["joint_offset", "crank_speed_rpm", "initial_crank_angle_deg"])
def test_non_finite_mechanism_values_are_refused_by_name(base, name):
    # a NaN start angle or speed would integrate into a NaN record instead of an error
    with pytest.raises(ParameterError, match=rf"mechanism\.{name} must be finite"):
        replace_nested(PARAMETER_SETS[base], **{f"mechanism.{name}": float("nan")})


@pytest.mark.parametrize(
    ("base", "name", "axes"),
    [
        ("zhang2023", "follower_inertia", "I3x, I3y, I3z"),
        ("slider_crank", "rod_inertia", "Ix, Iy, Iz"),
    ],
)
def test_inertia_triples_are_checked_alike(base, name, axes):
    with pytest.raises(ParameterError, match=rf"mechanism\.{name} must hold 3 values \({axes}\)"):
        replace_nested(PARAMETER_SETS[base], **{f"mechanism.{name}": (1e-3, 1e-3)})
    with pytest.raises(ParameterError, match=rf"mechanism\.{name}\[1\] must be a positive"):
        replace_nested(PARAMETER_SETS[base], **{f"mechanism.{name}": (1e-3, -1e-3, 1e-3)})
