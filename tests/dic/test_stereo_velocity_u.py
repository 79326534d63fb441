"""Velocity uncertainty parts: the differentiator's truncation error and the position noise,
against closed forms."""

from __future__ import annotations

import numpy as np

from jointwear.dic.footage._rigid import derivative_truncation, position_noise, time_derivative


def test_truncation_estimate_covers_the_true_truncation_error():
    # a crank-like signal at 50 samples/s: harmonics 2 and 6 Hz (the four-bar's content)
    t = np.arange(120) / 50.0
    w1, w2 = 2 * np.pi * 2, 2 * np.pi * 6
    x = 0.1 * np.sin(w1 * t) + 0.01 * np.cos(w2 * t)
    v_true = 0.1 * w1 * np.cos(w1 * t) - 0.01 * w2 * np.sin(w2 * t)
    v, _ = time_derivative(t, x)
    est = derivative_truncation(t, x)
    ok = np.isfinite(v)
    err = np.abs(v - v_true)[ok]
    assert np.mean(err <= 2 * est[ok]) >= 0.9
    assert np.sqrt(np.mean(est[ok] ** 2)) <= 5 * np.sqrt(np.mean(err**2))
    # the ends, where the window shrinks, carry the largest errors and estimates
    assert est[1] > 5 * np.median(est[ok])
    # a polynomial of the filter's degree is differentiated exactly inside the record (no
    # truncation estimated); at the ends, where the degree drops, the estimate is the error
    p = 3 * t**5 - t**3 + 2 * t
    vp, _ = time_derivative(t, p)
    true = np.abs(vp - (15 * t**4 - 3 * t**2 + 2))
    est = derivative_truncation(t, p)
    inner = slice(6, -6)  # beyond the end windows and the estimate's 3-sample maximum
    assert np.nanmax(est[inner]) < 1e-6 * np.nanmax(np.abs(vp))
    assert true[-2] > 1e-3 and 0.9 * true[-2] <= est[-2] <= 3 * true[-2]


def test_position_noise_recovers_white_noise_on_slow_motion():
    rng = np.random.default_rng(4)
    t = np.arange(400) / 50.0
    x = np.column_stack([1e-3 * np.sin(0.5 * t), 2e-3 * t]) + rng.normal(0, [2e-6, 5e-6], (400, 2))
    np.testing.assert_allclose(position_noise(t, x), [2e-6, 5e-6], rtol=0.15)
    # with gaps (dropped frames) the actual times are used
    keep = np.ones(400, bool)
    keep[[50, 51, 200]] = False
    np.testing.assert_allclose(position_noise(t[keep], x[keep]), [2e-6, 5e-6], rtol=0.15)
