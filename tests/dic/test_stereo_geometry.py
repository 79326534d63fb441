"""Triangulation, uncertainty, rigid fits and differentiation against projected ground truth."""

from __future__ import annotations

import numpy as np
import pytest

from jointwear.datasets.rig import RigConfig, VirtualRig
from jointwear.dic.calibration._stereo import epipolar_distance, stereo_noise_floor, triangulate
from jointwear.dic.footage._rigid import (
    fit_rigid,
    fit_rigid_robust,
    rotation_angle_z,
    time_derivative,
)
from jointwear.errors import BadInputError


@pytest.fixture(scope="module")
def cal():
    return VirtualRig(RigConfig(width=1280, height=1024)).calibration


def _points(n, seed=0):
    rng = np.random.default_rng(seed)
    return np.column_stack(
        [rng.uniform(0.15, 0.45, n), rng.uniform(0.0, 0.3, n), rng.uniform(-0.01, 0.03, n)]
    )


def test_triangulation_exact_on_projected_points(cal):
    X = _points(200)
    Xt, cov, rep = triangulate(cal, cal.left.project(X), cal.right.project(X))
    assert np.max(np.abs(Xt - X)) < 1e-9
    assert np.max(rep) < 1e-6
    assert np.all(np.linalg.eigvalsh(cov) > 0)
    assert np.max(epipolar_distance(cal, cal.left.project(X), cal.right.project(X))) < 1e-6


def test_triangulation_noise_matches_propagated_covariance_and_noise_floor(cal):
    # Monte Carlo: image noise sigma -> scatter of Z agrees with the propagated covariance and
    # with the textbook floor Z^2/(f B) sqrt(2) sigma (within the geometry's factor ~1.2)
    rng = np.random.default_rng(3)
    X0 = np.array([[0.29, 0.16, 0.0]])
    X = np.repeat(X0, 4000, axis=0)
    sigma = 0.05
    ul = cal.left.project(X) + rng.normal(0, sigma, (len(X), 2))
    ur = cal.right.project(X) + rng.normal(0, sigma, (len(X), 2))
    Xt, cov, _ = triangulate(cal, ul, ur, sigma_px=sigma)
    scatter = np.std(Xt - X0, axis=0)
    predicted = np.sqrt(np.diag(cov[0]))
    assert np.allclose(scatter, predicted, rtol=0.08)
    floor = stereo_noise_floor(cal, X0[0], sigma)
    # in this rig the cameras look along -z of the mechanism: depth = out-of-plane
    assert 0.6 < scatter[2] / floor < 1.4


def test_nan_rows_and_shape_errors(cal):
    X = _points(3)
    ul, ur = cal.left.project(X), cal.right.project(X)
    ul[1] = np.nan
    Xt, cov, rep = triangulate(cal, ul, ur)
    assert np.isnan(Xt[1]).all() and np.isfinite(Xt[[0, 2]]).all()
    with pytest.raises(BadInputError, match="differ in shape"):
        triangulate(cal, ul, ur[:2])


def test_calibrated_rig_measures_distances(cal):
    # a calibrated rig (here: the exact one) measures a 0.1 m distance exactly
    X = np.array([[0.2, 0.1, 0.0], [0.3, 0.1, 0.0]])
    Xt, _, _ = triangulate(cal, cal.left.project(X), cal.right.project(X))
    assert np.linalg.norm(Xt[1] - Xt[0]) == pytest.approx(0.1, abs=1e-12)


def test_rigid_fit_recovers_transform():
    rng = np.random.default_rng(0)
    P = rng.normal(size=(50, 3))
    a = 0.7
    R = np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])
    t = np.array([0.1, -0.2, 0.3])
    Q = P @ R.T + t
    Rf, tf = fit_rigid(P, Q)
    assert np.allclose(Rf, R) and np.allclose(tf, t)
    assert rotation_angle_z(Rf) == pytest.approx(a)
    Q[:5] += 5.0  # outliers
    Rr, tr, inl, rms = fit_rigid_robust(P, Q)
    assert np.allclose(Rr, R, atol=1e-9) and not inl[:5].any() and inl[5:].all() and rms < 1e-9
    with pytest.raises(BadInputError, match="only 2 valid points"):
        fit_rigid_robust(P[:2], Q[:2])


def test_derivative_exact_for_polynomials_and_handles_gaps():
    t = np.arange(40) / 50.0
    t = np.delete(t, [17, 18])  # dropped frames
    x = 1 + 2 * t - 3 * t**2 + 0.5 * t**5
    v, gain = time_derivative(t, x, window=9, order=5)
    exact = 2 - 6 * t + 2.5 * t**4
    assert np.allclose(v[4:-4], exact[4:-4], atol=1e-8)
    # ends: symmetric shrinking windows (centred differences), NaN at the first/last sample
    assert np.isnan(v[[0, -1]]).all() and np.allclose(v[1:-1], exact[1:-1], atol=2e-3)
    assert np.all(gain[1:-1] > 0)
    # noise gain: Monte Carlo scatter of the derivative of white noise
    rng = np.random.default_rng(0)
    tt = np.arange(2000) / 50.0
    noise = rng.normal(0, 1e-5, (2000, 1))
    vn, g = time_derivative(tt, noise)
    assert np.std(vn[10:-10]) == pytest.approx(g[1000] * 1e-5, rel=0.1)
    with pytest.raises(BadInputError, match="odd"):
        time_derivative(tt, noise, window=8)
