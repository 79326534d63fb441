"""First use after an install: what ``jointwear demo --quick`` compiles on an empty numba cache.

``python benchmarks/bench_first_compile.py`` runs the quick demo in a fresh process with
``NUMBA_CACHE_DIR`` pointing at an empty folder (a new install) and counts, through numba's
``numba:compile`` event (it fires on a cache miss only): the kernels compiled, their
compilations (a kernel compiled for several argument types counts once per type), the kernels
compiled more than once with their number of signatures (candidates for fewer
specialisations), and the kernels per package. CPU seconds (user + system of the process) and
wall seconds are recorded with the 1-minute load average before and after: the machine may be
shared, so compare CPU seconds, not wall time. Writes ``results/first_compile.json``.
"""

from __future__ import annotations

import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _common import write_results  # noqa: E402

#: Runs in the fresh process: the quick demo, with a listener on numba's compile event.
CHILD = """
import collections, json, sys
from numba.core import event

seen = collections.defaultdict(list)


class Listener(event.Listener):
    def on_start(self, ev):
        f = ev.data["dispatcher"].py_func
        seen[f"{f.__module__}.{f.__qualname__}"].append(str(ev.data["args"]))

    def on_end(self, ev):
        pass


event.register("numba:compile", Listener())
from jointwear.reports.demo import run_demo

run_demo(sys.argv[1], quick=True, workers=1)
print("COMPILED " + json.dumps(seen))
"""


def _package(name: str) -> str:
    parts = name.split(".")
    return ".".join(parts[:3] if parts[0] == "jointwear" else parts[:1])


def main() -> None:
    load_start = round(os.getloadavg()[0], 2)
    with tempfile.TemporaryDirectory() as tmp:
        env = {**os.environ, "NUMBA_CACHE_DIR": str(Path(tmp) / "cache")}
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.perf_counter()
        run = subprocess.run(
            [sys.executable, "-c", CHILD, str(Path(tmp) / "demo")],
            env=env,
            capture_output=True,
            text=True,
            check=True,
        )
        wall = time.perf_counter() - t0
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
    line = next(ln for ln in run.stdout.splitlines() if ln.startswith("COMPILED "))
    seen: dict[str, list[str]] = json.loads(line[len("COMPILED ") :])
    packages: dict[str, int] = {}
    for name in seen:
        packages[_package(name)] = packages.get(_package(name), 0) + 1
    figures = {
        "command": "jointwear demo --quick (run_demo quick=True, workers=1), empty NUMBA_CACHE_DIR",
        "kernels_compiled": len(seen),
        "compilations": sum(map(len, seen.values())),
        "kernels_with_several_signatures": {k: len(v) for k, v in seen.items() if len(v) > 1},
        "kernels_per_package": dict(sorted(packages.items(), key=lambda kv: -kv[1])),
        "cpu_s": round(after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime, 1),
        "wall_s": round(wall, 1),
        "load_average_1min": {"start": load_start, "end": round(os.getloadavg()[0], 2)},
    }
    write_results("first_compile", figures)


if __name__ == "__main__":
    main()
