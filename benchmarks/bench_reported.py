"""The reference study's reported measurements decided against the default rig, at full size.

Runs :func:`jointwear.datasets.reference_study.run_reference_study` with
:data:`~jointwear.datasets.reference_study.FULL` (the study's 20 x 200 grid, a verification
study over the wear-update interval dN = 1e5, 5e4, 2.5e4 and a 10-member Latin-hypercube
ensemble over kw, the bore radius and friction) and writes every decision - state, value,
reason - and every metric of the reported quantities to ``results/reported.json``, with the
wall and CPU time of the run. docs/compare-report.md quotes the verdicts from that file.

    python benchmarks/bench_reported.py [--out DIR]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _common import write_results  # noqa: E402

from jointwear.compare.outcome import card_lines  # noqa: E402
from jointwear.datasets.reference_study import FULL, run_reference_study  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=None, help="keep the files in this folder")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        out = args.out or Path(tmp)
        t0, c0 = time.perf_counter(), time.process_time()
        result = run_reference_study(out, FULL, say=lambda s: print(s, flush=True))
        wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    for line in card_lines(result):
        print(line)
    decisions = [
        {k: (str(v) if k != "passed" else bool(v)) for k, v in row.items()}
        for row in result.decisions.to_dict("records")
    ]
    metrics = [{**row, "value": float(row["value"])} for row in result.metrics.to_dict("records")]
    write_results(
        "reported",
        {
            "size": {
                "layers": FULL.layers,
                "points": FULL.points,
                "verification_dn": list(FULL.levels),
                "ensemble_runs": FULL.ensemble_runs,
                "ensemble_dn": FULL.ensemble_dn,
            },
            "summary": result.summary(),
            "notes": list(result.notes),
            "decisions": decisions,
            "metrics": metrics,
            "wall_s": round(wall, 1),
            "cpu_s_main_process": round(cpu, 1),
        },
    )


if __name__ == "__main__":
    main()
