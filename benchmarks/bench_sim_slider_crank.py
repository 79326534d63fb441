"""CPU time of the slider-crank benchmark: one crank cycle, and a 1e5-cycle wear prediction.

``PARAMETER_SETS["slider_crank"]`` (rod-slider clearance 0.5 mm, 5000 rpm, 8 x 200 grid,
recording at 1e-5 s); median CPU time of this process over one-cycle runs after settling (the
machine is shared), and the CPU time of ``simulate_wear`` to 1e5 cycles (adaptive updates).
"""

from __future__ import annotations

import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _common import write_results  # noqa: E402

from jointwear.sim import PARAMETER_SETS, run_cycles, simulate_wear  # noqa: E402


def main() -> None:
    p = PARAMETER_SETS["slider_crank"]
    settled = run_cycles(p, cycles=1.0, record=False).state  # compiles / loads the kernels too
    cpu, steps = [], []
    for _ in range(7):
        c0 = time.process_time()
        steps.append(run_cycles(p, cycles=1.0, state=settled).n_steps)
        cpu.append(time.process_time() - c0)
    c0 = time.process_time()
    ds = simulate_wear(p, cycles=1e5)
    wear_cpu = time.process_time() - c0
    write_results(
        "sim_slider_crank",
        {
            "cpu_seconds_per_cycle": statistics.median(cpu),
            "accepted_steps_per_cycle": statistics.median(steps),
            "wear_1e5_cycles_cpu_s": wear_cpu,
            "wear_1e5_cycles_simulated": float(ds.attrs["cycles_simulated"]),
            "wear_1e5_max_depth_um": float(ds["max_wear_depth"].isel(cycles=-1)) * 1e6,
        },
    )


if __name__ == "__main__":
    main()
