"""calibrate -> predict -> compare through the command line, at reduced size (a 5 x 24 bore)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from jointwear import io
from jointwear.cli import main

TRUTH_KW = 1.2e-15
BASE = (
    "[joint]\nn_layers = 5\nn_points = 24\n"
    '[wear]\nscheme = "fixed"\ndn = 100\nsettle_cycles = 0.25\ninitial_settle_cycles = 0.5\n'
)


def measured_maps(tmp_path) -> None:
    """Synthetic measured maps of the truth (kw = TRUTH_KW) at 200 and 400 cycles, 1 % noise."""
    from jointwear.params import from_mapping, read_toml
    from jointwear.sim import WearSettings, load_parameters, simulate_wear

    base = tmp_path / "base.toml"
    p = load_parameters(base)
    w = from_mapping(WearSettings, read_toml(base)["wear"], where="wear")
    ds = simulate_wear(
        p, cycles=400, settings=dataclasses.replace(w, kw=TRUTH_KW), snapshots=[200, 400]
    )
    for c in (200, 400):
        m = ds.sel(cycles=c)[["wear_depth"]].drop_vars("cycles")
        u = 0.01 * float(m["wear_depth"].max())
        noise = u * np.random.default_rng(c).standard_normal(m["wear_depth"].shape)
        m["wear_depth"] = (m["wear_depth"] + noise).assign_attrs(ds["wear_depth"].attrs)
        m["wear_depth_u"] = (m["wear_depth"] * 0 + u).assign_attrs(
            units="m", long_name="standard uncertainty of wear_depth"
        )
        m.attrs = {"data_origin": "synthetic", "cycles": c, "bearing_radius_m": 8e-3}
        io.save(m, tmp_path / f"meas-{c}.nc")


@pytest.mark.slow  # about 30 CPU s once the kernels are compiled
def test_calibrate_predict_compare_end_to_end(tmp_path, capsys):
    (tmp_path / "base.toml").write_text(BASE)
    measured_maps(tmp_path)
    spec = tmp_path / "spec.toml"
    spec.write_text(
        '[calibrate]\ndata = ["meas-200.nc"]\ncycles = 200\nsamples = 40\nseed = 1\n'
        "u_num_rel = 0.02\n"
        '[parameters."wear.kw"]\ndistribution = "uniform"\nbounds = [4.5e-16, 1.8e-15]\n'
    )
    post, pred = tmp_path / "post.nc", tmp_path / "pred.nc"
    base = ["--params", str(tmp_path / "base.toml"), "--workers", "0"]
    assert main(["sim", "calibrate", str(spec), "--out", str(post), *base]) == 0
    out = capsys.readouterr().out
    assert "wear.kw: posterior" in out and ": informed" in out
    ds = io.load(post)
    lo, hi = float(ds["posterior_q025"][0]), float(ds["posterior_q975"][0])
    assert lo < TRUTH_KW < hi
    assert float(ds["posterior_sd"][0]) / float(ds["posterior_mean"][0]) < 0.1
    assert (tmp_path / "post.design-200.nc").exists()  # the training runs are kept
    record = ds.attrs["calibration_data"]
    assert "meas-200.nc" in record and "sha256" in record
    # resume: the training runs are read back, nothing is simulated again; the same posterior
    stamp = (tmp_path / "post.design-200.nc").stat().st_mtime_ns
    assert main(["sim", "calibrate", str(spec), "--out", str(post), "--resume", *base]) == 0
    assert (tmp_path / "post.design-200.nc").stat().st_mtime_ns == stamp
    again = io.load(post)
    assert float(again["posterior_mean"][0]) == float(ds["posterior_mean"][0])

    predict = ["sim", "predict", str(post), "--cycles", "400", "--out", str(pred)]
    assert main([*predict, "--samples", "4", "--workers", "0"]) == 0
    ens = io.load(pred)
    assert ens.sizes["run"] == 4 and ens["wear_depth"].dims == ("run", "z", "theta")
    assert ens.attrs["jointwear_file"] == "posterior_prediction"
    assert np.all((ens["wear.kw"] > lo * 0.9) & (ens["wear.kw"] < hi * 1.1))

    criteria = tmp_path / "criteria.toml"
    criteria.write_text("wear_u_num_rel = 0.02\n")
    metrics = tmp_path / "m.nc"
    cmp = ["compare", str(pred), "--cycles", "400", "--criteria", str(criteria)]
    code = main([*cmp, str(tmp_path / "meas-400.nc"), "--out", str(metrics)])
    text = capsys.readouterr().out
    assert code == 0, text
    m = io.load(metrics)
    assert m.attrs["n_failed"] == 0 and m.attrs["n_pass"] >= 3
    bases = [str(m[v].attrs.get("basis", "")) for v in m.data_vars if v.endswith("__u_input")]
    assert any("pred.nc" in b for b in bases), bases  # u_input: the posterior runs' spread

    # the calibration map itself: refused, then a labelled calibration check
    code = main([*cmp, str(tmp_path / "meas-200.nc"), "--out", str(tmp_path / "c.nc")])
    assert code == 3
    assert "calibration data never validate" in capsys.readouterr().err
    code = main(
        [
            *cmp,
            str(tmp_path / "meas-200.nc"),
            "--out",
            str(tmp_path / "c.nc"),
            "--calibration-check",
        ]
    )
    text = capsys.readouterr().out
    assert "calibration check, not validation" in text
    checked = io.load(tmp_path / "c.nc")
    assert checked.attrs["validation_passed"] == 0
    assert checked.attrs["verdict_summary"].startswith("calibration check, not validation")
