"""Grid convergence of the wear prediction (issue 16): 20x200 -> 40x400 -> 80x800.

For each grid and wear projection (``contact.wear_projection``: the default
``local_conserving``, ``local``, and ``lumped`` as before issue 16): the wear map after 4e5
cycles (study mechanism, default kw, *fixed* update interval so that the adaptive controller
cannot make the grids differ by their update sequences) - maximum depth, worn volume and the
maximum depth of each edge layer - and the wear work of one cycle on the new bore at the
edge layers (mean of three consecutive cycles after settling; the impacts make single cycles
differ by several per cent). Also the impact-velocity floor: the same figures with
``contact.impact_velocity_floor`` 0.01 and 0.001 m/s on the coarsest grid. Targets: <= 5 %
between the two coarsest grids, <= 3 % between the two finest.

Usage: ``python benchmarks/bench_sim_grid.py [--projections local_conserving]
[--grids 20x200,40x400] [--set contact.impact_latch=layer] [--name other]``.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _common import write_results  # noqa: E402

from jointwear.params import replace_nested  # noqa: E402
from jointwear.sim import PARAMETER_SETS, WearSettings, run_cycles, simulate_wear  # noqa: E402

CYCLES = 4e5
DN = 10_000


def _value(text: str) -> object:
    for conv in (int, float):
        try:
            return conv(text)
        except ValueError:
            pass
    return {"true": True, "false": False}.get(text.lower(), text)


def one_cycle_edge_work(params, cycles: int = 3) -> dict[str, float]:
    """Mean over ``cycles`` cycles (after one settling cycle) of edge and total wear work."""
    st = run_cycles(params, cycles=1.0, record=False).state
    first, last, total, normal = [], [], [], []
    for _ in range(cycles):
        r = run_cycles(params, cycles=1.0, state=st, record=False)
        st = r.state
        first.append(float(r.wear_work[0].max()))
        last.append(float(r.wear_work[-1].max()))
        total.append(float(np.sum(r.wear_work * r.point_area)))
        normal.append(r.normal_work)
    return {
        "edge_work_first_layer_Pa_m": float(np.mean(first)),
        "edge_work_last_layer_Pa_m": float(np.mean(last)),
        "wear_work_times_area_N_m": float(np.mean(total)),
        "normal_work_N_m": float(np.mean(normal)),
    }


def wear_at(params, cycles: float = CYCLES, dn: int = DN) -> dict[str, float]:
    """Figures of the wear map after ``cycles`` with a fixed update interval ``dn``."""
    t0 = time.process_time()
    ds = simulate_wear(
        params, cycles=cycles, settings=WearSettings(scheme="fixed", dn=dn), snapshots=[cycles]
    )
    h = ds["wear_depth"].isel(cycles=-1).transpose("z", "theta").values  # z ascending
    return {
        "max_depth_um": 1e6 * float(ds["max_wear_depth"][-1]),
        "volume_mm3": 1e9 * float(ds["worn_volume"][-1]),
        "archard_volume_mm3": 1e9 * float(ds["archard_volume"][-1]),
        "edge_depth_first_layer_um": 1e6 * float(h[-1].max()),  # layer 1 at z = +wb/2
        "edge_depth_last_layer_um": 1e6 * float(h[0].max()),
        "cylindricity_um": 1e6 * float(ds["cylindricity"][-1]),
        "cpu_s": time.process_time() - t0,
    }


def _changes(per_grid: dict[str, dict[str, float]]) -> dict[str, dict[str, float]]:
    grids = list(per_grid)
    out = {}
    for a, b in zip(grids[:-1], grids[1:], strict=True):
        out[f"{a}_to_{b}_percent"] = {
            k: 100.0 * (per_grid[b][k] / per_grid[a][k] - 1.0)
            for k in per_grid[a]
            if not k.startswith("cpu") and per_grid[a][k] != 0
        }
    return out


def grid_study(base, grids) -> dict[str, object]:
    """One-cycle and 4e5-cycle figures on each grid, and their changes between grids."""
    one, long = {}, {}
    for nl, nd in grids:
        p = replace_nested(base, **{"joint.n_layers": nl, "joint.n_points": nd})
        one[f"{nl}x{nd}"] = one_cycle_edge_work(p)
        long[f"{nl}x{nd}"] = wear_at(p)
        print(base.contact.wear_projection, f"{nl}x{nd}", one[f"{nl}x{nd}"], long[f"{nl}x{nd}"])
    return {
        "one_cycle_new_bore": one,
        "one_cycle_changes": _changes(one),
        "after_4e5_cycles": long,
        "after_4e5_changes": _changes(long),
    }


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--set", action="append", default=[], help="parameter override key=value")
    ap.add_argument("--grids", default="20x200,40x400,80x800")
    ap.add_argument("--projections", default="local_conserving,local,lumped")
    ap.add_argument("--name", default="sim_grid")
    ap.add_argument("--no-floor", action="store_true", help="skip the impact-velocity floor study")
    args = ap.parse_args(argv)
    base = PARAMETER_SETS["zhang2023"]
    overrides = dict(kv.split("=", 1) for kv in args.set)
    base = replace_nested(base, **{k: _value(v) for k, v in overrides.items()})
    grids = [tuple(int(v) for v in g.split("x")) for g in args.grids.split(",")]
    figures: dict[str, object] = {
        "overrides": overrides,
        "impact_latch": base.contact.impact_latch,
        "cycles": CYCLES,
        "fixed_dn": DN,
        "target": "<= 5 % coarsest pair, <= 3 % finest pair (edge wear work, max depth, volume)",
    }
    for proj in args.projections.split(","):
        figures[f"projection_{proj}"] = grid_study(
            replace_nested(base, **{"contact.wear_projection": proj}), grids
        )
    if not args.no_floor:
        nl, nd = grids[0]
        one, long = {}, {}
        for floor in (1e-2, 1e-3):
            p = replace_nested(
                base,
                **{
                    "joint.n_layers": nl,
                    "joint.n_points": nd,
                    "contact.impact_velocity_floor": floor,
                },
            )
            one[f"{floor:g}"] = one_cycle_edge_work(p)
            long[f"{floor:g}"] = wear_at(p)
        figures[f"impact_velocity_floor_{nl}x{nd}"] = {
            "one_cycle_new_bore": one,
            "one_cycle_changes": _changes(one),
            "after_4e5_cycles": long,
            "after_4e5_changes": _changes(long),
        }
    write_results(args.name, figures)


if __name__ == "__main__":
    main()
