"""benchmarks/bench_calibration.py at its CI size (--quick): the figures it writes hold."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest

BENCH = Path(__file__).resolve().parents[2] / "benchmarks" / "bench_calibration.py"


@pytest.mark.slow  # about 90 CPU s: 2 x 40 training runs, 4 calibrations, 12 validation runs
def test_quick_calibration_benchmark_recovers_kw_and_narrows_u_val(tmp_path, monkeypatch):
    monkeypatch.syspath_prepend(str(BENCH.parent))
    monkeypatch.setattr(sys, "argv", ["bench_calibration.py", "--quick"])
    spec = importlib.util.spec_from_file_location("bench_calibration_quick", BENCH)
    bench = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bench)
    assert bench.SIZE["replicates"] == 3
    fig = bench.run(bench.SIZE, tmp_path)
    assert fig["replicates_covered"] >= 2  # the truth's kw inside the 95 % interval
    assert 0.9 < fig["posterior_mean_over_truth_median"] < 1.1
    assert fig["posterior_sd_over_mean_max"] <= 0.2 < fig["prior_sd_over_mean"]
    u_val = fig["u_val_over_d_max_depth"]
    assert u_val["after_posterior"] < 0.5 * u_val["before_prior_ensemble"]
    wrong = fig["wrong_form"]  # tilt stiffness 0 against the tilt-1000 truth
    assert wrong["calibration"].startswith("refused") or wrong["failed"], wrong
