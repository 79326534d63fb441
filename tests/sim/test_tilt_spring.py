"""The lumped tilt spring-damper of joint C (``joint.tilt_stiffness``, ``joint.tilt_damping``).

Truths: for stiffness 0 the simulator before the spring, bit for bit (the defaults have
k = c = 0, and ``test_kernels_split.py`` pins the defaults to the kernels of commit 7a7587e);
the closed-form oscillator
theta(t) = (w0 / wn) exp(-zeta wn t) sin(wd t) of the follower rocking about its own axis
(body y, moment of inertia I3y) on the spring, without gravity, drive or contact; conservation
of the mechanical energy (which then includes k theta^2 / 2) with impacts; and the wear on the
default rig, which a stiff spring moves from the bearing edges to the whole width.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from jointwear.errors import ParameterError
from jointwear.params import replace_nested
from jointwear.sim import (
    DEFAULT_KW,
    PARAMETER_SETS,
    WearSettings,
    edge_volume_share,
    initial_state,
    run_cycles,
    simulate_wear,
)

BASE = PARAMETER_SETS["zhang2023"]


def _rocking(k: float, c: float, w0: float = 0.5, t_end: float = 0.02):
    """Follower rocking about its own axis on the tilt spring: no gravity, crank held."""
    p = replace_nested(
        BASE,
        **{
            "mechanism.gravity": 0.0,
            "mechanism.crank_speed_rpm": 0.0,
            "joint.tilt_stiffness": k,
            "joint.tilt_damping": c,
            "solver.output_interval": 1e-5,
        },
    )
    st = initial_state(p)
    y = st.y.copy()
    y[8:11] = (0.0, w0, 0.0)  # body-frame angular velocity of the follower: about its axis
    st = dataclasses.replace(st, y=y)
    ds = run_cycles(p, duration=t_end, state=st).dataset
    # signed tilt: the journal axis leans along the bearing's x when the follower turns about y
    signed = np.arcsin(np.clip(ds["journal_axis"].sel(axis="x").values, -1, 1))
    return p, ds, ds["time"].values, signed


@pytest.mark.parametrize("damping_ratio", [0.0, 0.05])
def test_follower_rocks_on_the_tilt_spring_as_the_closed_form_oscillator(damping_ratio):
    k = 1000.0
    inertia = BASE.mechanism.follower_inertia[1]  # about the link axis through D and the COM
    wn = math.sqrt(k / inertia)
    c = damping_ratio * 2.0 * math.sqrt(k * inertia)
    w0 = 0.5
    p, ds, t, signed = _rocking(k, c, w0)
    assert int(np.max(ds["contact_mode"].values)) == 0  # no contact: the spring alone
    wd = wn * math.sqrt(1.0 - damping_ratio**2)
    exact = w0 / wd * np.exp(-damping_ratio * wn * t) * np.sin(wd * t)
    amplitude = w0 / wn
    assert np.max(np.abs(signed)) > 0.5 * amplitude
    sign = np.sign(np.sum(signed * exact))  # the axis sign convention of the record
    np.testing.assert_allclose(sign * signed, exact, atol=0.01 * amplitude)
    assert ds["journal_tilt"].values == pytest.approx(np.abs(exact), abs=0.01 * amplitude)


def test_an_anti_restoring_spring_would_fail_the_oscillator_check():
    # the check above can fail: a spring without stiffness lets the follower drift instead
    _, _, t, signed = _rocking(0.0, 0.0, 0.5, t_end=0.005)
    wn = math.sqrt(1000.0 / BASE.mechanism.follower_inertia[1])
    exact = 0.5 / wn * np.sin(wn * t)
    assert np.max(np.abs(np.abs(signed) - np.abs(exact))) > 0.1 * 0.5 / wn


def _free_rig(damping: float):
    """No drive, no friction, elastic impacts (ce = 1), tilt spring of 300 N m/rad."""
    return replace_nested(
        BASE,
        **{
            "mechanism.driver": False,
            "friction.enabled": False,
            "contact.restitution": 1.0,
            "joint.tilt_stiffness": 300.0,
            "joint.tilt_damping": damping,
        },
    )


def test_energy_is_conserved_with_the_spring_and_impacts():
    assert BASE.joint.tilt_stiffness == 0.0 and BASE.joint.tilt_damping == 0.0  # the defaults
    ds = run_cycles(_free_rig(0.0), cycles=1.0).dataset
    e = ds["mechanical_energy"].values
    assert np.abs(e - e[0]).max() / abs(e[0]) < 1e-4
    assert ds["contact_force"].max() > 100.0  # impacts happened
    spring = 0.5 * 300.0 * float(ds["journal_tilt"].max()) ** 2
    assert spring > 10 * 1e-4 * abs(e[0])  # the spring's energy is visible at that tolerance


def test_tilt_damping_dissipates():
    e = run_cycles(_free_rig(2.0), cycles=0.5).dataset["mechanical_energy"].values
    assert e[-1] < e[0] - 1e-3 * abs(e[0])
    assert np.all(np.diff(e) < 1e-6 * abs(e[0]))  # never gains energy


@pytest.mark.parametrize("name", ["joint.tilt_stiffness", "joint.tilt_damping"])
def test_negative_tilt_parameters_are_refused(name):
    with pytest.raises(ParameterError, match=name.split(".")[1]):
        replace_nested(BASE, **{name: -1.0})


def test_a_stiff_tilt_spring_spreads_the_wear_over_the_width():
    # reduced size: 10 x 60 grid, kw x 100 and 4000 cycles (the study-equivalent 4e5)
    params = replace_nested(BASE, **{"joint.n_layers": 10, "joint.n_points": 60})
    settings = WearSettings(kw=DEFAULT_KW * 100, tol=0.2, dn=50)
    share = {}
    for k in (0.0, 1e3):
        ds = simulate_wear(
            params,
            cycles=4000,
            snapshots=[],
            settings=settings,
            overrides={"joint.tilt_stiffness": k},
        )
        share[k] = float(edge_volume_share(ds["wear_depth"].isel(cycles=-1)))
    # uniform wear along z puts 20 % of the volume outside |z| <= 6 mm (15 mm bearing)
    assert share[0.0] > 0.5
    assert share[1e3] < 0.3


def test_edge_share_of_uniform_and_edge_wear_and_a_map_too_narrow():
    import xarray as xr

    from jointwear.errors import BadInputError

    z = np.linspace(-7.5e-3, 7.5e-3, 9) ** 3 / 7.5e-3**2  # unequal spacing: exact anyway
    th = np.arange(8.0) * 45.0
    uniform = xr.DataArray(np.ones((9, 8)), dims=("z", "theta"), coords={"z": z, "theta": th})
    assert float(edge_volume_share(uniform)) == pytest.approx(0.2, abs=1e-12)  # 3 of 15 mm
    zl = np.array([-7.5, -6.0, -3.0, 0.0, 3.0, 6.0, 7.5]) * 1e-3
    ramp = np.maximum(np.abs(zl) - 6e-3, 0.0)[:, None] * np.ones((1, 8))  # zero inside +-6 mm
    edge = xr.DataArray(ramp, dims=("z", "theta"), coords={"z": zl, "theta": th})
    assert float(edge_volume_share(edge)) == pytest.approx(1.0, abs=1e-12)
    with pytest.raises(BadInputError, match="does not reach beyond"):
        edge_volume_share(uniform.assign_coords(z=z * 0.7))  # a measured band of +-5.25 mm
