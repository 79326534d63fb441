"""Grid convergence of the wear prediction (issue 16): 20x200 -> 40x400 -> 80x800.

For each grid and wear projection (``contact.wear_projection``: the default
``local_conserving``, ``local``, and ``lumped`` as before issue 16): the wear map after 4e5
cycles (study mechanism, default kw, *fixed* update interval so that the adaptive controller
cannot make the grids differ by their update sequences) - maximum depth, worn volume and the
maximum depth of each edge layer - and the wear work of one cycle on the new bore at the
edge layers. The motion with clearance is chaotic (single cycles differ by several per cent in
normal work, by tens of per cent at an edge point), so every figure is a mean with its standard
error: the one-cycle work over 24 consecutive cycles after settling, the 4e5-cycle map over three
runs that start measuring at different phases of the motion; each change between grids is
given as [change, standard uncertainty] in per cent. Also the impact-velocity floor: the same figures with
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
from jointwear.sim import (  # noqa: E402
    DEFAULT_PARAMETER_SET,
    PARAMETER_SETS,
    WearSettings,
    run_cycles,
    simulate_wear,
)

CYCLES = 4e5
DN = 10_000
EDGE_CYCLES = 24  # single cycles averaged for the one-cycle edge wear work
REPLICATES = 3  # 4e5-cycle runs per grid, started from different phases of the motion


def _value(text: str) -> object:
    for conv in (int, float):
        try:
            return conv(text)
        except ValueError:
            pass
    return {"true": True, "false": False}.get(text.lower(), text)


def _mean_se(values: list[float]) -> tuple[float, float]:
    v = np.asarray(values, dtype=float)
    return float(v.mean()), float(v.std(ddof=1) / np.sqrt(v.size)) if v.size > 1 else float("nan")


def one_cycle_edge_work(
    params, cycles: int = EDGE_CYCLES, wear_depth: np.ndarray | None = None
) -> dict[str, list[float]]:
    """Mean and standard error over ``cycles`` single cycles (after one settling cycle) of the
    wear work at the edge layers and of the total wear work.

    The motion with clearance is chaotic: single cycles differ by several per cent in normal
    work and by tens of per cent in the wear work at an edge point, so a grid comparison is
    made on means with their standard errors. ``wear_depth`` (layer order, [m]): on that worn
    bore instead of the new one.
    """
    st = run_cycles(params, cycles=1.0, wear_depth=wear_depth, record=False).state
    rows: dict[str, list[float]] = {
        "edge_work_first_layer_Pa_m": [],
        "edge_work_last_layer_Pa_m": [],
        "wear_work_times_area_N_m": [],
        "normal_work_N_m": [],
    }
    for _ in range(cycles):
        r = run_cycles(params, cycles=1.0, wear_depth=wear_depth, state=st, record=False)
        st = r.state
        rows["edge_work_first_layer_Pa_m"].append(float(r.wear_work[0].max()))
        rows["edge_work_last_layer_Pa_m"].append(float(r.wear_work[-1].max()))
        rows["wear_work_times_area_N_m"].append(float(np.sum(r.wear_work * r.point_area)))
        rows["normal_work_N_m"].append(r.normal_work)
    return {k: list(_mean_se(v)) for k, v in rows.items()}


def _wear_once(params, cycles: float, dn: int, settle: float, edge_cycles: int) -> dict[str, float]:
    ds = simulate_wear(
        params,
        cycles=cycles,
        settings=WearSettings(scheme="fixed", dn=dn, initial_settle_cycles=settle),
        snapshots=[cycles],
    )
    h = ds["wear_depth"].isel(cycles=-1).transpose("z", "theta").values  # z ascending
    # the edge wear work on the worn bore: one cycle on the final map (layer order)
    edge = one_cycle_edge_work(params, cycles=edge_cycles, wear_depth=h[::-1])
    return {
        "edge_work_first_layer_at_end_Pa_m": edge["edge_work_first_layer_Pa_m"][0],
        "edge_work_last_layer_at_end_Pa_m": edge["edge_work_last_layer_Pa_m"][0],
        "max_depth_um": 1e6 * float(ds["max_wear_depth"][-1]),
        "volume_mm3": 1e9 * float(ds["worn_volume"][-1]),
        "archard_volume_mm3": 1e9 * float(ds["archard_volume"][-1]),
        "edge_depth_first_layer_um": 1e6 * float(h[-1].max()),  # layer 1 at z = +wb/2
        "edge_depth_last_layer_um": 1e6 * float(h[0].max()),
        "cylindricity_um": 1e6 * float(ds["cylindricity"][-1]),
    }


def wear_at(
    params,
    cycles: float = CYCLES,
    dn: int = DN,
    replicates: int = REPLICATES,
    edge_cycles: int = EDGE_CYCLES,
) -> dict[str, list[float]]:
    """Figures of the wear map after ``cycles`` with a fixed update interval ``dn``: mean and
    standard error over ``replicates`` runs whose measured cycles start at different phases
    of the motion (2, 3, 4 ... initial settling cycles); the edge wear work on the final map
    is averaged over ``edge_cycles`` cycles in all."""
    t0 = time.process_time()
    per_run = max(2, edge_cycles // replicates)
    runs = [_wear_once(params, cycles, dn, 2.0 + k, per_run) for k in range(replicates)]
    out = {k: list(_mean_se([r[k] for r in runs])) for k in runs[0]}
    out["cpu_s"] = [time.process_time() - t0, float("nan")]
    return out


def _changes(per_grid: dict[str, dict[str, list[float]]]) -> dict[str, dict[str, list[float]]]:
    """Relative change between consecutive grids [%] and its standard uncertainty [%]."""
    grids = list(per_grid)
    out = {}
    for a, b in zip(grids[:-1], grids[1:], strict=True):
        row = {}
        for k, (ma, sa) in per_grid[a].items():
            mb, sb = per_grid[b][k]
            if k.startswith("cpu") or ma == 0:
                continue
            u = 100.0 * (mb / ma) * np.hypot(sa / ma, sb / mb) if np.isfinite(sa + sb) else None
            row[k] = [100.0 * (mb / ma - 1.0), u]
        out[f"{a}_to_{b}_percent"] = row
    return out


def grid_study(
    base, grids, replicates: int = REPLICATES, edge_cycles: int = EDGE_CYCLES
) -> dict[str, object]:
    """One-cycle and 4e5-cycle figures on each grid, and their changes between grids
    (each figure as [mean, standard error])."""
    one, long = {}, {}
    for nl, nd in grids:
        p = replace_nested(base, **{"joint.n_layers": nl, "joint.n_points": nd})
        one[f"{nl}x{nd}"] = one_cycle_edge_work(p, edge_cycles)
        long[f"{nl}x{nd}"] = wear_at(p, replicates=replicates, edge_cycles=edge_cycles)
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
    ap.add_argument(
        "--edge-cycles", type=int, default=EDGE_CYCLES, help="cycles averaged per edge wear work"
    )
    ap.add_argument("--replicates", type=int, default=REPLICATES, help="4e5-cycle runs per grid")
    ap.add_argument("--no-floor", action="store_true", help="skip the impact-velocity floor study")
    args = ap.parse_args(argv)
    base = PARAMETER_SETS[DEFAULT_PARAMETER_SET]
    overrides = dict(kv.split("=", 1) for kv in args.set)
    base = replace_nested(base, **{k: _value(v) for k, v in overrides.items()})
    grids = [tuple(int(v) for v in g.split("x")) for g in args.grids.split(",")]
    figures: dict[str, object] = {
        "overrides": overrides,
        "impact_latch": base.contact.impact_latch,
        "cycles": CYCLES,
        "fixed_dn": DN,
        "replicates": args.replicates,
        "edge_cycles": args.edge_cycles,
        "target": "<= 5 % coarsest pair, <= 3 % finest pair (edge wear work, max depth, volume)",
    }
    for proj in args.projections.split(","):
        figures[f"projection_{proj}"] = grid_study(
            replace_nested(base, **{"contact.wear_projection": proj}),
            grids,
            args.replicates,
            args.edge_cycles,
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
            one[f"{floor:g}"] = one_cycle_edge_work(p, args.edge_cycles)
            long[f"{floor:g}"] = wear_at(
                p, replicates=args.replicates, edge_cycles=args.edge_cycles
            )
        figures[f"impact_velocity_floor_{nl}x{nd}"] = {
            "one_cycle_new_bore": one,
            "one_cycle_changes": _changes(one),
            "after_4e5_cycles": long,
            "after_4e5_changes": _changes(long),
        }
    write_results(args.name, figures)


if __name__ == "__main__":
    main()
