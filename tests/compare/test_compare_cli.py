"""``jointwear compare`` on files."""

from __future__ import annotations

import re

import _jw_synth as syn
import pandas as pd
import pytest

from jointwear import io
from jointwear.cli import main


@pytest.fixture()
def files(tmp_path):
    paths = {}
    for name, ds in {
        "sim_wear": syn.sim_wear(),
        "sim_motion": syn.sim_motion(),
        "meas_wear": syn.meas_wear(u=1e-6),
        "meas_wear_full": syn.meas_wear(u=1e-6, n_layers=16),  # covers the simulated width
        "meas_wear_turned": syn.meas_wear(u=1e-6, n_layers=16, rotate_deg=180.0),
        "meas_wear_turned_narrow": syn.meas_wear(u=1e-6, rotate_deg=180.0),  # +-6 mm scan
        "meas_wear_bad": syn.meas_wear(scale=2.0, u=1e-6),
        "meas_motion": syn.meas_motion(u=0.002),
        "meas_unstated": syn.meas_wear(state_convention=False),
    }.items():
        paths[name] = tmp_path / f"{name}.nc"
        io.save(ds, paths[name], validate=name != "meas_unstated")
    return paths


def _stated_zero(tmp_path):
    crit = tmp_path / "criteria.toml"
    crit.write_text(
        "[criteria]\nwear_u_num_rel = 1e-9\nwear_u_input_rel = 1e-9\n"
        "motion_u_num_rel = 1e-9\nmotion_u_input_rel = 1e-9\n"
    )
    return crit


def test_compare_cli_writes_metrics_and_table(files, tmp_path, capsys):
    out = tmp_path / "m.nc"
    table = tmp_path / "m.csv"
    argv = ["compare", str(files["sim_wear"]), str(files["meas_wear_full"]), "--out", str(out)]
    argv += ["--sim", str(files["sim_motion"]), "--meas", str(files["meas_motion"])]
    argv += ["--criteria", str(_stated_zero(tmp_path))]
    assert main([*argv, "--table", str(table)]) == 0
    text = capsys.readouterr().out
    # everything decided but the axial distribution of the wear, whose input uncertainty needs an
    # ensemble of maps (a stated relative u_input is a common scale): --strict says so, exit 1
    assert (
        "not assessed (" in text and "axial distribution of the wear" in text.split("metrics:")[1]
    )
    assert main([*argv, "--strict", "--overwrite"]) == 1
    assert "PASS            wear map shape" in text and "follower velocity x history" in text
    assert (
        "13 criteria" not in text
        and "criteria: " in text
        and "fail" not in text.split("metrics:")[1]
    )
    ds = io.load(out)
    assert {"wear_depth_sim", "wear_depth_diff", "follower_velocity_diff"} <= set(ds.data_vars)
    prov = io.parse_provenance(ds)
    assert len(prov["inputs"]) == 4 and all("sha256" in r for r in prov["inputs"])
    df = pd.read_csv(table)
    assert list(df.columns) == [
        "quantity",
        "metric",
        "value",
        "units",
        "long_name",
        "definition",
        "basis",
    ]
    assert (df.query("metric == 'rmse' and quantity == 'wear_depth'")["units"] == "m").all()
    # the user-stated uncertainties are labelled as such
    basis = df.query("metric == 'u_input' and quantity == 'max_wear_depth'")["basis"].iloc[0]
    assert basis.startswith("user-stated")


def _compare_wear(files, meas, out_flag, out):
    """Arguments of ``jointwear compare`` of the simulated wear map with ``files[meas]``."""
    return ["compare", str(files["sim_wear"]), str(files[meas]), out_flag, str(out), "--overwrite"]


def test_compare_cli_exit_codes(files, tmp_path, capsys):
    out = tmp_path / "m.nc"
    bad = _compare_wear(files, "meas_wear_bad", "--out", out)
    # without u_num and u_input the depth that is 2x off is not assessed: the screening
    # threshold it exceeds is shown, never counted as a fail (nor, elsewhere, as a pass)
    assert main(bad) == 0
    assert "screening only, not a verdict: |S - D| / |D| = 0.497 > 0.3" in capsys.readouterr().out
    bad += ["--criteria", str(_stated_zero(tmp_path))]
    assert main(bad) == 1  # a failed criterion exits 1 (no --strict needed)
    captured = capsys.readouterr()
    assert "FAIL            maximum wear depth" in captured.out
    assert "validation failed for: maximum wear depth" in captured.err
    # nothing fails, but V&V 20 is not assessed and the narrow scan leaves part of the
    # simulation unvalidated: exit 0 with a summary saying so; --strict makes it exit 1
    undecided = _compare_wear(files, "meas_wear", "-o", out)
    assert main(undecided) == 0
    text = capsys.readouterr().out
    assert "not assessed (an uncertainty is unknown" in text
    assert "validation domain: the wear criteria are decided within z = −6…+6 mm only" in text
    # the criteria file's switch restores the strict rule: the narrow scan is not comparable
    strict = tmp_path / "strict.toml"
    strict.write_text("[criteria]\nstrict_coverage = true\n")
    assert main([*undecided, "--criteria", str(strict)]) == 0
    assert "not comparable (the data do not cover it): wear map shape" in capsys.readouterr().out
    strict.write_text("[criteria]\nwear_u_num_rel = 0\n")  # a stated 0 is refused: exit 3
    assert main([*undecided, "--criteria", str(strict)]) == 3
    assert "exactly zero" in capsys.readouterr().err
    assert main([*undecided, "--strict"]) == 1
    assert "--strict: not every criterion was decided" in capsys.readouterr().err
    unstated = ["compare", str(files["sim_wear"]), str(files["meas_unstated"]), "-o", str(out)]
    unstated.append("--overwrite")
    assert main(unstated) == 3
    assert "angle_zero" in capsys.readouterr().err


def test_compare_cli_map_turned_180_degree_fails(files, tmp_path, capsys):
    """A measurement turned half a turn (a wrong angle zero) must fail, not pass."""
    out = tmp_path / "m.nc"
    argv = ["compare", str(files["sim_wear"]), str(files["meas_wear_turned"]), "-o", str(out)]
    assert main(argv) == 1
    text = capsys.readouterr().out
    # exactly half a turn: +180 or -180 by round-off in the located maxima
    assert re.search(
        r"FAIL +angle of maximum wear within z = −7\.5…\+7\.5 mm: [+-]180\.0 degree", text
    )
    assert "FAIL            wear map shape" in text
    # the same on the reference study's layout (13 layers, +-6 mm of a 15 mm bearing): the
    # simulated maximum outside the band no longer lets the turned map escape as not comparable
    argv = ["compare", str(files["sim_wear"]), str(files["meas_wear_turned_narrow"]), "-o"]
    assert main([*argv, str(out), "--overwrite"]) == 1
    text = capsys.readouterr().out
    assert re.search(r"FAIL +angle of maximum wear within z = −6…\+6 mm: [+-]180\.0 degree", text)


def test_compare_cli_motion_variables(files, tmp_path, capsys):
    out = tmp_path / "m.nc"
    argv = ["compare", str(files["sim_motion"]), str(files["meas_motion"]), "-o", str(out)]
    argv.append("--overwrite")  # the same --out for every run
    assert main([*argv, "--variable", "follower_velocity"]) == 0
    text = capsys.readouterr().out
    # z is out of the mechanism's plane: not compared unless asked for
    assert "follower velocity z history" not in text and "wear map" not in text
    assert "component(s) z not compared" in text
    assert main([*argv, "--axis", "x", "--axis", "y", "--axis", "z"]) == 0
    assert "follower velocity z history" in capsys.readouterr().out
    assert "motion aligned by crank angle: shift -111.41 ± " in text and "(-80.2 degree" in text
    assert main([*argv, "--variable", "journal_offset"]) == 3
    assert "journal_offset are not in both" in capsys.readouterr().err


def test_compare_cli_ensemble_and_verification(files, tmp_path, capsys):
    """--ensemble: u_input is the ensemble's standard deviation; --verification: GCI u_num."""
    import numpy as np
    import xarray as xr

    depth = np.array([31e-6, 33e-6, 32.5e-6, 30e-6, 34e-6])
    ens = xr.Dataset(
        {"max_wear_depth": ("run", depth, {"units": "m", "long_name": "max depth"})},
        coords={
            "run": np.arange(5),
            "kw": ("run", np.linspace(1, 2, 5), {"units": "1", "long_name": "kw"}),
        },
        attrs={"cycles": 4e5},  # the cycles of the measured map: spreads are absolute
    )
    tol = np.array([0.4, 0.2, 0.1])
    study = xr.Dataset(
        {"max_wear_depth": ("tol", 32e-6 * (1 + 0.04 * tol), {"units": "m", "long_name": "d"})},
        coords={"tol": ("tol", tol, {"units": "1", "long_name": "tolerance"})},
    )
    io.save(ens, tmp_path / "ens.nc")
    io.save(study, tmp_path / "ver.nc")
    out = tmp_path / "m.nc"
    argv = ["compare", str(files["sim_wear"]), str(files["meas_wear_full"]), "-o", str(out)]
    argv += ["--ensemble", str(tmp_path / "ens.nc"), "--verification", str(tmp_path / "ver.nc")]
    assert main(argv) in (0, 1)
    from jointwear.compare import load_comparison

    c = load_comparison(out)
    assert c.value("max_wear_depth", "u_input") == pytest.approx(np.std(depth, ddof=1))
    assert c.value("max_wear_depth", "u_num") > 0
    assert c.state("maximum wear depth", "V&V 20") in ("pass", "fail")
    assert (
        "ens.nc"
        in c.metrics.set_index(["quantity", "metric"]).loc[("max_wear_depth", "u_input"), "basis"]
    )
