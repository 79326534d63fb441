"""Coverage of the demo's motion verification study against a finer solution.

For 40 initial crank angles of the demo's rig, the follower velocity RMS (x and y) over the
footage's window is computed at the solver tolerances of a study (the demo's nine, and the five
and seven tried before) and at rtol 1e-8, 3e-9 and 1e-9, whose mean is the truth. The study goes
through :func:`jointwear.compare.verification.refinement_study` (Eça & Hoekstra's least squares
for four or more levels); a case is covered when |finest - truth| <= 2 u_num. Figures: the
covered fraction per study, the median |error| / u_num, and the truth's own spread relative to
the error (how much of the "error" the truth's scatter could be). About 35 s of CPU.
"""

from __future__ import annotations

import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _common import write_results  # noqa: E402

from jointwear.compare.verification import refinement_study  # noqa: E402
from jointwear.params import replace_nested  # noqa: E402
from jointwear.reports.demo import FULL, _params  # noqa: E402
from jointwear.reports.demo_studies import MOTION_RTOLS, _rms_window  # noqa: E402
from jointwear.sim import run_cycles  # noqa: E402

STUDIES = {
    "nine_levels": MOTION_RTOLS,
    "seven_levels": (1e-4, 3e-5, 1e-5, 5e-6, 3e-6, 2e-6),
    "five_levels": (1e-4, 3e-5, 1e-5, 3e-6),
}
FINE_RTOLS = (1e-8, 3e-9, 1e-9)
ANGLES_DEG = np.arange(0.0, 360.0, 9.0)


def main() -> None:
    params = _params(FULL)
    finest_rtol = float(params.solver.rtol)
    rtols = sorted({finest_rtol, *FINE_RTOLS, *(r for s in STUDIES.values() for r in s)})
    c0 = time.process_time()
    rms: dict[tuple[float, float], np.ndarray] = {}
    for angle in ANGLES_DEG:
        for rtol in rtols:
            changes = {"solver.rtol": rtol, "mechanism.initial_crank_angle_deg": float(angle)}
            motion = run_cycles(replace_nested(params, **changes), cycles=FULL.motion_cycles)
            r = _rms_window(motion.dataset, FULL.rig_duration)
            rms[angle, rtol] = np.array(
                [r["follower_velocity_x_rms"], r["follower_velocity_y_rms"]]
            )
    figures: dict = {"cases": 2 * len(ANGLES_DEG), "fine_rtols": list(FINE_RTOLS)}
    for name, study in STUDIES.items():
        levels = [*study, finest_rtol]
        covered, ratio, truth_spread = [], [], []
        for angle in ANGLES_DEG:
            values = np.array([rms[angle, r] for r in levels])
            fine = np.array([rms[angle, r] for r in FINE_RTOLS])
            for c in range(2):
                g = refinement_study(levels, values[:, c], formal_order=1.0, refined="solver_rtol")
                u = g.u_num_rel * abs(values[-1, c]) if g.assessed else float("nan")
                err = abs(values[-1, c] - fine[:, c].mean())
                covered.append(bool(err <= 2 * u))
                ratio.append(err / u)
                truth_spread.append(fine[:, c].std(ddof=1) / err)
        figures[name] = {
            "levels": len(levels),
            "covered_fraction_2u": float(np.mean(covered)),
            "median_error_over_u": float(statistics.median(ratio)),
            "median_truth_spread_over_error": float(statistics.median(truth_spread)),
        }
    figures["cpu_s"] = round(time.process_time() - c0, 1)
    path = write_results("motion_verification", figures)
    print(path)


if __name__ == "__main__":
    main()
