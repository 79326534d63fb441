"""The demo's calibrate -> validate step and its motion truth (issues 35 item 5, 36 item 6)."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from jointwear.reports import demo
from jointwear.reports.demo_calibration import (
    CALIBRATED,
    base_toml,
    spec_toml,
)
from jointwear.reports.demo_studies import ensemble_spec, main_wear_settings


def test_the_calibration_params_file_is_the_demos_rig_and_verified_scheme(tmp_path):
    """``calibrate_params.toml`` read as ``sim calibrate --params`` reads it gives the demo's
    rig and the wear settings its verification study verified (so its u_num applies)."""
    from jointwear.params import from_mapping, read_toml
    from jointwear.sim import WearSettings, load_parameters

    path = tmp_path / "p.toml"
    path.write_text(base_toml(demo.FULL))
    assert load_parameters(path) == demo._params(demo.FULL)
    wear = from_mapping(WearSettings, read_toml(path)["wear"], where="wear")
    assert wear == main_wear_settings(demo.FULL)


def test_the_spec_calibrates_kw_around_nominal_on_the_earlier_snapshot(tmp_path):
    from jointwear.sim import DEFAULT_KW
    from jointwear.sim.calibrate import read_calibration_spec

    data = tmp_path / "metrology_wear_calibration.nc"
    data.write_bytes(b"")
    path = tmp_path / "calibrate.toml"
    path.write_text(spec_toml(data, demo.FULL, demo._params(demo.FULL)))
    spec = read_calibration_spec(path)
    assert spec.names == list(CALIBRATED) == ["wear.kw"]
    assert spec.cycles == (demo.FULL.calibration_cycles,) and spec.data == (data,)
    assert spec.samples == demo.FULL.training_runs
    lo, hi = spec.parameters[0].bounds
    assert lo == pytest.approx(0.5 * DEFAULT_KW) and hi == pytest.approx(1.5 * DEFAULT_KW)
    # the earlier snapshot is another, earlier scan of the same bore; the validation is later
    assert 0 < demo.FULL.calibration_cycles < demo.FULL.cycles


def test_the_input_ensemble_leaves_the_calibrated_inputs_to_the_posterior():
    """Two ensembles varying kw would be refused by compare (an input counted twice)."""
    full = ensemble_spec(demo._params(demo.FULL), demo.FULL)["parameters"]
    rest = ensemble_spec(demo._params(demo.FULL), demo.FULL, calibrated=tuple(CALIBRATED))
    assert "wear.kw" in full and set(full) - set(rest["parameters"]) == set(CALIBRATED)
    assert demo._calibrated(demo.FULL) == tuple(CALIBRATED)
    assert demo._calibrated(demo.QUICK) == ()  # --quick does not calibrate


def test_the_motion_truth_is_not_the_simulated_linkage():
    """The rig's crank runs MOTION_SPEED_FACTOR faster than the simulated crank: a straight
    crank angle at 120 rpm gives the rig 120.6 rpm, within a drive's 1 % tolerance."""
    t = np.linspace(0.0, 0.75, 400)
    phi = 30.0 + 2 * np.pi * 2.0 * t  # 120 rpm
    motion = xr.Dataset({"crank_angle": ("time", np.angle(np.exp(1j * phi)))}, {"time": t})
    rpm = demo.rig_speed_rpm(motion)
    assert rpm == pytest.approx(120.0 * demo.MOTION_SPEED_FACTOR, rel=1e-9)
    assert rpm != pytest.approx(120.0, rel=1e-3) and abs(rpm / 120.0 - 1) <= 0.01
    # the report says what the footage is: the rig's kinematics at another speed
    assert "faster than the simulated one" in demo.SYNTHETIC_NOTE


def test_the_report_says_what_the_known_truths_give():
    """The notes after the comparison: the resolution the calibrated comparison reached, and
    what the motion criteria decided about the rig's faster crank (states and resolutions as
    the comparison gave them; no motion rows, no motion note)."""
    import types

    import pandas as pd

    rows = pd.DataFrame(
        {
            "key": ["max_wear_depth", "wear_field", "follower_velocity_x_rms", "wear_depth"],
            "quantity": ["max depth", "wear field", "x RMS", "shape"],
            "state": ["pass", "fail", "pass", "not_assessed"],
            "resolution": ["detects errors outside −12 %…+13 %", "D² > 73", "−2 %…+2 %", ""],
        }
    )
    result = types.SimpleNamespace(decisions=rows)
    parts = demo._Parts(calibration=object())
    wear, motion = demo._outcome_notes(result, parts)
    assert "max depth PASS, detects errors outside −12 %…+13 %" in wear
    assert "wear field FAIL" in wear and "6-degree turn" in wear
    assert "0.5% faster" in motion and "x RMS PASS (−2 %…+2 %)" in motion
    assert "shape" not in motion  # an undecided row is not reported as a decision
    uncalibrated = demo._outcome_notes(result, demo._Parts())
    assert len(uncalibrated) == 1 and "Motion truth" in uncalibrated[0]
    no_motion = types.SimpleNamespace(decisions=rows[~rows.key.str.startswith("follower")])
    assert not any("Motion" in n for n in demo._outcome_notes(no_motion, demo._Parts()))
