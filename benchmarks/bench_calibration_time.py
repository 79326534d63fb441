"""Benchmark: the CPU time of a full-size calibrate -> predict -> compare on the default rig.

The default rig (the default bore grid and adaptive wear scheme), a synthetic measurement of
it with kw = 1.15 x the default (1 % noise per point, independent, stated as ``wear_depth_u``
and ``wear_depth_u_random``) after 2e5 cycles (calibration) and 4e5 cycles (validation); kw
calibrated from a uniform ±50 % prior on ``training_runs`` training runs, ``sim predict`` of
``prediction_runs`` posterior samples at 4e5 cycles, ``compare`` against the 4e5 map. Each
phase's CPU time (this process: ``workers = 0``, everything in-process) is written as soon as it
ends, so a run stopped early keeps the phases done. The target is 15 min on 2 cores.

Run: ``python benchmarks/bench_calibration_time.py [--training-runs N] [--prediction-runs M]
[--folder DIR]`` (results: benchmarks/results/calibration_time.json). With ``--folder`` the
study is kept there; run again with ``--resume-predict`` it keeps the recorded calibrate phase
and measures the prediction and the comparison on that posterior (a run stopped after its
calibration, on a machine too loaded to finish in one go); ``predict_per_run`` then gives
the prediction's CPU per posterior sample, and ``total_at_default_prediction_runs`` the total
with the default 16 prediction runs at that rate.
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _common import write_results  # noqa: E402
from bench_calibration import NOISE, U_NUM_REL, spec_text, truth_maps  # noqa: E402


def _arg(name: str, default: int) -> int:
    return int(sys.argv[sys.argv.index(name) + 1]) if name in sys.argv else default


SIZE: dict[str, Any] = {
    "replicates": 1,
    "n_layers": None,
    "n_points": None,
    "calibration_cycles": 200000,
    "validation_cycles": 400000,
    "training_runs": _arg("--training-runs", 20),
    "prediction_runs": _arg("--prediction-runs", 16),
    "wear_update": "the default (adaptive)",
}


def main() -> None:
    import json

    from _common import RESULTS

    from jointwear.compare import compare_files
    from jointwear.sim.calibrate import PREDICT_SAMPLES, calibrate, predict
    from jointwear.sim.wear._settings import DEFAULT_KW

    kept = sys.argv[sys.argv.index("--folder") + 1] if "--folder" in sys.argv else None
    folder = Path(kept) if kept else Path(tempfile.mkdtemp(prefix="bench-calibration-time-"))
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "base.toml").write_text("")  # the default rig
    figures: dict[str, Any] = {
        "size": SIZE,
        "truth": {"rig": "default", "kw_factor": 1.15, "noise_rel": NOISE},
        "cpu_s": {},
        "note": "CPU time of this process (workers = 0) on a shared 2-core machine (see the "
        "load average); the synthetic measurement's own simulation is not counted",
    }

    def phase(name: str, t0: float) -> None:
        figures["cpu_s"][name] = time.process_time() - t0
        figures["cpu_s"]["total"] = sum(
            v for k, v in figures["cpu_s"].items() if k in ("calibrate", "predict", "compare")
        )
        write_results("calibration_time", figures)

    early, late = truth_maps(folder, SIZE, 0, 1.15 * DEFAULT_KW)
    if "--resume-predict" in sys.argv:  # the calibrate phase as recorded, on this posterior
        old = json.loads((RESULTS / "calibration_time.json").read_text())["figures"]
        figures.update({k: v for k, v in old.items() if k.startswith("posterior_kw")})
        figures["cpu_s"] = {"calibrate": old["cpu_s"]["calibrate"]}
        figures["size"]["training_runs"] = old["size"]["training_runs"]
    else:
        spec = folder / "spec.toml"
        spec.write_text(spec_text(early, SIZE, DEFAULT_KW))
        t0 = time.process_time()
        post = calibrate(spec, out=folder / "post.nc", params=folder / "base.toml", workers=0)
        figures["posterior_kw_over_truth"] = float(post["posterior_mean"][0]) / (1.15 * DEFAULT_KW)
        figures["posterior_kw_sd_over_mean"] = float(
            post["posterior_sd"][0] / post["posterior_mean"][0]
        )
        phase("calibrate", t0)
    t0 = time.process_time()
    c2 = SIZE["validation_cycles"]
    pred = folder / "prediction.nc"
    predict(folder / "post.nc", cycles=c2, out=pred, samples=SIZE["prediction_runs"], workers=0)
    phase("predict", t0)
    per_run = figures["cpu_s"]["predict"] / SIZE["prediction_runs"]
    figures["cpu_s"]["predict_per_run"] = per_run
    t0 = time.process_time()
    crit = folder / "criteria.toml"
    crit.write_text(f"wear_u_num_rel = {U_NUM_REL}\n")
    res = compare_files([pred], [late], folder / "m.nc", criteria=crit, cycles=c2)
    figures["compare_summary"] = res.summary()
    figures["u_val_over_d_max_depth"] = res.value("max_wear_depth", "U_val") / abs(
        res.value("max_wear_depth", "value_meas")
    )
    phase("compare", t0)
    cpu = figures["cpu_s"]
    cpu["total"] = cpu["calibrate"] + cpu["predict"] + cpu["compare"]
    cpu["total_at_default_prediction_runs"] = (
        cpu["calibrate"] + PREDICT_SAMPLES * per_run + cpu["compare"]
    )
    figures["within_15_min"] = cpu["total_at_default_prediction_runs"] <= 900.0
    write_results("calibration_time", figures)


if __name__ == "__main__":
    main()
