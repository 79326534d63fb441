"""The verdict can tell a right model from wrong ones (issue 20), at reduced size.

Truth rig -> virtual scans on the reference study's layout (13 layers at 1 mm, z = -6…+6 mm,
instrument noise) -> right model (independent run) and wrong models (kw x 2, joint offset 0,
friction 0), each with its own u_num (adaptive update) and an ensemble's u_input; the right
model's map turned by 180 degree must make ``jointwear compare`` exit 1. The full-size figures
(5 replicates, own ensembles) come from benchmarks/bench_validation_power.py.
"""

from __future__ import annotations

import logging

import pytest

from jointwear import io
from jointwear.cli import main
from jointwear.reports.power import CI_SIZE, WRONG_MODELS, run_power


@pytest.fixture(scope="module")
def power(tmp_path_factory):
    logging.disable(logging.WARNING)
    try:
        keep: dict = {}
        result = run_power(CI_SIZE, folder=tmp_path_factory.mktemp("power"), keep=keep)
    finally:
        logging.disable(logging.NOTSET)
    return result, keep


@pytest.mark.slow
def test_right_model_passes_and_every_wrong_model_fails(power):
    result, _ = power
    right = result["right"]
    assert right["false_fail_rate"] == 0.0
    assert right["min_passes"] >= 3
    for rep in right["replicates"]:
        assert rep["n_not_assessed"] == 0  # u_num, u_input and u_D all assessed
    for name in WRONG_MODELS:
        assert result["wrong"][name]["detection_rate"] == 1.0, name
    assert result["turned_180"]["exit_codes"] == [1] * CI_SIZE.replicates
    assert result["targets_met"]


@pytest.mark.slow
def test_turned_map_exits_1_through_the_command_line(power, tmp_path, capsys):
    _, keep = power
    paths = {}
    for name in ("measurement", "right", "turned", "ensemble"):
        paths[name] = tmp_path / f"{name}.nc"
        io.save(keep[name], paths[name], validate=False)
    common = ["--ensemble", str(paths["ensemble"]), "--overwrite"]
    ok = ["compare", str(paths["right"]), str(paths["measurement"]), "-o", str(tmp_path / "a.nc")]
    assert main([*ok, *common]) == 0
    bad = ["compare", str(paths["turned"]), str(paths["measurement"]), "-o", str(tmp_path / "b.nc")]
    assert main([*bad, *common]) == 1
    assert "FAIL            angle of maximum wear within z = −6…+6 mm" in capsys.readouterr().out
