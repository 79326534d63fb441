"""Benchmark: the full default wear prediction (study mechanism, 20 x 200 grid, 10^6 cycles).

Reports the wall time (median of 3 runs), the cycles actually simulated, the update-interval
sequence, the predicted wear, and the convergence of the adaptive interval (the same run
repeated with every update interval halved). Target: <= 5 minutes.
"""

from __future__ import annotations

import dataclasses
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _common import write_results  # noqa: E402

from jointwear.sim import (  # noqa: E402
    DEFAULT_PARAMETER_SET,
    PARAMETER_SETS,
    WearSettings,
    halved_schedule,
    simulate_wear,
)


def main() -> None:
    params = PARAMETER_SETS[DEFAULT_PARAMETER_SET]
    settings = WearSettings()
    cycles = 1e6
    runs = []
    for _ in range(3):
        t0 = time.perf_counter()
        ds = simulate_wear(params, cycles=cycles, settings=settings)
        runs.append((time.perf_counter() - t0, ds))
    times = [t for t, _ in runs]
    ds = runs[0][1]
    t0 = time.perf_counter()
    half = simulate_wear(
        params,
        cycles=cycles,
        settings=dataclasses.replace(settings, scheme="schedule", schedule=halved_schedule(ds)),
    )
    t_half = time.perf_counter() - t0

    def final(d, name):
        return float(d[name].values[-1])

    figures = {
        "grid": f"{params.joint.n_layers} x {params.joint.n_points}",
        "cycles_target": cycles,
        "kw_m2_per_N": settings.kw,
        "wall_time_s_median": float(np.median(times)),
        "wall_time_s_runs": times,
        "target_s": 300.0,
        "cycles_simulated": float(ds.attrs["cycles_simulated"]),
        "updates_accepted": int(ds.attrs["n_updates"]),
        "updates_rejected": int(ds.attrs["n_rejected"]),
        "dn_sequence": ds["update_dn"].values.astype(int).tolist(),
        "dn_max": int(ds["update_dn"].values.max()),
        "max_wear_depth_um": final(ds, "max_wear_depth") * 1e6,
        "worn_volume_mm3": final(ds, "worn_volume") * 1e9,
        "archard_volume_mm3": final(ds, "archard_volume") * 1e9,
        "cylindricity_um": final(ds, "cylindricity") * 1e6,
        "halved_intervals": {
            "updates_accepted": int(half.attrs["n_updates"]),
            "wall_time_s": t_half,
            "cycles_simulated": float(half.attrs["cycles_simulated"]),
            "max_wear_depth_um": final(half, "max_wear_depth") * 1e6,
            "worn_volume_mm3": final(half, "worn_volume") * 1e9,
            "max_depth_change_percent": 100
            * (final(ds, "max_wear_depth") / final(half, "max_wear_depth") - 1),
            "volume_change_percent": 100
            * (final(ds, "worn_volume") / final(half, "worn_volume") - 1),
        },
        "runs_identical": all(
            np.array_equal(d["wear_depth"].values, ds["wear_depth"].values) for _, d in runs
        ),
    }
    write_results("sim_wear", figures)


if __name__ == "__main__":
    main()
