"""``jointwear compare`` on files."""

from __future__ import annotations

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
        "meas_wear_bad": syn.meas_wear(scale=2.0),
        "meas_motion": syn.meas_motion(u=0.002),
        "meas_unstated": syn.meas_wear(state_convention=False),
    }.items():
        paths[name] = tmp_path / f"{name}.nc"
        io.save(ds, paths[name], validate=name != "meas_unstated")
    return paths


def test_compare_cli_writes_metrics_and_table(files, tmp_path, capsys):
    out = tmp_path / "m.nc"
    table = tmp_path / "m.csv"
    argv = ["compare", str(files["sim_wear"]), str(files["meas_wear"]), "--out", str(out)]
    argv += ["--sim", str(files["sim_motion"]), "--meas", str(files["meas_motion"])]
    assert main([*argv, "--table", str(table), "--strict"]) == 0
    text = capsys.readouterr().out
    assert "PASS  wear map shape" in text and "follower velocity x history" in text
    ds = io.load(out)
    assert {"wear_depth_sim", "wear_depth_diff", "follower_velocity_diff"} <= set(ds.data_vars)
    prov = io.parse_provenance(ds)
    assert len(prov["inputs"]) == 4 and all("sha256" in r for r in prov["inputs"])
    df = pd.read_csv(table)
    assert list(df.columns) == ["quantity", "metric", "value", "units", "long_name", "definition"]
    assert (df.query("metric == 'rmse' and quantity == 'wear_depth'")["units"] == "m").all()


def test_compare_cli_exit_codes(files, tmp_path, capsys):
    out = tmp_path / "m.nc"
    bad = ["compare", str(files["sim_wear"]), str(files["meas_wear_bad"]), "-o", str(out)]
    bad.append("--overwrite")  # the same --out for every run
    assert main(bad) == 0  # without --strict a failed criterion is only reported
    assert "FAIL  maximum wear depth" in capsys.readouterr().out
    assert main([*bad, "--strict"]) == 1
    assert "validation failed for: maximum wear depth" in capsys.readouterr().err
    unstated = ["compare", str(files["sim_wear"]), str(files["meas_unstated"]), "-o", str(out)]
    unstated.append("--overwrite")
    assert main(unstated) == 3
    assert "angle_zero" in capsys.readouterr().err


def test_compare_cli_motion_variables(files, tmp_path, capsys):
    out = tmp_path / "m.nc"
    argv = ["compare", str(files["sim_motion"]), str(files["meas_motion"]), "-o", str(out)]
    argv.append("--overwrite")  # the same --out for every run
    assert main([*argv, "--variable", "follower_velocity"]) == 0
    text = capsys.readouterr().out
    assert "follower velocity z history" in text and "wear map" not in text
    assert "motion aligned by crank angle: shift -111.41 ms (-80.2 degree" in text
    assert main([*argv, "--variable", "journal_offset"]) == 3
    assert "journal_offset are not in both" in capsys.readouterr().err
