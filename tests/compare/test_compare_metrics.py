"""Metrics against closed forms and textbook cases."""

from __future__ import annotations

import math

import numpy as np
import pytest

import jointwear.compare as jc
from jointwear.errors import BadInputError


def test_rmse_nrmse_r_closed_forms():
    d = np.array([0.0, 1.0, 2.0, 3.0])
    s = d + np.array([1.0, -1.0, 1.0, -1.0])
    assert jc.rmse(s, d) == pytest.approx(1.0)
    assert jc.nrmse(s, d) == pytest.approx(1.0 / 3.0)
    assert jc.pearson_r(d, d) == pytest.approx(1.0)
    assert jc.pearson_r(-2 * d + 5, d) == pytest.approx(-1.0)
    assert math.isnan(jc.nrmse(d, np.ones(4)))


def test_metrics_refuse_different_grids():
    with pytest.raises(BadInputError, match="same grid"):
        jc.rmse(np.zeros(3), np.zeros(4))


@pytest.mark.parametrize("ratio", [0.5, 1.0, 1.2, 3.0])
def test_sprague_geers_pure_amplitude_error(ratio):
    t = np.linspace(0, 2, 401)
    d = np.exp(-t) * np.sin(2 * np.pi * 3 * t)
    sg = jc.sprague_geers(ratio * d, d)
    assert sg.M == pytest.approx(ratio - 1.0, abs=1e-12)
    assert sg.P == pytest.approx(0.0, abs=1e-6)
    assert sg.C == pytest.approx(abs(ratio - 1.0), abs=1e-6)


@pytest.mark.parametrize("shift", [0.1, 0.5, 1.0, 2.0])
def test_sprague_geers_pure_phase_shift(shift):
    t = np.linspace(0, 4 * np.pi, 4000, endpoint=False)  # two whole periods
    sg = jc.sprague_geers(np.sin(t + shift), np.sin(t))
    assert sg.M == pytest.approx(0.0, abs=1e-9)
    assert sg.P == pytest.approx(shift / np.pi, abs=1e-9)


def test_sprague_geers_opposite_sign_is_phase_one():
    t = np.linspace(0, 2 * np.pi, 100, endpoint=False)
    assert jc.sprague_geers(-np.sin(t), np.sin(t)).P == pytest.approx(1.0)


def test_vv20_verdict_flips_where_e_crosses_uval():
    # E = 3; u_val = sqrt(1 + 0.5^2 + u_D^2); k = 2
    below = jc.vv20(10.0, 7.0, u_num=1.0, u_input=0.5, u_d=1.0, k=2.0)  # U = 3.0 -> pass (equal)
    assert (
        below.E == 3.0 and below.u_val == pytest.approx(1.5) and below.U_val == pytest.approx(3.0)
    )
    assert below.passed
    above = jc.vv20(10.0, 7.0, u_num=1.0, u_input=0.5, u_d=0.99, k=2.0)
    assert above.U_val < 3.0 and not above.passed
    assert jc.vv20(7.0, 10.0, u_num=1.6, k=2.0).passed  # |E| = 3 <= 3.2, sign does not matter
    with pytest.raises(BadInputError, match="u_D must be a finite number >= 0"):
        jc.vv20(1.0, 1.0, u_d=-1.0)


def test_area_validation_metric_closed_forms():
    assert jc.area_validation_metric([2.0], [5.0]) == pytest.approx(3.0)
    rng = np.random.default_rng(3)
    x = rng.normal(size=500)
    assert jc.area_validation_metric(x + 0.7, x) == pytest.approx(0.7)
    assert jc.area_validation_metric(x, x) == 0.0
    # uniform [0,1] sample vs point mass at 0.5: integral |F| = 0.25
    u = (np.arange(10000) + 0.5) / 10000
    assert jc.area_validation_metric(u, [0.5]) == pytest.approx(0.25, abs=1e-6)


def test_wrap_angle():
    assert jc.wrap_angle_deg(350.0) == pytest.approx(-10.0)
    assert jc.wrap_angle_deg(-190.0) == pytest.approx(170.0)
    assert jc.wrap_angle_deg(180.0) == pytest.approx(180.0)


def test_max_location_sub_grid():
    theta = np.arange(0, 360, 2.0)
    z = np.array([-1e-3, 0.0, 1e-3])
    true = 101.3
    d = (theta - true + 180) % 360 - 180
    field = np.exp(-0.5 * (d / 20.0) ** 2)[None, :] * np.array([0.5, 1.0, 0.2])[:, None]
    value, zmax, th = jc.max_location(field, z, theta)
    assert zmax == 0.0
    assert th == pytest.approx(true, abs=0.05)
    assert value == pytest.approx(1.0, abs=1e-3)


def test_worn_volume_uniform_depth():
    theta = np.arange(0, 360, 1.0)
    z = np.linspace(-5e-3, 5e-3, 11)
    h = np.full((11, 360), 10e-6)
    # uniform depth h over radius R and width w: 2 pi R w h
    assert jc.worn_volume(h, z, theta, 8e-3) == pytest.approx(2 * np.pi * 8e-3 * 10e-3 * 10e-6)


def test_lsq_cylindricity_removes_offset_and_tilt():
    theta = np.arange(0, 360, 3.0)
    z = np.linspace(-5e-3, 5e-3, 6)
    tr = np.deg2rad(theta)[None, :]
    zz = z[:, None]
    # eccentric, tilted perfect cylinder: zero cylindricity
    field = 3e-6 + (2e-6 + 1e-4 * zz) * np.cos(tr) - (1e-6 - 2e-4 * zz) * np.sin(tr)
    assert jc.lsq_cylindricity(field, z, theta) == pytest.approx(0.0, abs=1e-15)
    # a pure second harmonic of amplitude a: peak-to-valley 2a
    assert jc.lsq_cylindricity(field + 4e-6 * np.cos(2 * tr) + 0 * zz, z, theta) == pytest.approx(
        8e-6, rel=1e-9
    )
