"""Where a stiff tilt spring's cost goes: steps, rejections and CPU per step, one cycle each.

For ``joint.tilt_stiffness`` = 0, 1e3 and 3e3 N m/rad on the reference rig (``zhang2023``,
20 x 200, new bore, after two settling cycles) and ``solver.rtol`` = 1e-6 (default) and 1e-5:
accepted and rejected DOPRI5 steps per crank cycle, CPU seconds per cycle and per accepted step,
and the cycle's normal work (what the wear depends on). Issue 41 item 4 (the stiff rigs of
``bench_tilt.py`` take 43-93 s CPU for 1.2e6 cycles against a 60-s target): this says whether
the extra cost is more steps (accuracy or stability of the line contact's vibration) or more
work per step (every layer in contact).

Rows 0-5 measure every rate's error against its own magnitude (``solver.rate_error_scale =
"component"``, the integration before issue 41, bit for bit); rows 6-7 the default since
(``"auto"``: with a tilt spring the rotating body's angular velocity as one vector, at
``AUTO_VECTOR_RTOL_FACTOR`` times the rtol: ``rtol_held``); row 8 the rigid rig with
``"vector"`` (its default stays ``"component"``); row 9 the stiff rig with ``"vector"`` at the
given rtol (the vector scale without the default's factor).

Usage: ``python benchmarks/bench_tilt_profile.py``. The machine is shared: the load average is
recorded; CPU seconds of this process.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _common import write_results  # noqa: E402

import jointwear.sim.dynamics as dynamics  # noqa: E402
from jointwear.params import replace_nested  # noqa: E402
from jointwear.sim import PARAMETER_SETS, run_cycles  # noqa: E402
from jointwear.sim.parameters import AUTO_VECTOR_RTOL_FACTOR  # noqa: E402

CYCLES = 2


def profile(k: float, rtol: float, scale: str = "component") -> dict[str, float]:
    """One configuration's steps and cost per cycle (after two settling cycles)."""
    counts = {"accepted": 0, "rejected": 0}
    integrate = dynamics.integrate

    def counted(*args):
        out = integrate(*args)
        counts["accepted"] += out[4]
        counts["rejected"] += out[5]
        return out

    p = replace_nested(
        PARAMETER_SETS["zhang2023"],
        **{"joint.tilt_stiffness": k, "solver.rtol": rtol, "solver.rate_error_scale": scale},
    )
    state = run_cycles(p, cycles=2, record=False).state
    dynamics.integrate = counted
    try:
        c0 = time.process_time()
        res = run_cycles(p, cycles=CYCLES, state=state, record=False)
        cpu = time.process_time() - c0
    finally:
        dynamics.integrate = integrate
    return {
        "tilt_stiffness": k,
        "rtol": rtol,
        "rtol_held": dynamics._effective_rtol(p),
        "rate_error_scale": scale,
        "cpu_s_per_cycle": cpu / CYCLES,
        "accepted_steps_per_cycle": counts["accepted"] / CYCLES,
        "rejected_steps_per_cycle": counts["rejected"] / CYCLES,
        "cpu_us_per_accepted_step": 1e6 * cpu / counts["accepted"],
        "normal_work_per_cycle_N_m": res.normal_work / CYCLES,
    }


def main() -> None:
    rows = [profile(k, rtol) for k in (0.0, 1e3, 3e3) for rtol in (1e-6, 1e-5)]
    # the default since issue 41: with a tilt spring the angular velocity as one vector
    rows += [profile(k, 1e-6, "auto") for k in (1e3, 3e3)]
    # the rigid rig with the vector scale (not its default: that keeps its results bit for bit)
    rows.append(profile(0.0, 1e-6, "vector"))
    # the stiff rig with the vector scale at the given rtol (what "auto" was before its factor)
    rows.append(profile(3e3, 1e-6, "vector"))
    for r in rows:
        print(r, flush=True)
    base = rows[0]
    stiff = next(r for r in rows if r["tilt_stiffness"] == 3e3 and r["rtol"] == 1e-6)
    stiff_auto = next(
        r for r in rows if r["tilt_stiffness"] == 3e3 and r["rate_error_scale"] == "auto"
    )
    rigid_vector, stiff_vector = rows[8], rows[9]
    write_results(
        "tilt_profile",
        {
            "rig": "zhang2023, 20 x 200, new bore, one-cycle figures over 2 cycles after 2 "
            "settling cycles",
            "note": "the machine is shared (2 cores, several agents): CPU seconds of this process",
            "rows": rows,
            "steps_ratio_3e3_to_0": stiff["accepted_steps_per_cycle"]
            / base["accepted_steps_per_cycle"],
            "cost_per_step_ratio_3e3_to_0": stiff["cpu_us_per_accepted_step"]
            / base["cpu_us_per_accepted_step"],
            "steps_ratio_3e3_component_to_auto": stiff["accepted_steps_per_cycle"]
            / stiff_auto["accepted_steps_per_cycle"],
            "cpu_ratio_3e3_component_to_auto": stiff["cpu_s_per_cycle"]
            / stiff_auto["cpu_s_per_cycle"],
            "steps_ratio_0_component_to_vector": base["accepted_steps_per_cycle"]
            / rigid_vector["accepted_steps_per_cycle"],
            "steps_ratio_3e3_auto_to_vector": stiff_auto["accepted_steps_per_cycle"]
            / stiff_vector["accepted_steps_per_cycle"],
            "auto_vector_rtol_factor": AUTO_VECTOR_RTOL_FACTOR,
        },
    )


if __name__ == "__main__":
    main()
