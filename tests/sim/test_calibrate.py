"""Bayesian calibration (jointwear.sim.calibrate): closed forms, known emulator errors, refusals."""

from __future__ import annotations

import numpy as np
import pytest

from jointwear import io
from jointwear.errors import BadInputError, ParameterError
from jointwear.sim.calibrate import CalibrationRefused, calibrate, read_calibration_spec
from jointwear.sim.calibrate._emulator import fit_emulator
from jointwear.sim.calibrate._sampler import sample, split_rhat

# prior x ~ N(m0, diag s0^2), one datum y = a . x + e, e ~ N(0, u^2): a Gaussian posterior
M0, S0, A, Y, U = np.array([1.0, 2.0]), np.array([0.5, 1.0]), np.array([1.0, 2.0]), 5.5, 0.2


def closed_form() -> tuple[np.ndarray, np.ndarray, float]:
    """Posterior mean, sd and correlation of the linear-Gaussian model (Bayes' rule)."""
    a = A[None, :]
    cov = np.linalg.inv(np.diag(1 / S0**2) + a.T @ a / U**2)
    mean = cov @ (M0 / S0**2 + a.T[:, 0] * Y / U**2)
    sd = np.sqrt(np.diag(cov))
    return mean, sd, cov[0, 1] / (sd[0] * sd[1])


def linear_spec(**calibrate_keys) -> dict:
    keys = {
        "run": "function",
        "function": "linear",
        "function_args": {"a": A.tolist()},
        "samples": 16,
        "seed": 3,
        "walkers": 32,
        "values": [{"quantity": "y", "value": Y, "u": U, "source": "closed-form test"}],
    }
    keys.update(calibrate_keys)
    return {
        "calibrate": keys,
        "parameters": {
            "x1": {"distribution": "normal", "mean": M0[0], "std": S0[0]},
            "x2": {"distribution": "normal", "mean": M0[1], "std": S0[1]},
        },
    }


def test_sampler_recovers_a_gaussian_posterior_to_one_percent():
    mean, sd, _ = closed_form()
    cov = np.diag(sd**2)

    def log_prob(x):
        return -0.5 * np.sum((x - mean) ** 2 / np.diag(cov), axis=1)

    start = mean + sd * np.random.default_rng(0).standard_normal((256, 2))
    chain = sample(log_prob, start, max_steps=20000, seed=2)
    assert chain.long_enough and np.all(chain.rhat < 1.01)
    assert 0.3 < chain.acceptance < 0.9  # the stretch move's usual range in 2-D
    assert np.all(np.abs(chain.samples.mean(0) - mean) < 0.01 * sd)
    assert np.all(np.abs(chain.samples.std(0) / sd - 1) < 0.01)
    assert np.all(chain.ess > 10000)


def test_split_rhat_flags_chains_that_disagree():
    rng = np.random.default_rng(1)
    same = rng.standard_normal((8, 2000, 1))
    assert abs(split_rhat(same)[0] - 1) < 0.01
    shifted = same + np.arange(8)[:, None, None] * 0.5  # each chain around its own mean
    assert split_rhat(shifted)[0] > 1.5
    drifting = same + np.linspace(0, 3, 2000)[None, :, None]  # halves disagree within a chain
    assert split_rhat(drifting)[0] > 1.1


@pytest.mark.slow  # about 10 CPU s
def test_calibration_of_the_linear_model_matches_the_closed_form(tmp_path):
    mean, sd, rho = closed_form()
    ds = calibrate(linear_spec(walkers=256), out=tmp_path / "post.nc", workers=0)
    got_mean = ds["posterior_mean"].values
    got_sd = ds["posterior_sd"].values
    assert np.all(np.abs(got_mean - mean) < 0.01 * np.abs(mean))
    assert np.all(np.abs(got_sd / sd - 1) < 0.01)
    assert abs(float(ds["correlation"].values[0, 1]) - rho) < 0.01
    # identifiability: x1 barely moves from its prior, x2 is pinned; they trade off
    assert ds["informed"].values.tolist() == [0, 1]
    assert "x1: posterior" in ds.attrs["identifiability"]
    assert "NOT informed" in ds.attrs["identifiability"].splitlines()[0]
    assert "x1 and x2 trade off" in ds.attrs["identifiability"]
    assert ds.sizes["sample"] > 1000 and "x1" in ds and ds["x1"].dims == ("sample",)
    # the file as written
    back = io.load(tmp_path / "post.nc")
    assert back.attrs["jointwear_file"] == "posterior"
    prov = io.parse_provenance(back)
    assert prov["parameters"]["calibration"]["values"][0]["source"] == "closed-form test"
    assert 0.05 < float(back["ppc_p_below"][0]) < 0.95
    # jointwear info says which parameter the data do not inform
    from jointwear.summary import summarise

    info = summarise(tmp_path / "post.nc")
    assert "x1: posterior" in info and "NOT informed by the data" in info


def test_emulator_error_is_what_was_planted():
    rng = np.random.default_rng(5)
    x = rng.random((40, 1))
    truth = 1.0 + 2.0 * x[:, 0] + 0.5 * np.sin(3 * x[:, 0])
    # a smooth function without noise: the emulated mean is nearly exact
    exact = fit_emulator(x, truth[:, None], seed=1)
    assert exact.cv_error[0] < 1e-3 and exact.error[0] < 1e-3
    # planted scatter of known sd: the white term finds it, the mean's error stays small
    eps = 0.02 * rng.standard_normal(40)
    sigma = float(np.std(eps))  # the scatter planted (as drawn)
    noisy = fit_emulator(x, (truth * np.exp(eps))[:, None], seed=1)
    assert noisy.log[0]  # positive: emulated in the logarithm, errors relative
    assert 0.7 * sigma < noisy.scatter[0] < 1.3 * sigma
    assert 0.8 * sigma < noisy.cv_error[0] < 1.4 * sigma
    assert noisy.error[0] < 0.6 * sigma
    # an emulator with too few runs for a wiggly function: its error is large, and said so
    wiggly = fit_emulator(x[:6], np.sin(20 * x[:6, 0])[:, None], seed=1)
    assert wiggly.cv_error[0] > 0.3


def test_refuses_an_emulator_error_above_the_stated_fraction(tmp_path):
    # the function's own noise (known: sd 0.5 on y) against a datum with u = 0.05
    spec = linear_spec(function_args={"a": A.tolist(), "noise": 0.5})
    spec["calibrate"]["values"][0]["u"] = 0.05
    spec["calibrate"]["samples"] = 6
    with pytest.raises(CalibrationRefused, match="emulator's cross-validated error of y") as e:
        calibrate(spec, out=tmp_path / "post.nc", workers=0)
    assert "emulator_max_fraction = 0.5" in str(e.value) and "raise [calibrate] samples" in str(
        e.value
    )
    assert not (tmp_path / "post.nc").exists()


@pytest.mark.slow  # a few chains of up to 12800 steps
def test_refuses_an_unconverged_chain_and_its_fix_works(tmp_path):
    spec = linear_spec(max_steps=200, walkers=32)
    with pytest.raises(CalibrationRefused, match="did not converge") as e:
        calibrate(spec, out=tmp_path / "post.nc", workers=0)
    assert "split-R-hat" in str(e.value) and "autocorrelation time" in str(e.value)
    for _ in range(3):  # the fix as printed: it works, or refuses again with a longer chain
        msg = str(e.value)
        spec["calibrate"]["max_steps"] = int(msg.split("max_steps to about ")[1].split()[0])
        try:
            ds = calibrate(spec, out=tmp_path / "post.nc", workers=0, resume=True)
            break
        except CalibrationRefused as again:
            assert "did not converge" in str(again)
            e = pytest.ExceptionInfo.from_exception(again)
    else:
        pytest.fail(f"the printed fix never converged: {e.value}")
    assert float(ds["split_rhat"].max()) <= 1.01


def test_refuses_data_the_model_cannot_fit_naming_the_quantity(tmp_path):
    # y2 = 2 y by construction: y = 5.5 and y2 = 20 (y = 10) cannot both hold
    spec = linear_spec()
    spec["calibrate"]["values"] = [
        {"quantity": "y", "value": 5.5, "u": 0.1},
        {"quantity": "y2", "value": 20.0, "u": 0.1},
    ]
    with pytest.raises(CalibrationRefused, match=r"posterior predictive check failed for y"):
        calibrate(spec, out=tmp_path / "post.nc", workers=0)


def test_refuses_a_posterior_cut_by_the_emulator_range(tmp_path):
    # the datum lies far beyond what the prior's range can give: the posterior piles at the edge
    spec = linear_spec(max_steps=1000)
    spec["calibrate"]["values"][0].update(value=40.0, u=0.5)
    with pytest.raises(CalibrationRefused, match="edge of the emulator's training range"):
        calibrate(spec, out=tmp_path / "post.nc", workers=0)


def test_spec_errors_name_the_key(tmp_path):
    base = linear_spec()
    bad = {**base, "calibrate": {**base["calibrate"], "sample": 3}}
    with pytest.raises(ParameterError, match=r"unknown key\(s\) sample \(did you mean samples\?\)"):
        read_calibration_spec(bad)
    grid = {**base, "parameters": {"x1": {"values": [0.0, 1.0]}}}
    with pytest.raises(ParameterError, match="needs a prior"):
        read_calibration_spec(grid)
    nodata = {**base, "calibrate": {k: v for k, v in base["calibrate"].items() if k != "values"}}
    with pytest.raises(ParameterError, match="has no data"):
        read_calibration_spec(nodata)
    wear = {"calibrate": {"values": base["calibrate"]["values"]}, "parameters": {}}
    with pytest.raises(ParameterError, match="calibrates no parameter"):
        read_calibration_spec(wear)
    missing = {
        "calibrate": {"data": ["nothing.nc"], "cycles": 100},
        "parameters": {"wear.kw": {"distribution": "uniform", "bounds": [1e-16, 2e-16]}},
    }
    with pytest.raises(ParameterError, match="no file nothing.nc"):
        read_calibration_spec(missing)
    assert issubclass(CalibrationRefused, BadInputError)


def test_cli_defaults_are_the_librarys():
    import inspect

    from jointwear.sim.calibrate import calibrate as lib_calibrate
    from jointwear.sim.calibrate import predict
    from jointwear.sim.cli_calibrate import calibrate_cmd, predict_cmd

    cli, lib = inspect.signature(predict_cmd).parameters, inspect.signature(predict).parameters
    for name in ("samples", "workers", "scheduler", "resume"):
        assert cli[name].default == lib[name].default, name
    cli, lib = (
        inspect.signature(calibrate_cmd).parameters,
        inspect.signature(lib_calibrate).parameters,
    )
    for name in ("params", "workers", "scheduler", "resume"):
        assert cli[name].default == lib[name].default, name


def test_a_wear_calibration_without_u_num_is_refused_before_any_run(tmp_path):
    import xarray as xr

    from jointwear.conventions import theta_coord, z_coord

    theta = np.arange(0.0, 360.0, 30.0)
    depth = np.outer([1.0, 2.0, 1.0], 1 + np.cos(np.radians(theta))) * 1e-6
    m = xr.Dataset(
        {
            "wear_depth": (("z", "theta"), depth, {"units": "m", "long_name": "wear depth"}),
            "wear_depth_u": (("z", "theta"), depth * 0 + 1e-8, {"units": "m", "long_name": "u"}),
        },
        coords={"z": z_coord([-2e-3, 0.0, 2e-3]), "theta": theta_coord(theta)},
        attrs={"data_origin": "synthetic"},
    )
    io.save(m, tmp_path / "map.nc")
    spec = {
        "calibrate": {"data": [str(tmp_path / "map.nc")], "cycles": 1000},
        "parameters": {"wear.kw": {"distribution": "uniform", "bounds": [4.5e-16, 1.35e-15]}},
    }
    with pytest.raises(CalibrationRefused, match=r"u_num of max_wear_depth of map.nc .* not known"):
        calibrate(spec, out=tmp_path / "post.nc", workers=0)
    assert not list(tmp_path.glob("post*"))  # refused before the training runs
