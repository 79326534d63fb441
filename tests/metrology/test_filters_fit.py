"""Filters (transmission), harmonic spectrum, outlier removal and exact least-squares fits."""

from __future__ import annotations

import numpy as np
import pytest

from jointwear.errors import BadInputError
from jointwear.metrology.filters import (
    filter_profile,
    harmonic_spectrum,
    remove_outliers,
    transmission,
)
from jointwear.metrology.fit import fit_circle, fit_circle_polar, fit_cylinder

N = 3600
TH = np.arange(N) * 2 * np.pi / N


def _amp(profile, k):
    return harmonic_spectrum(profile)[k]


@pytest.mark.parametrize("kc", [15, 50, 150, 500, 37.5])
def test_gaussian_transmission_is_half_at_cutoff(kc):
    assert abs(transmission(kc, kc)) == pytest.approx(0.5, rel=1e-12)
    k = int(kc) if float(kc).is_integer() else 37
    prof = 1e-6 * np.cos(k * TH + 0.3)
    expected = np.exp(-np.pi * (np.sqrt(np.log(2) / np.pi) * k / kc) ** 2)
    assert _amp(filter_profile(prof, kc), k) == pytest.approx(1e-6 * expected, rel=1e-9)


def test_gaussian_attenuates_harmonics_by_the_formula():
    kc = 50
    for k, h in [(25, 0.5**0.25), (100, 0.5**4), (5, 0.5 ** (1 / 100))]:
        prof = 2e-6 * np.sin(k * TH)
        assert _amp(filter_profile(prof, kc), k) == pytest.approx(2e-6 * h, rel=1e-9)


def test_2rc_high_pass_is_75_percent_at_cutoff():
    kc = 50
    prof = 1e-6 * np.cos(kc * TH)
    mean_line = filter_profile(prof, kc, kind="2rc")
    assert _amp(prof - mean_line, kc) == pytest.approx(0.75e-6, rel=1e-9)
    # far below the cut-off the high pass removes almost everything: |H_hp| = q^2/(1+q^2)
    q2 = 3 * (5 / kc) ** 2
    prof5 = 1e-6 * np.cos(5 * TH)
    assert _amp(prof5 - filter_profile(prof5, kc, kind="2rc"), 5) == pytest.approx(
        1e-6 * q2 / (1 + q2), rel=1e-9
    )


def test_filter_errors():
    with pytest.raises(BadInputError, match="cut-off must be > 0"):
        transmission(1, 0)
    with pytest.raises(BadInputError, match="filter 'box' is not known"):
        transmission(1, 50, "box")
    with pytest.raises(BadInputError, match="contains NaN"):
        filter_profile(np.array([1.0, np.nan, 1.0, 1.0]), 15)


def test_harmonic_spectrum_amplitudes():
    prof = 8e-3 + 3e-6 * np.cos(2 * TH + 1) + 0.5e-6 * np.sin(7 * TH)
    spec = harmonic_spectrum(prof, max_order=10)
    assert spec[0] == pytest.approx(8e-3)
    assert spec[2] == pytest.approx(3e-6, rel=1e-9)
    assert spec[7] == pytest.approx(0.5e-6, rel=1e-9)
    assert spec[3] < 1e-18 and spec.size == 11


def test_outlier_removal_reports_and_restores():
    rng = np.random.default_rng(0)
    clean = 2e-6 * np.cos(3 * TH) + 0.01e-6 * rng.standard_normal(N)
    dirty = clean.copy()
    spikes = [100, 1000, 2500]
    dirty[spikes] += [5e-6, -3e-6, 8e-6]
    out, removed = remove_outliers(dirty, threshold=6)
    assert set(np.flatnonzero(removed)) == set(spikes)
    np.testing.assert_allclose(out[spikes], clean[spikes], atol=0.05e-6)


def test_exact_circle_fit_symmetric_perturbation():
    # points on a circle (a, b, R) with a 3-lobe perturbation: it has no first harmonic, so the
    # exact LS circle is exactly (a, b, R) (stationary point of the geometric objective)
    a, b, R = 1.234e-3, -0.567e-3, 8e-3
    t = np.arange(360) * np.pi / 180
    rho = R + 2e-6 * np.cos(3 * t)
    fit = fit_circle(a + rho * np.cos(t), b + rho * np.sin(t))
    assert fit.x0 == pytest.approx(a, rel=1e-9)
    assert fit.y0 == pytest.approx(b, rel=1e-9)
    assert fit.radius == pytest.approx(R, rel=1e-9)
    assert fit.rms == pytest.approx(2e-6 / np.sqrt(2), rel=1e-6)


def test_exact_fit_differs_from_limacon_for_large_eccentricity():
    # a perfect circle seen from an axis 200 µm off-centre: the exact fit is exact, while the
    # limaçon leaves the e^2/(2R) peak-to-valley second harmonic
    e, R = 200e-6, 8e-3
    phi = np.arange(720) * np.pi / 360
    r = e * np.cos(phi) + np.sqrt(R**2 - (e * np.sin(phi)) ** 2)
    fit = fit_circle_polar(np.degrees(phi), r)
    assert fit.x0 == pytest.approx(e, rel=1e-9) and abs(fit.y0) < 1e-12
    assert np.nanmax(np.abs(fit.residual)) < 1e-12


def test_exact_cylinder_fit_tilted_axis():
    rng = np.random.default_rng(1)
    R, x0, y0, tx, ty = 8e-3, 30e-6, -20e-6, 0.01, -0.02
    zs = np.linspace(-6e-3, 6e-3, 7)
    t = np.arange(180) * 2 * np.pi / 180
    pts = []
    d = np.array([tx, ty, 1.0]) / np.sqrt(1 + tx**2 + ty**2)
    u = np.cross(d, [0, 1.0, 0])
    u /= np.linalg.norm(u)
    v = np.cross(d, u)
    for s in zs:
        rho = R + 1e-6 * np.cos(4 * t)
        c = np.array([x0, y0, 0.0]) + s * d
        pts.append(c + rho[:, None] * (np.cos(t)[:, None] * u + np.sin(t)[:, None] * v))
    p = np.concatenate(pts)
    p += 0 * rng.standard_normal(p.shape)
    fit = fit_cylinder(p[:, 0], p[:, 1], p[:, 2])
    zr = fit.z_ref
    assert fit.tx == pytest.approx(tx, rel=1e-9)
    assert fit.ty == pytest.approx(ty, rel=1e-9)
    assert fit.x0 == pytest.approx(x0 + tx * zr, abs=1e-12)
    assert fit.radius == pytest.approx(R, rel=1e-9)
