"""How much the default verification study's u_num depends on the replicates' start phases.

Runs the default study of ``jointwear sim verify`` on the reference rig (``zhang2023``, 20 x 200,
4e5 cycles: ΔN = 5000 .. 40000, 4 replicates, 4 runs on the 40 x 400 grid) twice: with the
default start phases (0, 1, 2, 3 cycles) and with phases drawn from ``--seed`` (default 1), and
records per quantity value, u_num and its parts for both, their ratio, and each study's run
warnings (issue 41: the finest levels' "not converged" warnings, judged against the runs' own
rate noise).

Usage: ``python benchmarks/bench_verify_seeds.py [--cycles 4e5] [--workers 0] [--seed 1]``.
The machine is shared: the load average is recorded with the figures; CPU seconds are of this
process (``--workers 0`` runs every run in it).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _common import write_results  # noqa: E402
from bench_verify import quantity_table  # noqa: E402

from jointwear.sim import VerifySpec, verify_wear  # noqa: E402


def study(cycles: float, seed: int | None, workers: int) -> tuple[object, dict]:
    """One default study (with ``seed``: drawn phases) and its cost."""
    spec = VerifySpec.default(cycles, seed=seed)
    c0, t0 = time.process_time(), time.perf_counter()
    ds = verify_wear(None, spec=spec, workers=workers)
    cost = {"cpu_s": time.process_time() - c0, "wall_s": time.perf_counter() - t0}
    return ds, cost


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cycles", type=float, default=4e5)
    ap.add_argument("--workers", type=int, default=0)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--name", default="verify_seeds")
    args = ap.parse_args(argv)
    figures: dict[str, object] = {
        "rig": "zhang2023 (20 x 200 grid)",
        "cycles": args.cycles,
        "note": "the machine is shared (2 cores, several agents): CPU seconds of this process "
        "with --workers 0, wall time inflated by the load",
    }
    studies = {}
    for label, seed in (("phases_0123", None), (f"seed_{args.seed}", args.seed)):
        ds, cost = study(args.cycles, seed, args.workers)
        studies[label] = ds
        figures[f"{label}_cost"] = cost
        figures[f"{label}_phases"] = [float(v) for v in ds["initial_settle_cycles"].values]
        figures[f"{label}_run_warnings"] = {
            "summary": ds.attrs["run_warnings_summary"],
            "verdict": ds.attrs["run_warnings_verdict"],
            "convergence_warnings_per_level": [
                int(v)
                for v in ds["level_warning_count"].sel(warning_kind="convergence_warning").values
            ],
        }
        print(label, cost, ds.attrs["run_warnings_summary"], flush=True)
    (la, a_ds), (lb, b_ds) = studies.items()

    def row(q: str, a, b) -> dict:
        out = {}
        for label, fit in ((la, a), (lb, b)):
            out[label] = {
                "assessed": bool(fit.assessed),
                "value": fit.value,
                "u_num": fit.u_num,
                "u_stat": fit.u_stat,
                "u_refinement": fit.u_refinement,
                "u_grid": fit.u_grid,
                "branch": fit.branch if fit.assessed else f"not assessed: {fit.reason}",
            }
        if a.assessed and b.assessed and a.u_num > 0:
            out["u_num_ratio"] = b.u_num / a.u_num
            out["value_change_over_u_num"] = (b.value - a.value) / max(a.u_num, b.u_num)
        return out

    figures["quantities"] = quantity_table(a_ds, b_ds, row)
    write_results(args.name, figures)


if __name__ == "__main__":
    main()
