"""Fixtures of the report tests: synthetic simulation/measurement files with known truth."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "compare"))

import _jw_synth as syn  # noqa: E402

from jointwear import io  # noqa: E402


@pytest.fixture(scope="session")
def report_files(tmp_path_factory):
    """Simulated wear + motion, measured wear (rotated 40 degree) + motion, saved as netCDF."""
    folder = tmp_path_factory.mktemp("report-inputs")
    data = {
        "sim_wear": syn.sim_wear(),
        "sim_motion": syn.sim_motion(),
        "metrology": syn.meas_wear(u=1e-6, rotate_deg=40.0, scale=1.5),
        "dic": syn.meas_motion(u=0.01, scale=1.05),
    }
    paths = {}
    for name, ds in data.items():
        paths[name] = folder / f"{name}.nc"
        io.save(ds, paths[name], command=f"synthetic {name}")
    return paths


@pytest.fixture(scope="session")
def report_of_all(report_files):
    """``report_of_all(out, command)``: the report of every file of ``report_files`` with the
    strict coverage rule (the narrow scan leaves some criteria not comparable)."""
    from jointwear.compare import Criteria
    from jointwear.reports import report_from_files

    f = report_files

    def build(out, command):
        return report_from_files(
            out,
            sim=[f["sim_wear"], f["sim_motion"]],
            metrology=[f["metrology"]],
            dic=[f["dic"]],
            command=command,
            criteria=Criteria(strict_coverage=True),
        )

    return build
