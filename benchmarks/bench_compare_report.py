"""Benchmark of jointwear.compare and jointwear.reports at the reference study's sizes.

Figures: wall and CPU time to align a simulated wear map (20 layers x 200 points, 3 snapshots) with an
instrument map (13 layers x 18000 points, other angle convention); time of the full comparison
(wear + motion: variable-step simulation vs 50 frames/s over 2 s); time to render the HTML
report (figures included) and its size; wall and CPU time of ``jointwear demo --quick`` and
of the full ``jointwear demo`` (in a subprocess, each the second run: warm numba cache), with the
time of each phase the demo announces, the CPU split between the demo's process and its worker
processes, and its outcome (criteria by state, exit code). Medians of repeated runs; the machine is shared, so
the load average is recorded with the figures. ``--quiet-load L``: before the full demo, wait
(at most ``--patience`` seconds) until the 1-minute load average is below ``L``.
"""

from __future__ import annotations

import os
import re
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "compare"))

import _jw_synth as syn  # noqa: E402
from _common import cpu_time, median_time, write_results  # noqa: E402

from jointwear.compare import align_wear_maps, compare  # noqa: E402
from jointwear.reports import build_report, render_html  # noqa: E402

#: A phase announcement of ``jointwear demo`` on stderr: ``[2/5] ...``.
PHASE = re.compile(r"\[(\d+)/\d+\] ")
#: What the demo says when it compiles the numba kernels (a cold cache): that run is repeated.
COMPILING = "compiling numerical kernels"
#: The demo's last line: CPU of its own process and of its worker processes.
CPU_LINE = re.compile(r"CPU: ([\d.]+) s in this process, ([\d.]+) s in worker processes")
#: ... and, where the system says it, the CPU of each worker process.
CPU_EACH = re.compile(r"in worker processes \(([\d., ]+) s each\)")
#: How many worker processes the demo ran its parts on.
WORKERS = re.compile(r"in (\d+) worker processes")


def demo_run(quick: bool) -> dict[str, object]:
    """One ``jointwear demo`` run in a subprocess: wall and CPU time [s], phases, outcome.

    CPU time is user + system of the process tree (``RUSAGE_CHILDREN``: the demo and every
    process it started and waited for); the 1-minute load average is recorded before and after,
    as the machine is shared. ``phases_s`` is the wall time from each announced phase
    (``[k/5]`` on stderr) to the next one (the last to the end of the run); ``criteria`` counts
    the decisions of the demo's ``metrics.nc`` by state. ``cpu_s_demo_process`` and
    ``cpu_s_worker_processes`` split the CPU time between the demo's own process (start, the
    comparison and the report) and its ``workers`` worker processes (the parts of phase 1);
    ``wall_s_idle_estimate`` is what the wall time would be on an idle machine with a core per
    worker: own CPU + the busiest worker's CPU (``cpu_s_each_worker``; even shares where the
    system does not say it) - an estimate, not a measurement: the machine is shared.
    """
    from jointwear.compare import load_comparison

    with tempfile.TemporaryDirectory() as tmp:
        args = [sys.executable, "-m", "jointwear", "demo", "--out", tmp]
        load_before = os.getloadavg()[0]
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.perf_counter()
        marks: list[tuple[str, float]] = []
        compiled = False
        cpu_split: tuple[float, float] | None = None
        each: list[float] = []
        workers = 1
        with subprocess.Popen(
            [*args, "--quick"] if quick else args,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            text=True,
        ) as proc:
            for line in proc.stderr:
                compiled = compiled or COMPILING in line
                if CPU_LINE.search(line):
                    cpu_split = tuple(float(v) for v in CPU_LINE.search(line).groups())
                if CPU_EACH.search(line):
                    each = [float(v) for v in CPU_EACH.search(line).group(1).split(",")]
                if WORKERS.search(line):
                    workers = int(WORKERS.search(line).group(1))
                found = PHASE.match(line)
                if found:
                    marks.append((found.group(1), time.perf_counter() - t0))
        code = proc.returncode
        wall = time.perf_counter() - t0
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        load_after = os.getloadavg()[0]
        metrics = Path(tmp) / "metrics.nc"
        states = (
            load_comparison(metrics).decisions["state"].value_counts().to_dict()
            if metrics.exists()
            else {}
        )
    ends = [t for _, t in marks[1:]] + [wall]
    phases = {k: round(end - start, 1) for (k, start), end in zip(marks, ends, strict=True)}
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    split = {}
    if cpu_split is not None:
        own, others = cpu_split
        split = {
            "cpu_s_demo_process": own,
            "cpu_s_worker_processes": others,
            "workers": workers,
            "cpu_s_each_worker": each,
            # the busiest worker sets the end of phase 1 (even shares if not known)
            "wall_s_idle_estimate": round(own + (max(each) if each else others / workers), 1),
        }
    return {
        "wall_s": round(wall, 1),
        "cpu_s": round(cpu, 1),
        **split,
        "exit_code": code,
        "phases_s": phases,
        "criteria": {str(k): int(v) for k, v in sorted(states.items())},
        "criteria_total": int(sum(states.values())),
        "load_average_1min_before": round(load_before, 2),
        "load_average_1min_after": round(load_after, 2),
        "compiled": compiled,
    }


def wait_for_quiet(load: float, patience_s: float) -> float:
    """Wait until the 1-minute load average is below ``load`` (at most ``patience_s``); the
    load average then (the demo's wall time means something only on a quiet machine)."""
    deadline = time.monotonic() + patience_s
    while os.getloadavg()[0] >= load and time.monotonic() < deadline:
        time.sleep(10)
    return os.getloadavg()[0]


def main() -> None:
    import argparse

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument(
        "--quiet-load",
        type=float,
        default=None,
        help="before the full demo, wait until the 1-minute load average is below this",
    )
    ap.add_argument("--patience", type=float, default=900.0, help="longest wait [s]")
    a = ap.parse_args()
    sim_w = syn.sim_wear(n_layers=20, n_points=200)
    meas_w = syn.meas_wear(n_points=18000, u=1e-6)
    sim_m = syn.sim_motion(duration=1.2)
    meas_m = syn.meas_motion(duration=2.0, u=0.002)
    t_align, _ = median_time(lambda: align_wear_maps(sim_w, meas_w), repeat=5)
    t_compare, _ = median_time(lambda: compare([sim_w, sim_m], [meas_w, meas_m]), repeat=5)
    result = compare([sim_w, sim_m], [meas_w, meas_m])
    t_render, _ = median_time(lambda: render_html(result, command="bench"), repeat=3)
    with tempfile.TemporaryDirectory() as tmp:
        path = build_report(result, Path(tmp) / "r.html", command="bench")
        size = path.stat().st_size
        t_pdf, _ = median_time(
            lambda: build_report(
                result, Path(tmp) / "r2.html", command="bench", pdf=Path(tmp) / "r.pdf"
            ),
            repeat=3,
        )
    cpu = {
        "align_wear_maps_cpu_s": round(cpu_time(lambda: align_wear_maps(sim_w, meas_w)), 4),
        "render_html_report_cpu_s": round(cpu_time(lambda: render_html(result, command="b")), 3),
    }
    # the figures are of a warm run (numba kernels cached): a run that announced compiling them
    # is repeated, with a fresh output folder
    demos = {}
    for name, quick in (("demo_quick", True), ("demo_full", False)):
        if a.quiet_load is not None and not quick:
            wait_for_quiet(a.quiet_load, a.patience)
        run = demo_run(quick)
        demos[name] = demo_run(quick) if run.pop("compiled") else run
    write_results(
        "compare_report",
        {
            **cpu,
            **demos,
            "align_wear_maps_20x200_vs_13x18000_s": round(t_align, 4),
            "compare_wear_and_motion_s": round(t_compare, 4),
            "render_html_report_s": round(t_render, 3),
            "html_and_pdf_report_s": round(t_pdf, 3),
            "html_report_bytes": size,
            "sizes": {
                "sim_wear": "3 snapshots x 20 layers x 200 points",
                "measured_wear": "13 layers x 18000 points",
                "sim_motion_samples": int(sim_m.sizes["time"]),
                "measured_motion_frames": int(meas_m.sizes["time"]),
            },
        },
    )


if __name__ == "__main__":
    main()
