"""Cost of the default verification study and the stability of its u_num (issue 21).

Runs ``jointwear sim verify`` of the reference rig (``zhang2023``, 20 x 200 grid) at 4e5 cycles
with its default study (ΔN = 5000, 10000, 20000, 40000; 4 replicates each; 4 runs on the
40 x 400 grid) on a local dask cluster of 2 worker processes and records its wall time (target
<= 5 min on 2 cores). Then the same study with the replicates doubled (8 per level, 8 grid runs):
u_num is stable when doubling the replicates changes it by less than its own uncertainty, the
standard deviation of u_num over bootstrap resamples of the replicates (within each level and
of the grid runs) of the default study.

Usage: ``python benchmarks/bench_verify.py [--cycles 4e5] [--workers 2] [--resamples 100]``.
The machine is shared: the load average at the start is recorded with the figures.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _common import write_results  # noqa: E402

from jointwear.refinement import study_uncertainty  # noqa: E402
from jointwear.sim import VerifySpec, verify_wear  # noqa: E402


def bootstrap_sd(study, quantity: str, resamples: int, seed: int = 0) -> float:
    """Standard deviation of u_num over bootstrap resamples of the replicates."""
    rng = np.random.default_rng(seed)
    base = study.copy(deep=True)
    rv = study["replicate_value"].values
    gv = study["grid_replicate_value"].values
    nrep, ng = rv.shape[-1], gv.shape[-1]
    out = []
    for _ in range(resamples):
        idx = rng.integers(0, nrep, size=(rv.shape[1], nrep))
        base["replicate_value"].values[:] = np.take_along_axis(rv, idx[None, :, :], axis=-1)
        base["grid_replicate_value"].values[:] = gv[:, rng.integers(0, ng, size=ng)]
        fit = study_uncertainty(base, quantity)
        out.append(fit.u_num)
    out = np.asarray(out, dtype=float)
    out = out[np.isfinite(out)]
    return float(np.std(out, ddof=1)) if out.size > 2 else float("nan")


def quantity_table(a_study, b_study, row: Callable[[str, Any, Any], dict]) -> dict[str, dict]:
    """Per quantity of ``a_study``: its units and ``row(quantity, a, b)`` of the two studies'
    :func:`study_uncertainty` fits (``a`` of ``a_study``, ``b`` of ``b_study``), each row
    printed as it is made."""
    table = {}
    for q in (str(v) for v in a_study["quantity"].values):
        a, b = study_uncertainty(a_study, q), study_uncertainty(b_study, q)
        table[q] = {"units": str(a_study["quantity_units"].sel(quantity=q).values), **row(q, a, b)}
        print(q, table[q], flush=True)
    return table


def run(
    cycles: float, replicates: int, workers: int, folder: Path, reuse: bool
) -> tuple[object, dict]:
    """The study and its cost (wall time [s], CPU seconds of each worker); with ``reuse`` an
    earlier one kept in ``folder``."""
    from jointwear import io

    out = folder / f"study_r{replicates}.nc"
    timing = out.with_suffix(".wall_s.json")
    if reuse and out.exists() and timing.exists():
        return io.load(out), json.loads(timing.read_text())
    spec = VerifySpec.default(cycles, replicates=replicates, grid_replicates=replicates)
    with _cluster(workers) as (address, worker_cpu):
        t0 = time.perf_counter()
        ds = verify_wear(None, spec=spec, scheduler=address, out=out, resume=out.exists())
        wall = time.perf_counter() - t0
        cpu = worker_cpu()
    record = {
        "wall_s": wall,
        "worker_cpu_s": cpu,
        "runs_computed_now": ds.attrs["runs_computed_now"],
    }
    timing.write_text(json.dumps(record))
    return ds, record


@contextlib.contextmanager
def _cluster(workers: int):
    """A local cluster as ``jointwear sim verify --workers N`` starts one (same environment),
    and a function giving the CPU seconds each worker process has used since it started."""
    from jointwear.sim.sweep._exec import _client

    client, cluster, _ = _client(workers, None)

    def cpu() -> dict[str, float]:
        used = client.run(lambda: sum(os.times()[:2]))
        return {str(k): float(v) for k, v in used.items()}

    try:
        yield cluster.scheduler_address, cpu
    finally:
        client.close()
        cluster.close()


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cycles", type=float, default=4e5)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--resamples", type=int, default=100)
    ap.add_argument("--name", default="verify")
    ap.add_argument("--folder", type=Path, help="keep the study files here (default: temporary)")
    ap.add_argument(
        "--reuse", action="store_true", help="take finished studies (and their times) from --folder"
    )
    args = ap.parse_args(argv)
    default = VerifySpec.default(args.cycles)
    figures: dict[str, object] = {
        "rig": "zhang2023 (20 x 200 grid)",
        "cycles": args.cycles,
        "workers": args.workers,
        "default_study": default.describe(),
        "target": "default study <= 300 s on 2 cores; |u_num(2R) - u_num(R)| < sd_bootstrap(u_num(R))",
        "note": "the machine is shared: wall times are inflated by the load; the CPU seconds of "
        "each worker process (worker_cpu_s) give the idle-machine wall time",
    }
    with tempfile.TemporaryDirectory() as tmp:
        folder = args.folder or Path(tmp)
        folder.mkdir(parents=True, exist_ok=True)
        if args.reuse:
            figures["reused"] = (
                "studies and their costs taken from earlier runs kept in --folder (their time "
                "and load are in default_cost / doubled_cost and the studies' history); the "
                "machine record below is of this rewrite"
            )
        ds1, c1 = run(args.cycles, default.replicates, args.workers, folder, args.reuse)
        figures["default_cost"] = c1
        figures["default_runs"] = int(ds1.attrs["n_runs"])
        figures["default_ok"] = int(ds1.attrs["n_ok"])
        cpu = list(c1.get("worker_cpu_s", {}).values())
        if cpu:
            # on an idle machine each worker has a core: the wall time is the busiest worker's CPU
            figures["default_wall_s_estimated_idle"] = max(cpu)
        print(f"default study: {c1}", flush=True)
        ds2, c2 = run(args.cycles, 2 * default.replicates, args.workers, folder, args.reuse)
        figures["doubled_cost"] = c2
        figures["doubled_ok"] = int(ds2.attrs["n_ok"])

        def row(q: str, a, b) -> dict:
            out = {
                "value_R": a.value,
                "value_2R": b.value,
                "u_num_R": a.u_num,
                "u_num_2R": b.u_num,
                "u_stat_R": a.u_stat,
                "u_refinement_R": a.u_refinement,
                "u_grid_R": a.u_grid,
                "branch_R": a.branch if a.assessed else f"not assessed: {a.reason}",
                "branch_2R": b.branch if b.assessed else f"not assessed: {b.reason}",
            }
            if a.assessed and b.assessed:
                sd = bootstrap_sd(ds1, q, args.resamples)
                out["u_num_R_bootstrap_sd"] = sd
                out["change"] = b.u_num - a.u_num
                out["stable"] = bool(abs(b.u_num - a.u_num) < sd)
            return out

        figures["quantities"] = quantity_table(ds1, ds2, row)
    write_results(args.name, figures)


if __name__ == "__main__":
    main()
