"""The instrument-file generator: its truth is what it claims to be."""

from __future__ import annotations

import numpy as np
import pytest

from jointwear.conventions import CANONICAL, AngleConvention
from jointwear.datasets.instruments import default_wear, generate, write
from jointwear.errors import BadInputError
from jointwear.metrology.form import cylinder_zone


def test_setup_is_recovered_by_the_limacon_fit():
    sc = generate(
        n_layers=5,
        n_points=720,
        noise=0.0,
        quantisation=0.0,
        wear=None,
        harmonics={},
        eccentricity=(12e-6, -5e-6),
        tilt=(2e-3, 1e-3),
        convention=("+x", "counterclockwise"),
    )
    # instrument frame = +x counter-clockwise = the frame of the fit: centre/tilt come back
    z = sc.heights - sc.heights.mean()
    res = cylinder_zone(
        np.broadcast_to(z[:, None], sc.radius.shape),
        np.broadcast_to(sc.theta_deg, sc.radius.shape),
        sc.radius,
        reference="LS",
    )
    assert res.centre[0] == pytest.approx(12e-6, abs=1e-10)
    assert res.centre[1] == pytest.approx(-5e-6, abs=1e-10)
    assert res.tilt[0] == pytest.approx(2e-3, abs=1e-7)
    # a perfect cylinder: only the exact set-up's second harmonic e^2/(4R) remains
    e_max = np.hypot(12e-6 + 2e-3 * z.max(), -5e-6 + 1e-3 * z.max())
    assert res.total < e_max**2 / (2 * 8e-3) * 1.01


def test_noise_quantisation_and_wear_truth():
    sc = generate(n_layers=3, n_points=2000, noise=0.1e-6, quantisation=0.05e-6, seed=4)
    t = sc.truth
    steps = (t["radius"].values - sc.nominal_radius) / 0.05e-6
    np.testing.assert_allclose(steps, np.round(steps), atol=1e-6)
    resid = t["radius"].values - t["radius_true"].values
    assert np.std(resid) == pytest.approx(np.sqrt(0.1e-6**2 + 0.05e-6**2 / 12), rel=0.05)
    w = default_wear(t["theta"].values[None, :], t["z"].values[:, None], width_mm=2.0)
    np.testing.assert_allclose(t["wear_depth"].values, w, atol=1e-15)
    # the main lobe sits near canonical 90 degree at the first layer
    assert abs(t["theta"].values[np.argmax(t["wear_depth"].values[0])] - 90.0) < 1.0
    assert t["theta"].attrs["angle_zero"] == CANONICAL.zero


def test_instrument_convention_maps_to_canonical():
    conv = AngleConvention("-y", "clockwise")
    sc = generate(
        n_layers=1,
        n_points=360,
        convention=conv,
        noise=0,
        quantisation=0,
        harmonics={},
        eccentricity=(0, 0),
        tilt=(0, 0),
    )
    # the wear peak (canonical 90) must appear at the instrument angle that points there
    k = np.argmax(sc.radius[0])
    assert CANONICAL.from_physical(conv.to_physical(sc.theta_deg[k])) == pytest.approx(
        90.0, abs=1.0
    )


def test_write_rejects_bad_options(tmp_path):
    sc = generate(n_layers=2, n_points=36)
    with pytest.raises(BadInputError, match="layout 'zip' not supported"):
        write(sc, tmp_path / "x", layout="zip")
    with pytest.raises(BadInputError, match="decimal separator and delimiter must differ"):
        write(sc, tmp_path / "x", delimiter=",", decimal=",")
    with pytest.raises(BadInputError, match="wide layout"):
        write(sc, tmp_path / "x.txt", layout="wide", angle="xy")
