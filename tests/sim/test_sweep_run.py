"""Sweeps executed in this process: outputs, failures, part files, resume, SALib indices, CLI."""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest

from jointwear import io
from jointwear.cli import main
from jointwear.errors import BadInputError
from jointwear.sim import analytic_sobol, run_sweep, to_grid
from jointwear.sim.sweep import _driver as sweep_mod
from jointwear.sim.sweep._store import parts_dir

PI = math.pi


def function_spec(method="lhs", samples=8, function="linear", args=None, params=None, **sw):
    params = params or {
        "x1": {"distribution": "uniform", "bounds": [0.0, 1.0]},
        "x2": {"distribution": "uniform", "bounds": [0.0, 1.0]},
    }
    sweep = {"run": "function", "function": function, "method": method, **sw}
    if method != "grid":
        sweep["samples"] = samples
    if args:
        sweep["function_args"] = args
    return {"sweep": sweep, "parameters": params}


def test_ishigami_sobol_indices_match_the_analytic_values_within_salib_intervals():
    u = {"distribution": "uniform", "bounds": [-PI, PI]}
    ds = run_sweep(
        function_spec(
            "sobol", samples=1024, function="ishigami", params={"x1": u, "x2": u, "x3": u}, seed=2
        ),
        workers=0,
    )
    assert ds.sizes["run"] == 1024 * 5  # Saltelli: N (D + 2)
    truth = analytic_sobol("ishigami")
    for k in ("S1", "ST"):
        est = ds[f"sobol_{k}"].sel(output="y")
        conf = ds[f"sobol_{k}_conf"].sel(output="y")
        for name in ("x1", "x2", "x3"):
            err = abs(float(est.sel(parameter=name)) - truth[k][name])
            assert err <= float(conf.sel(parameter=name)), (k, name, err)
    # and the intervals are informative, not so wide that anything would pass
    assert float(ds.sobol_S1_conf.max()) < 0.1
    assert float(ds.sobol_ST.sel(output="y", parameter="x3")) > 0.15  # interaction x1 x3
    assert float(ds.sobol_S1.sel(output="y", parameter="x3")) < 0.05
    assert ds.attrs["probabilistic_sample"] is True and ds.attrs["ensemble_complete"] is True


def test_morris_ranks_a_linear_model_by_its_coefficients():
    params = {f"x{i}": {"distribution": "uniform", "bounds": [0.0, 1.0]} for i in (1, 2, 3, 4)}
    ds = run_sweep(function_spec("morris", samples=20, params=params, seed=1), workers=0)
    mu = ds["y_morris_mu_star"]
    # elementary effects of y = x1 + 2 x2 + 3 x3 + 4 x4 per unit range are exactly a_i
    assert np.allclose(mu.values, [1, 2, 3, 4])
    assert np.allclose(ds["y_morris_sigma"].values, 0, atol=1e-12)  # no interactions
    assert np.allclose(ds["y2_morris_mu_star"].values, [2, 4, 6, 8])
    assert ds["y_morris_mu_star"].attrs["units"] == "1"
    assert ds.attrs["probabilistic_sample"] is False


def test_failed_runs_are_recorded_and_do_not_stop_the_sweep(tmp_path):
    out = tmp_path / "s.nc"
    ds = run_sweep(function_spec(samples=20, args={"fail_above": {"x1": 0.75}}), out=out, workers=0)
    x1 = ds["x1"].values
    failed = ds["status"].values == 1
    assert np.array_equal(failed, x1 > 0.75) and failed.any() and (~failed).any()
    assert np.all(np.isnan(ds["y"].values[failed]))
    assert all("exceeds fail_above" in e for e in ds["error"].values[failed])
    assert np.allclose(ds["y"].values[~failed], x1[~failed] + 2 * ds["x2"].values[~failed])
    back = io.load(out)
    assert back.attrs["n_failed"] == int(failed.sum())
    assert back.attrs["ensemble_complete"] is False and back.attrs["probabilistic_sample"] is True
    assert back["status"].attrs["flag_meanings"] == "ok failed not_run"
    assert back["x1"].attrs["units"] == "1"
    assert json.loads(back.attrs["provenance"])["parameters"]["spec"]["method"] == "lhs"
    assert not parts_dir(out).exists()  # the result file holds everything now


def test_sobol_with_failed_runs_is_not_assessed_rather_than_biased():
    u = {"distribution": "uniform", "bounds": [0.0, 1.0]}
    ds = run_sweep(
        function_spec(
            "sobol", samples=16, params={"x1": u, "x2": u}, args={"fail_above": {"x1": 0.9}}
        ),
        workers=0,
    )
    assert np.all(np.isnan(ds["sobol_S1"].values))
    assert "y" in json.loads(ds.attrs["sensitivity_not_assessed"])


def test_resume_computes_only_the_missing_runs(tmp_path, monkeypatch):
    out = tmp_path / "s.nc"
    spec = function_spec(samples=12, args={"noise": 0.5})
    full = run_sweep(spec, workers=0)

    # an interrupted sweep: the executor dies after 5 runs (their parts are on disk)
    real = sweep_mod.execute_runs

    def dying(tasks, **kw):
        calls = []

        def on_result(res):
            kw_on(res)
            calls.append(res.index)
            if len(calls) == 5:
                raise KeyboardInterrupt

        kw_on = kw["on_result"]
        real(tasks, **{**kw, "on_result": on_result})

    monkeypatch.setattr(sweep_mod, "execute_runs", dying)
    with pytest.raises(KeyboardInterrupt):
        run_sweep(spec, out=out, workers=0)
    assert not out.exists()
    assert len(list(parts_dir(out).glob("run-*.npz"))) == 5

    given = []

    def counting(tasks, **kw):
        given.extend(t.index for t in tasks)
        real(tasks, **kw)

    monkeypatch.setattr(sweep_mod, "execute_runs", counting)
    with pytest.raises(BadInputError, match="holds 5 finished run.*--resume"):
        run_sweep(spec, out=out, workers=0)
    other = function_spec(samples=12, args={"noise": 0.6})
    with pytest.raises(BadInputError, match="another spec.*noise"):
        run_sweep(other, out=out, workers=0, resume=True)
    ds = run_sweep(spec, out=out, workers=0, resume=True)
    assert sorted(given) == list(range(5, 12))
    assert ds.attrs["runs_resumed"] == 5 and ds.attrs["runs_computed_now"] == 7
    # same numbers as the uninterrupted sweep (each run's noise comes from its own seed)
    assert np.array_equal(ds["y"].values, full["y"].values)
    assert np.array_equal(io.load(out)["y"].values, full["y"].values)
    given.clear()  # resuming a finished sweep computes nothing and returns it
    again = run_sweep(spec, out=out, workers=0, resume=True)
    assert given == [] and again.attrs["runs_computed_now"] == 0
    assert np.array_equal(again["y"].values, full["y"].values)


def test_grid_sweep_reshapes_to_parameter_axes():
    ds = run_sweep(
        function_spec(
            "grid",
            params={"x1": {"values": [0.0, 1.0, 2.0]}, "x3": {"values": [10.0, 20.0]}},
        ),
        workers=0,
    )
    g = to_grid(ds)
    assert g["y"].dims == ("x1", "x3")
    expected = np.add.outer([0.0, 1.0, 2.0], 3 * np.array([10.0, 20.0]))
    assert np.array_equal(g["y"].values, expected)
    with pytest.raises(BadInputError, match="only a method"):
        to_grid(run_sweep(function_spec(samples=4), workers=0))


def tiny_base(tmp_path):
    base = tmp_path / "base.toml"
    base.write_text(
        "[joint]\nn_layers = 4\nn_points = 24\n"
        '[wear]\nscheme = "fixed"\ndn = 100\nsettle_cycles = 0.25\ninitial_settle_cycles = 0.5\n'
    )
    return base


def test_wear_sweep_equals_direct_simulations_with_the_overridden_parameters(tmp_path):
    from jointwear.params import from_mapping, read_toml
    from jointwear.sim import WearSettings, load_parameters, simulate_wear

    base = tiny_base(tmp_path)
    spec = {
        "sweep": {
            "run": "wear",
            "method": "grid",
            "cycles": 200,
            "outputs": ["max_wear_depth", "worn_volume", "max_wear_theta", "mean_contact_force"],
            "keep": ["wear_depth"],
        },
        "parameters": {
            "wear.kw": {"values": [9e-16]},
            "mechanism.joint_offset": {"values": [0.0, 0.01]},
        },
    }
    ds = run_sweep(spec, params=base, workers=0)
    assert (ds["status"].values == 0).all(), ds["error"].values
    p0 = load_parameters(base)
    w0 = from_mapping(WearSettings, read_toml(base)["wear"], where="wear")
    for i, off in enumerate([0.0, 0.01]):
        p = dataclasses.replace(p0, mechanism=dataclasses.replace(p0.mechanism, joint_offset=off))
        direct = simulate_wear(p, cycles=200, settings=w0, snapshots=[200])
        assert float(ds["max_wear_depth"][i]) == float(direct["max_wear_depth"][-1])
        assert float(ds["worn_volume"][i]) == float(direct["worn_volume"][-1])
        assert np.array_equal(ds["wear_depth"][i].values, direct["wear_depth"][-1].values)
        k = int(np.argmax(direct["wear_depth"][-1].values)) % direct.sizes["theta"]
        assert float(ds["max_wear_theta"][i]) == float(direct["theta"][k])
    assert ds["max_wear_depth"].values[0] != ds["max_wear_depth"].values[1]
    assert 0 < float(ds["mean_contact_force"][0]) < 1e3
    assert ds.attrs["data_origin"] == "simulated"


def test_cli_sweep_writes_the_file_and_reports_failures(tmp_path, capsys):
    spec = tmp_path / "spec.toml"
    spec.write_text(
        '[sweep]\nrun = "function"\nfunction = "linear"\nmethod = "lhs"\nsamples = 6\nseed = 4\n'
        "[sweep.function_args]\nfail_above = {x1 = 0.8}\n"
        '[parameters.x1]\ndistribution = "uniform"\nbounds = [0, 1]\n'
    )
    out = tmp_path / "s.nc"
    code = main(["sim", "sweep", str(spec), "--out", str(out), "--workers", "0"])
    cap = capsys.readouterr()
    assert code == 0, cap.err
    ds = io.load(out)
    n_failed = int((ds["x1"].values > 0.8).sum())
    assert 0 < n_failed < 6
    assert f"{6 - n_failed} ok, {n_failed} failed, 0 not run" in cap.out
    assert "exceeds fail_above" in cap.err
    prov = io.parse_provenance(ds)
    assert any(str(spec) in i["path"] and "sha256" in i for i in prov["inputs"])
    code = main(["sim", "sweep", str(spec), "--out", str(out), "--params", "x.toml", "--overwrite"])
    assert code == 3 and "--params does not apply" in capsys.readouterr().err
    spec.write_text(spec.read_text().replace('"lhs"', '"lhz"'))
    code = main(["sim", "sweep", str(spec), "--out", str(tmp_path / "s2.nc"), "--workers", "0"])
    err = capsys.readouterr().err
    assert code == 3 and "method = 'lhz'" in err and "Traceback" not in err


def test_runs_lost_by_the_cluster_are_not_run_and_resumable(tmp_path, monkeypatch, capsys):
    spec = tmp_path / "spec.toml"
    spec.write_text(
        '[sweep]\nrun = "function"\nfunction = "linear"\nmethod = "lhs"\nsamples = 6\n'
        '[parameters.x1]\ndistribution = "uniform"\nbounds = [0, 1]\n'
    )
    out = tmp_path / "s.nc"
    real = sweep_mod.execute_runs

    def losing(tasks, **kw):  # dask gives up on run 2 (it killed several workers)
        kw["on_lost"](2, "KilledWorker: attempted to run task 3 times")
        real([t for t in tasks if t.index != 2], **kw)

    monkeypatch.setattr(sweep_mod, "execute_runs", losing)
    code = main(["sim", "sweep", str(spec), "--out", str(out), "--workers", "0"])
    err = capsys.readouterr().err
    assert code == 3 and "--resume" in err
    ds = io.load(out)  # what was computed is written ...
    assert ds["status"].values.tolist() == [0, 0, 2, 0, 0, 0]
    assert "KilledWorker" in str(ds["error"].values[2]) and np.isnan(ds["y"].values[2])
    assert len(list(parts_dir(out).glob("run-*.npz"))) == 5  # ... and the parts are kept
    monkeypatch.setattr(sweep_mod, "execute_runs", real)
    assert main(["sim", "sweep", str(spec), "--out", str(out), "--workers", "0", "--resume"]) == 0
    ds = io.load(out)
    assert ds.attrs["runs_computed_now"] == 1 and (ds["status"].values == 0).all()
    assert not parts_dir(out).exists()


def test_second_order_sobol_index_of_the_ishigami_interaction():
    u = {"distribution": "uniform", "bounds": [-PI, PI]}
    ds = run_sweep(
        function_spec(
            "sobol",
            samples=512,
            function="ishigami",
            params={"x1": u, "x2": u, "x3": u},
            second_order=True,
            seed=3,
        ),
        workers=0,
    )
    assert ds.sizes["run"] == 512 * 8  # N (2D + 2)
    truth = analytic_sobol("ishigami")
    s13_true = truth["ST"]["x3"]  # x3 acts only through its interaction with x1
    s2 = ds["sobol_S2"].sel(output="y")
    conf = ds["sobol_S2_conf"].sel(output="y")
    est = float(s2.sel(parameter="x1", parameter_2="x3"))
    assert abs(est - s13_true) <= float(conf.sel(parameter="x1", parameter_2="x3"))
    assert abs(float(s2.sel(parameter="x1", parameter_2="x2"))) <= float(
        conf.sel(parameter="x1", parameter_2="x2")
    )


def test_a_wear_run_over_its_cycle_budget_fails_with_the_reason(tmp_path):
    spec = {
        "sweep": {
            "run": "wear",
            "method": "grid",
            "cycles": 300,
            "max_cycles_simulated": 3,
            "outputs": ["max_wear_depth"],
        },
        "parameters": {"wear.kw": {"values": [9e-16]}},
    }
    ds = run_sweep(spec, params=tiny_base(tmp_path), workers=0)
    assert ds["status"].values.tolist() == [1]
    err = str(ds["error"].values[0])
    assert "max_cycles_simulated = 3" in err and "of 300 cycles done" in err
    assert np.isnan(ds["max_wear_depth"].values[0])
