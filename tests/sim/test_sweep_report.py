"""Sweeps report what their runs know: accuracy, uncertainty, warnings, sample size, angles.

Truths: Sobol confidence half-widths shrink as 1/sqrt(N), so the recommended N follows from the
file's own half-widths; the circular mean and spread of an angle uniform on an arc crossing
0/360 in closed form; each wear run's own accuracy as its wear map states it.
"""

from __future__ import annotations

import json
import logging
import math

import numpy as np
import pytest
from _rigs import NOISE_LIMITED_TOML

from jointwear import io
from jointwear.cli import main
from jointwear.sim import run_sweep


def spec(method, samples, function="linear", params=None, outputs=None, **args):
    u = {"distribution": "uniform", "bounds": [0.0, 1.0]}
    sweep = {"run": "function", "function": function, "method": method, "samples": samples}
    sweep["seed"] = 5
    if args:
        sweep["function_args"] = args
    if outputs:
        sweep["outputs"] = outputs
    return {"sweep": sweep, "parameters": params or {"x1": u, "x2": u, "x3": u}}


def test_sobol_with_n8_warns_and_names_the_n_that_would_do(caplog):
    with caplog.at_level(logging.WARNING, logger="jointwear.sim.sweep"):
        ds = run_sweep(spec("sobol", 8, function="ishigami"), workers=0)
    conf = max(float(ds["sobol_S1_conf"].max()), float(ds["sobol_ST_conf"].max()))
    assert conf > 0.1  # N = 8 is too small: the check has something to find
    want = 2 ** math.ceil(math.log2(8 * (conf / 0.1) ** 2))
    assert ds.attrs["sensitivity_recommended_samples"] == want
    assert f"use samples = {want}" in ds.attrs["sensitivity_sample_warning"]
    assert any(f"use samples = {want}" in r.getMessage() for r in caplog.records)


def test_large_enough_sobol_sample_does_not_warn(caplog):
    with caplog.at_level(logging.WARNING, logger="jointwear.sim.sweep"):
        ds = run_sweep(spec("sobol", 1024), workers=0)
    assert float(ds["sobol_S1_conf"].max()) < 0.1
    assert "sensitivity_sample_warning" not in ds.attrs
    assert ds.attrs["sensitivity_recommended_samples"] == 1024
    assert not caplog.records


def test_morris_with_few_trajectories_warns():
    u = {"distribution": "uniform", "bounds": [0.0, 1.0]}
    ds = run_sweep(
        spec("morris", 4, function="ishigami", params={"x1": u, "x2": u, "x3": u}), workers=0
    )
    ratio = float(ds["y_morris_mu_star_conf"].max() / ds["y_morris_mu_star"].max())
    assert ratio > 0.1
    assert ds.attrs["sensitivity_recommended_samples"] == math.ceil(4 * (ratio / 0.1) ** 2)
    assert "use samples" in ds.attrs["sensitivity_sample_warning"]


def test_angle_outputs_are_circular():
    u = {"distribution": "uniform", "bounds": [0.0, 1.0]}
    ds = run_sweep(spec("lhs", 64, function="angle", params={"x1": u}), workers=0)
    theta = ds["theta"]
    # uniform on the arc 350..370 degrees: circular mean 0 (= 360), circular std
    # sqrt(-2 ln R) with R = sin(h)/h, h the half-width (10 degrees)
    h = math.radians(10.0)
    std = math.degrees(math.sqrt(-2 * math.log(math.sin(h) / h)))
    mean = theta.attrs["circular_mean_deg"]
    assert min(mean, 360.0 - mean) < 0.5
    assert theta.attrs["circular_std_deg"] == pytest.approx(std, rel=0.05)
    assert abs(float(theta.mean()) - 180.0) < 60  # the arithmetic mean is meaningless here
    with pytest.raises(AssertionError):
        np.testing.assert_allclose(float(theta.mean()), 0.0, atol=5)


def test_sobol_of_an_angle_is_refused_and_its_linear_twin_assessed():
    u = {"distribution": "uniform", "bounds": [0.0, 1.0]}
    ds = run_sweep(spec("sobol", 64, function="angle", params={"x1": u}), workers=0)
    assert np.isnan(float(ds["sobol_S1"].sel(output="theta", parameter="x1")))
    assert "angle" in json.loads(ds.attrs["sensitivity_not_assessed"])["theta"]
    assert float(ds["sobol_S1"].sel(output="theta_linear", parameter="x1")) == pytest.approx(
        1.0, abs=0.1
    )


@pytest.mark.slow
def test_wear_sweep_record_holds_each_runs_accuracy_and_one_line_per_warning(tmp_path, capsys):
    base = tmp_path / "base.toml"
    base.write_text(NOISE_LIMITED_TOML + "max_average_cycles = 2\n")
    sweep = tmp_path / "s.toml"
    sweep.write_text(
        '[sweep]\nrun = "wear"\ncycles = 2000\nmethod = "lhs"\nsamples = 2\nseed = 1\n'
        'outputs = ["max_wear_depth", "worn_volume", "cylindricity", "max_wear_theta"]\n'
        '[parameters."friction.dynamic_coefficient"]\ndistribution = "uniform"\n'
        "bounds = [0.08, 0.12]\n"
    )
    out = tmp_path / "s.nc"
    code = main(
        ["sim", "sweep", str(sweep), "--out", str(out), "--params", str(base), "--workers", "0"]
    )
    assert code == 0
    ds = io.load(out)
    assert set(ds["accuracy_status"].values) <= {"reached", "not reached"}
    u = ds["max_wear_depth_u"]
    assert u.attrs["coverage_factor"] == 1 and np.all(u.values > 0)
    assert np.all(u.values < 0.5 * ds["max_wear_depth"].values)
    assert np.all(np.isnan(ds["cylindricity_u"].values))  # not assessed, never 0
    assert "not assessed" in ds["cylindricity_u"].attrs["comment"]
    warned = [json.loads(w) for w in ds["run_warnings"].values if w]
    kinds = {item.split(":")[0] for w in warned for item in w}
    assert "accuracy_warning" in kinds  # 2 cycles averaged at most, tol 0.05: noise-limited
    err = capsys.readouterr().err
    for kind in kinds:
        assert err.count(f"warning: {kind} in ") == 1, err
    assert "the cycle-to-cycle variability" not in err.split("e.g.:")[0]
