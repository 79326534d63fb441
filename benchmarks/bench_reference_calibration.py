"""The reference study calibrated on the paper's 4e5 growth and validated at 1.2e6 (issue 35).

Runs :func:`jointwear.datasets.reference_study.run_reference_study` and then
:func:`jointwear.datasets.reference_calibration.calibrate_reference` (kw and the tilt stiffness
calibrated on the 4e5 cylindricity growth on the 13 layers centred, the 1.2e6 growth decided
with the posterior prediction and the calibrated model's own update-interval study), and writes
the posterior (mean, sd, posterior/prior sd, informed or not), the 1.2e6 decision (state, S, D,
E, U_val, detectable error), the growth ratios and the CPU time of the calibrate -> validate
step to ``results/reference_calibration.json`` (``--reduced``: the CI size,
``results/reference_calibration_reduced.json``). docs/compare-report.md quotes it.

    python benchmarks/bench_reference_calibration.py [--reduced]
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _common import write_results  # noqa: E402

from jointwear.datasets.reference_calibration import (  # noqa: E402
    VALIDATION_KEY,
    calibrate_reference,
    reference_lines,
)
from jointwear.datasets.reference_study import FULL, REDUCED, run_reference_study  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--reduced", action="store_true", help="the CI size (REDUCED)")
    args = ap.parse_args()
    size = REDUCED if args.reduced else FULL
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.process_time()
        prior = run_reference_study(tmp, size)
        t1 = time.process_time()
        cal = calibrate_reference(tmp, size, prior, say=print)
        t2 = time.process_time()
    lines = reference_lines(cal)
    print("\n".join(lines))
    post = cal.posterior
    names = json.loads(post.attrs["calibrated_parameters"])
    lost = set(json.loads(post.attrs["not_informed"]))
    row = cal.validation.decisions[cal.validation.decisions.key == VALIDATION_KEY].iloc[0]

    def metric(name: str) -> float:
        try:
            return cal.validation.value(VALIDATION_KEY, name)
        except KeyError:
            return float("nan")

    figures = {
        "size": "reduced" if args.reduced else "full",
        "grid": f"{size.layers} x {size.points}",
        "training_runs": size.training_runs,
        "prediction_runs": size.prediction_runs,
        "posterior": {
            n: {
                "mean": float(post["posterior_mean"].values[k]),
                "sd": float(post["posterior_sd"].values[k]),
                "width_ratio": round(float(post["width_ratio"].values[k]), 3),
                "informed": n not in lost,
            }
            for k, n in enumerate(names)
        },
        "u_num_basis_calibration": cal.u_num_basis,
        "validation_1_2e6": {
            "state": str(row.state),
            "S_um": round(metric("value_sim") * 1e6, 2),
            "D_um": round(metric("value_meas") * 1e6, 2),
            "E_um": round(metric("E") * 1e6, 2),
            "U_val_um": round(metric("U_val") * 1e6, 2),
            "detectable_error_low": round(metric("detectable_error_low"), 3),
            "detectable_error_high": round(metric("detectable_error_high"), 3),
        },
        "growth_ratio_measured": round(cal.measured_ratio, 3),
        "growth_ratio_predicted": round(cal.predicted_ratio, 3),
        "growth_ratio_predicted_u": round(cal.predicted_ratio_u, 3),
        "cpu_s_reference_study": round(t1 - t0, 1),
        "cpu_s_calibrate_validate": round(t2 - t1, 1),
        "printed": lines,
    }
    name = "reference_calibration_reduced" if args.reduced else "reference_calibration"
    print(write_results(name, figures))


if __name__ == "__main__":
    main()
