"""The slider-crank: closed-form kinematics, the ideal joint against a hand-derived Lagrangian,
the clearance -> 0 limit, the power balance of the clearance model and the benchmark's
qualitative signatures."""

from __future__ import annotations

import math

import numpy as np
import pytest

from jointwear.errors import ParameterError
from jointwear.params import replace_nested
from jointwear.sim import PARAMETER_SETS, load_parameters, run_cycles
from jointwear.sim.slider_crank import SliderCrankParameters, slider_crank_kinematics

SC = PARAMETER_SETS["slider_crank"]
L1, L2 = 0.05, 0.12


def test_the_named_set_is_the_benchmark():
    m = SC.mechanism
    assert isinstance(m, SliderCrankParameters)
    assert (m.crank_length, m.rod_length) == (0.05, 0.12)
    assert SC.joint.radial_clearance == pytest.approx(0.5e-3)
    assert m.period == pytest.approx(60 / 5000)


def test_closed_form_kinematics_against_geometry_and_finite_differences():
    th = np.linspace(0, 2 * math.pi, 721)
    w, al = 37.0, 5.0
    k = slider_crank_kinematics(th, L1, L2, w, al)
    x, phi = k["slider_position"], k["rod_angle"]
    # the rod joins B and C
    bx, by = L1 * np.cos(th), L1 * np.sin(th)
    np.testing.assert_allclose(np.hypot(x - bx, by), L2, rtol=1e-14)
    np.testing.assert_allclose(bx + L2 * np.cos(phi), x, atol=1e-15)
    np.testing.assert_allclose(by + L2 * np.sin(phi), 0.0, atol=1e-15)
    # dead centres and stroke
    assert x[0] == pytest.approx(L1 + L2) and x[360] == pytest.approx(L2 - L1)
    # derivatives: central differences of the position along theta(t) = theta + w t + al t^2/2
    h = 1e-5

    def pos(dt):
        t2 = th + w * dt + 0.5 * al * dt * dt
        kk = slider_crank_kinematics(t2, L1, L2, 0.0)
        return kk["slider_position"], kk["rod_angle"]

    (xp, pp), (xm, pm), (x0, p0) = pos(h), pos(-h), pos(0.0)
    np.testing.assert_allclose(k["slider_velocity"], (xp - xm) / (2 * h), atol=1e-7)
    np.testing.assert_allclose(k["slider_acceleration"], (xp - 2 * x0 + xm) / h**2, atol=5e-3)
    np.testing.assert_allclose(k["rod_angular_velocity"], (pp - pm) / (2 * h), atol=1e-6)
    np.testing.assert_allclose(k["rod_angular_acceleration"], (pp - 2 * p0 + pm) / h**2, atol=5e-2)


@pytest.mark.parametrize(
    ("change", "names"),
    [
        ({"mechanism.rod_length": 0.04}, "rod_length"),
        ({"mechanism.bearing_on": "crank"}, "bearing_on"),
        ({"mechanism.clearance_at": "crank_rod", "mechanism.bearing_on": "slider"}, "bearing_on"),
        ({"mechanism.driver": False}, "driver"),
        ({"mechanism.rod_inertia": (1e-4, 1e-4)}, "rod_inertia"),
    ],
)
def test_inconsistent_slider_crank_parameters_are_refused(change, names):
    with pytest.raises(ParameterError, match=names):
        replace_nested(SC, **change)


def test_toml_overrides_on_the_slider_crank_base(tmp_path):
    good = tmp_path / "good.toml"
    good.write_text(
        "[mechanism]\ncrank_speed_rpm = 1000.0\nclearance_at = 'crank_rod'\nbearing_on = 'rod'\n"
    )
    p = load_parameters(good, base="slider_crank")
    assert p.mechanism.clearance_at == "crank_rod" and p.mechanism.rod_length == 0.12
    # a four-bar name on the slider-crank base is refused, naming it
    bad = tmp_path / "bad.toml"
    bad.write_text("[mechanism]\ncoupler_length = 0.4\n")
    with pytest.raises(ParameterError, match="coupler_length"):
        load_parameters(bad, base="slider_crank")
    # choosing the mechanism inside the file instead of with the base set is ambiguous
    kind = tmp_path / "kind.toml"
    kind.write_text("[mechanism]\nkind = 'slider_crank'\n")
    with pytest.raises(ParameterError, match="--base slider_crank"):
        load_parameters(kind, base="zhang2023")


def _lagrangian_torque(theta, m, omega):
    """Driver torque of the ideal slider-crank at constant crank speed, from its Lagrangian.

    One coordinate theta: T = M(theta) theta_dot^2 / 2 with the velocity ratios of the bodies,
    V = g (m1 L1/2 sin theta + m_rod y_G); tau = M'(theta) omega^2 / 2 + V'(theta)
    (central differences in theta).
    """
    l1, l2, h = m.crank_length, m.rod_length, 0.5 * m.rod_length
    g = m.gravity

    def mass_and_potential(t):
        s, c = np.sin(t), np.cos(t)
        sphi = -l1 * s / l2
        cphi = np.sqrt(1 - sphi**2)
        dphi = -l1 * c / (l2 * cphi)
        gx = -l1 * s - h * sphi * dphi
        gy = l1 * c + h * cphi * dphi
        dx = -l1 * s - l2 * sphi * dphi
        mass = (
            m.crank_inertia
            + m.crank_mass * (l1 / 2) ** 2
            + m.rod_mass * (gx * gx + gy * gy)
            + m.rod_inertia[2] * dphi**2
            + m.slider_mass * dx * dx
        )
        pot = g * (m.crank_mass * l1 / 2 * s + m.rod_mass * (l1 * s + h * sphi))
        return mass, pot

    d = 1e-5
    mp, vp = mass_and_potential(theta + d)
    mm, vm = mass_and_potential(theta - d)
    return 0.5 * (mp - mm) / (2 * d) * omega**2 + (vp - vm) / (2 * d)


def test_ideal_joint_dynamics_match_a_hand_derived_lagrangian():
    p = replace_nested(SC, **{"joint.model": "ideal", "mechanism.crank_speed_rpm": 3000.0})
    ds = run_cycles(p, cycles=1.0).dataset
    m = p.mechanism
    want = _lagrangian_torque(ds.crank_angle.values, m, m.crank_speed)
    got = ds.driver_torque.values
    scale = np.abs(want).max()
    np.testing.assert_allclose(got, want, atol=1e-6 * scale)
    # the comparison can fail: without the slider's mass the torque differs by far more
    wrong = _lagrangian_torque(
        ds.crank_angle.values, SliderCrankParameters(slider_mass=1e-9), m.crank_speed
    )
    assert np.abs(wrong - want).max() > 0.1 * scale


def _small_clearance(c, rpm=300.0):
    return replace_nested(
        SC,
        **{
            "mechanism.crank_speed_rpm": rpm,
            "joint.bearing_radius": SC.joint.journal_radius + c,
            "joint.n_layers": 2,
            "contact.max_penetration_fraction": 50.0,
            "solver.output_interval": 1e-4,
            "solver.max_step": 1e-3,
        },
    )


def test_clearance_to_zero_gives_the_closed_form_kinematics():
    stroke = 2 * L1
    errors = []
    for c in (5e-6, 5e-7, 2e-8):
        p = _small_clearance(c)
        ds = run_cycles(p, cycles=1.0).dataset
        k = slider_crank_kinematics(ds.crank_angle.values, L1, L2, p.mechanism.crank_speed)
        err = np.abs(ds.slider_position.values[:, 0] - k["slider_position"]).max()
        # the journal floats within the clearance and presses into the bearing by the penetration
        assert err <= 1.05 * c + float(ds.penetration.max())
        errors.append(err)
    assert errors[0] > 1e-6 * stroke  # the check is not satisfied trivially
    assert errors[-1] < 1e-6 * stroke
    assert errors[0] > errors[1] > errors[2]


def test_small_clearance_joint_force_approaches_the_ideal_joint_reaction():
    p = _small_clearance(2e-8, rpm=3000.0)
    ideal = replace_nested(p, **{"joint.model": "ideal"})
    a = run_cycles(p, cycles=2.0).dataset.isel(time=slice(-1201, None))
    b = run_cycles(ideal, cycles=2.0).dataset.isel(time=slice(-1201, None))
    fa, fb = a.bearing_force.values[:, :2], b.bearing_force.values[:, :2]
    assert np.abs(fa - fb).mean() < 0.02 * np.abs(fb).mean()


@pytest.mark.parametrize(
    "change",
    [
        {},
        {"mechanism.bearing_on": "rod"},
        {"mechanism.clearance_at": "crank_rod", "mechanism.bearing_on": "crank"},
        {"mechanism.planar": False, "mechanism.joint_offset": 5e-3},
        {
            "mechanism.planar": False,
            "mechanism.joint_offset": 5e-3,
            "mechanism.clearance_at": "crank_rod",
            "mechanism.bearing_on": "rod",
        },
    ],
)
def test_driver_work_equals_the_energy_change_without_dissipation(change):
    # restitution 1, no friction: the driver's work is the only energy input, impacts included
    p = replace_nested(SC, **{"contact.restitution": 1.0, "solver.output_interval": 2e-7, **change})
    ds = run_cycles(p, cycles=0.5).dataset
    t = ds.time.values
    power = ds.driver_torque.values * p.mechanism.crank_speed
    work = np.concatenate([[0.0], np.cumsum(0.5 * (power[1:] + power[:-1]) * np.diff(t))])
    energy = ds.mechanical_energy.values
    swing = energy.max() - energy.min()
    assert swing > 50.0  # the check sees real energy exchange
    assert np.abs(energy - energy[0] - work).max() < 2e-4 * swing
    assert int((ds.contact_mode.values == 0).sum()) > 0  # with free flights and impacts


def test_bearing_on_either_body_gives_the_same_motion():
    # the impacts at the benchmark clearance amplify last-bit differences (chaotic sequence);
    # with a small clearance the motion is regular and the two frames must agree
    p = _small_clearance(2e-8, rpm=3000.0)
    a = run_cycles(p, cycles=1.0).dataset
    b = run_cycles(replace_nested(p, **{"mechanism.bearing_on": "rod"}), cycles=1.0).dataset
    np.testing.assert_allclose(a.slider_position, b.slider_position, atol=1e-10)
    fmax = float(a.contact_force.max())
    np.testing.assert_allclose(a.contact_force, b.contact_force, atol=1e-4 * fmax)
    # the journal offset is the same vector seen from the other body (bearing frame)
    np.testing.assert_allclose(a.eccentricity, b.eccentricity, atol=1e-10)
    ecc = np.hypot(a.journal_offset[:, 0], a.journal_offset[:, 1])
    np.testing.assert_allclose(a.eccentricity, ecc, rtol=1e-12)


def _episodes(in_contact):
    """Start indices and lengths (samples) of the runs of True."""
    edges = np.diff(np.concatenate([[0], in_contact.astype(int), [0]]))
    start = np.flatnonzero(edges == 1)
    return start, np.flatnonzero(edges == -1) - start


def test_benchmark_clearance_shows_the_published_signatures():
    # Flores et al.: with 0.5 mm clearance at the rod-slider joint the journal alternates free
    # flight, impacts and continuous contact; the joint force has peaks far above the ideal
    # joint's reaction, after the load reversal; the slider acceleration has peaks
    ds = run_cycles(SC, cycles=6.0).dataset.isel(time=slice(1200, None))  # after one cycle
    ideal = run_cycles(replace_nested(SC, **{"joint.model": "ideal"}), cycles=1.0).dataset
    dt = float(SC.solver.output_interval)
    mode = ds.contact_mode.values
    assert (mode == 0).mean() > 0.1  # free flight
    start, length = _episodes(mode != 0)
    impacts = start[length * dt < 2e-4]
    assert impacts.size >= 15  # trains of impacts
    assert (length * dt).max() > 0.3 * SC.mechanism.period  # continuous contact
    assert float(ds.contact_force.max()) > 5 * float(ideal.contact_force.max())
    acc = np.abs(ds.slider_acceleration.values[:, 0])
    assert acc.max() > 3 * np.abs(ideal.slider_acceleration.values[:, 0]).max()
    # the impacts follow the load reversal: the ideal slider acceleration (the joint's axial
    # load) turns from pulling to pushing at about 75 degrees and back at about 285 degrees
    k = slider_crank_kinematics(ds.crank_angle.values, L1, L2, SC.mechanism.crank_speed)
    pushing = k["slider_acceleration"] > 0
    assert pushing[impacts].mean() > 0.9
    assert pushing.mean() < 0.65  # the band is not the whole cycle


def test_cli_cycle_and_wear_on_the_slider_crank_base(tmp_path, capsys):
    import json

    from jointwear import io
    from jointwear.cli import main

    out = tmp_path / "sc.nc"
    code = main(["sim", "cycle", "--base", "slider_crank", "--cycles", "0.25", "--out", str(out)])
    assert code == 0, capsys.readouterr().err
    ds = io.load(out)
    for name in ("slider_position", "slider_velocity", "slider_acceleration"):
        assert ds[name].dims == ("time", "axis")
    assert ds.slider_position.attrs["units"] == "m"
    assert ds.attrs["data_origin"] == "simulated" and "slider-crank" in ds.attrs["title"]
    mech = json.loads(ds.attrs["parameters_json"])["mechanism"]
    assert (mech["crank_length"], mech["rod_length"]) == (0.05, 0.12)
    # the slider moves along the closed form's stroke (within the clearance and penetration)
    k = slider_crank_kinematics(ds.crank_angle.values, L1, L2, SC.mechanism.crank_speed)
    assert np.abs(ds.slider_position.values[:, 0] - k["slider_position"]).max() < 1e-3
    wear = tmp_path / "scw.nc"
    code = main(
        [
            "sim",
            "wear",
            "--base",
            "slider_crank",
            "--cycles",
            "300",
            "--out",
            str(wear),
            "--no-progress",
        ]
    )
    assert code == 0, capsys.readouterr().err
    w = io.load(wear)
    assert w.wear_depth.sizes["z"] == SC.joint.n_layers
    assert float(w.max_wear_depth.isel(cycles=-1)) > 0
    assert w.attrs["bearing_radius_m"] == pytest.approx(10e-3)
    # an unknown base is bad input naming the known sets
    code = main(
        ["sim", "wear", "--base", "slider", "--cycles", "10", "--out", str(tmp_path / "x.nc")]
    )
    assert code == 3 and "slider_crank" in capsys.readouterr().err


def test_sweep_on_the_slider_crank_base(tmp_path):
    from jointwear.sim import run_sweep

    spec = {
        "sweep": {
            "run": "cycle",
            "cycles": 0.25,
            "method": "grid",
            "outputs": ["mean_contact_force", "slider_velocity_rms", "follower_velocity_rms"],
        },
        "parameters": {"mechanism.crank_speed_rpm": {"values": [2000.0, 4000.0]}},
    }
    ds = run_sweep(spec, base="slider_crank", workers=0)
    assert (ds.status.values == 0).all()  # flag 0 = ok
    v = ds.slider_velocity_rms.values
    assert v[1] == pytest.approx(2 * v[0], rel=0.05)  # the slider's speed scales with the crank's
    assert np.isnan(ds.follower_velocity_rms.values).all()  # not assessed: no follower


def test_plot_cycle_draws_a_slider_crank_record(tmp_path):
    from jointwear.sim import plot_cycle

    ds = run_cycles(SC, cycles=0.2).dataset
    fig = plot_cycle(ds, tmp_path / "sc.png")
    assert (tmp_path / "sc.png").stat().st_size > 0
    assert fig.axes[2].get_title() == "slider"


def test_a_four_bar_state_does_not_continue_a_slider_crank(tmp_path):
    from jointwear.errors import BadInputError

    fb = replace_nested(PARAMETER_SETS["zhang2023"], **{"joint.n_layers": SC.joint.n_layers})
    state = run_cycles(fb, cycles=0.01, record=False).state  # same length of state vector
    with pytest.raises(BadInputError, match="four_bar run"):
        run_cycles(SC, cycles=0.1, state=state)
    # a slider-name in a four-bar parameter file is refused, naming it
    bad = tmp_path / "bad.toml"
    bad.write_text("[mechanism]\nrod_length = 0.12\n")
    with pytest.raises(ParameterError, match="rod_length"):
        load_parameters(bad)
