"""Does the simulated contact already spread as the bore wears into the journal's shape?

Issue 41 asks for a conformal-contact wear model because "as the bore wears into the journal's
shape, the contact spreads (pressure falls) and the wear rate should fall". The kernel spreads
each slice's force over the points the rigid journal overlaps in the *worn* bore, so part of
that is already in the model. This measures it on the reference rig (``zhang2023``, 20 x 200,
default kw, adaptive control): the default wear prediction to 1.2e6 cycles with snapshots at 4e5
and 1.2e6, then, on the new bore and on each snapshot's bore, four cycles after one settling
cycle: per edge layer (first z = +wb/2, last z = -wb/2) the arc over which the cycle's wear work
is spread (points with work above 5 % of the layer's largest, in degrees), the layer's largest
wear work per cycle [Pa m] and its total; the cylindricity growth at both snapshots and their
ratio (measured 0.682).

Usage: ``python benchmarks/bench_conformity.py``. The machine is shared: CPU seconds of this
process and the load average are recorded.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _common import write_results  # noqa: E402

from jointwear.sim import PARAMETER_SETS, run_cycles, simulate_wear  # noqa: E402

P = PARAMETER_SETS["zhang2023"]
SNAPS = {"4e5": 4e5, "1.2e6": 1.2e6}
CYCLES = 4


def spread(h: np.ndarray) -> dict[str, dict[str, float]]:
    """Per edge layer: arc of the wear work [deg], its largest and total per cycle [Pa m]."""
    state = run_cycles(P, cycles=1, wear_depth=h, record=False).state
    w = run_cycles(P, cycles=CYCLES, wear_depth=h, state=state, record=False).wear_work / CYCLES
    step = 360.0 / w.shape[1]
    out = {}
    for name, row in (("first_layer", w[0]), ("last_layer", w[-1])):
        top = float(row.max())
        out[name] = {
            "arc_deg": float(np.count_nonzero(row > 0.05 * top) * step) if top > 0 else 0.0,
            "max_work_Pa_m": top,
            "total_work_Pa_m": float(row.sum()),
        }
    return out


def main() -> None:
    c0 = time.process_time()
    ds = simulate_wear(P, cycles=SNAPS["1.2e6"], snapshots=list(SNAPS.values()))
    cpu_wear = time.process_time() - c0
    cyl = {k: float(ds["cylindricity"].sel(cycles=c)) * 1e6 for k, c in SNAPS.items()}
    bores = {"new": np.zeros((P.joint.n_layers, P.joint.n_points))}
    for k, c in SNAPS.items():  # the map's z ascends: layer 0 (z = +wb/2) is its last row
        bores[k] = np.asarray(ds["wear_depth"].sel(cycles=c).values)[::-1]
    c1 = time.process_time()
    per_bore = {name: spread(h) for name, h in bores.items()}
    figures = {
        "rig": "zhang2023, 20 x 200 graded, default kw, adaptive control",
        "note": "the machine is shared (2 cores, several agents): CPU seconds of this process",
        "cylindricity_growth_um": cyl,
        "growth_ratio_4e5_to_1.2e6": cyl["4e5"] / cyl["1.2e6"],
        "measured_growth_ratio": 28.32 / 41.55,
        "spread_per_bore": per_bore,
        "cpu_s_wear": cpu_wear,
        "cpu_s_spread": time.process_time() - c1,
    }
    for name, row in per_bore.items():
        print(name, row, flush=True)
    write_results("conformity", figures)


if __name__ == "__main__":
    main()
