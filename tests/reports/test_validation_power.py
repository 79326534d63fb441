"""Power of the verdict on known truth (issue 36), at reduced size.

Truth rig -> virtual scans on the reference study's layout (13 layers at 1 mm, z = -6…+6 mm,
instrument noise) -> the right model (its own start phase and grid, its own ensemble) and wrong
models (kw x 2, kw x 0.7), each with its own u_num and u_input; the right model's map turned by
180 degree must make ``jointwear compare`` exit 1. The curves on three truths, graded wrong
models and ten replicates come from benchmarks/bench_validation_power.py.
"""

from __future__ import annotations

import logging

import pytest

from jointwear import io
from jointwear.cli import main
from jointwear.reports.power import CI_SIZE, run_power


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
def test_right_model_passes_and_the_wrong_models_fail(power):
    result, _ = power
    truth = result["truths"]["default"]
    right = truth["right"]
    assert right["any_fail"] == 0.0, right["outcomes"]
    for rep in right["outcomes"]:
        # u_num, u_input and u_D assessed for the three band quantities and the field
        assert all(rep["states"][q] in ("pass", "fail") for q in
                   ("maximum wear depth", "worn volume", "wear field")), rep["states"]  # fmt: skip
    assert truth["wrong"]["kw x 2"]["fail_rate"]["maximum wear depth"] == 1.0
    assert truth["wrong"]["kw x 2"]["any_fail"] == 1.0
    assert truth["turned_180"]["exit_codes"] == [1] * CI_SIZE.replicates
    # the resolution of the right model's depth criterion is stated in every replicate
    budget = right["outcomes"][0]["budget"]["max_wear_depth"]
    assert budget["detectable_error_low"] < 0 < budget["detectable_error_high"]


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
