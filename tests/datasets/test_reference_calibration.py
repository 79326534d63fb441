"""The reference study calibrated on the paper's 4e5 growth and validated at 1.2e6 (issue 35):
its calibration datum and spec (fast); the run end to end is in test_reference_study (slow)."""

from __future__ import annotations

import numpy as np
import pytest

from jointwear.datasets.reference_calibration import (
    PRIORS,
    _centred,
    _growth,
    _layers,
    _spec,
)
from jointwear.datasets.reference_study import REDUCED, reference_file


@pytest.fixture(scope="module")
def reported():
    from jointwear.params import read_toml
    from jointwear.reported import reported_dataset

    src = reference_file()
    return reported_dataset(_centred(read_toml(src)), src)


def test_the_datum_is_the_papers_growth_with_compares_u(reported):
    """28.32 µm = 33.34 - 5.02 µm; u as compare takes it for one reference: the two readings'
    u and the new bore's form C0/sqrt(3) (the paper's figures, independently written out)."""
    value, u = _growth(reported, "cylindricity_4e5")
    assert value == pytest.approx(28.32e-6, abs=1e-12)
    floor = np.sqrt(2 * ((0.03 / np.sqrt(3)) ** 2 + (0.01 / np.sqrt(12)) ** 2) + 5.02**2 / 3)
    assert u * 1e6 == pytest.approx(floor, rel=1e-6)
    later, _ = _growth(reported, "cylindricity_1_2e6")
    assert value / later == pytest.approx(28.32 / 41.55)  # the measured ratio, 0.68


def test_the_layers_are_the_papers_13_centred_on_the_bore(reported):
    z = np.array(_layers(reported.attrs))
    assert len(z) == 13 and z[0] == pytest.approx(-6e-3) and z[-1] == pytest.approx(6e-3)
    np.testing.assert_allclose(np.diff(z), 1e-3)
    assert float(reported.attrs["layers_z_centre_m"]) == 0.0  # the reading is stated


def test_the_spec_calibrates_kw_and_the_tilt_stiffness_on_the_4e5_growth(tmp_path, reported):
    from jointwear.sim import DEFAULT_KW
    from jointwear.sim.calibrate import read_calibration_spec

    path = tmp_path / "calibration.toml"
    path.write_text(_spec(reported, REDUCED, 0.05))
    spec = read_calibration_spec(path)
    assert spec.names == list(PRIORS) == ["wear.kw", "joint.tilt_stiffness"]
    assert spec.cycles == (4e5,) and spec.samples == REDUCED.training_runs
    assert spec.u_num_rel == 0.05
    (v,) = spec.values
    assert v.quantity == "cylindricity" and v.value == pytest.approx(28.32e-6, abs=1e-12)
    assert len(v.z) == 13  # computed on the measured layers, not the whole bore
    lo, hi = spec.parameters[0].bounds
    assert lo == pytest.approx(PRIORS["wear.kw"][0] * DEFAULT_KW)
    assert hi == pytest.approx(PRIORS["wear.kw"][1] * DEFAULT_KW)
