"""Shared helpers for benchmark scripts: machine description and writing results."""

from __future__ import annotations

import json
import os
import platform
import statistics
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

RESULTS = Path(__file__).resolve().parent / "results"


def _load_average() -> float | None:
    try:
        return os.getloadavg()[0]
    except OSError:
        return None


#: the 1-minute load average when the benchmark started (this module is imported first)
_LOAD_AT_START = _load_average()


def machine() -> dict[str, Any]:
    """Describe the machine the figures were measured on."""
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as fh:
            for line in fh:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return {
        "cpu": cpu,
        "cores": os.cpu_count(),
        "python": platform.python_version(),
        "platform": platform.platform(),
        "load_average_1min_at_start": _LOAD_AT_START,
        "load_average_1min_at_end": _load_average(),
    }


def _times(
    fn: Callable[[], Any], clock: Callable[[], float], repeat: int, warmup: int
) -> list[float]:
    """``clock`` time of each of ``repeat`` runs of ``fn()`` after ``warmup`` runs [s]."""
    for _ in range(warmup):
        fn()
    times = []
    for _ in range(repeat):
        t0 = clock()
        fn()
        times.append(clock() - t0)
    return times


def median_time(
    fn: Callable[[], Any], *, repeat: int = 5, warmup: int = 1
) -> tuple[float, list[float]]:
    """Median wall time of ``fn()`` over ``repeat`` runs after ``warmup`` runs [s]."""
    times = _times(fn, time.perf_counter, repeat, warmup)
    return statistics.median(times), times


def cpu_time(fn: Callable[[], Any], *, repeat: int = 3, warmup: int = 0) -> float:
    """Median CPU time of ``fn()`` in this process over ``repeat`` runs after ``warmup`` runs
    [s] (less sensitive to a shared machine than wall time)."""
    return statistics.median(_times(fn, time.process_time, repeat, warmup))


def write_results(name: str, figures: dict[str, Any]) -> Path:
    """Print ``figures`` and write them with the machine description to results/<name>.json."""
    RESULTS.mkdir(parents=True, exist_ok=True)
    record = {
        "benchmark": name,
        "measured": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
        "machine": machine(),
        "figures": figures,
    }
    path = RESULTS / f"{name}.json"
    tmp = path.with_suffix(".json.tmp")
    tmp.write_text(json.dumps(record, indent=2, sort_keys=True, default=str) + "\n")
    os.replace(tmp, path)
    print(json.dumps(record, indent=2, sort_keys=True, default=str))
    return path
