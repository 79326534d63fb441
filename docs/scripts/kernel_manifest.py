"""(Re)write ``jointwear/_compile_manifest.py``: the numba kernels the command line calls, with the
argument types it calls them with, for the compile-once warm-up (:mod:`jointwear._compile`).

``python docs/scripts/kernel_manifest.py`` runs :data:`COMMANDS` (the full demo, which covers the
simulator, the verification study, the ensemble, the rig's footage and its tracking; a speckle
pair, its 2D correlation in both shape functions and its strain field) one after the other on an
empty ``NUMBA_CACHE_DIR`` with the warm-up off, and records through numba's ``numba:compile``
event every kernel compiled for a call from Python (the outermost compilations: a kernel that
another kernel calls is compiled with it), in every process (the demo's workers too), with its
argument types and the CPU seconds its compilation took here. It takes about five minutes of CPU.
Run it after adding a kernel or changing the types a command passes to one;
``tests/root/test_compile.py`` checks that every entry still names a kernel, and
``tests/reports/test_demo_pool.py`` that, after the warm-up, ``dic correlate`` compiles nothing.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
OUT = ROOT / "jointwear" / "_compile_manifest.py"

#: Commands run (in a scratch folder) to find the kernels; ``{tmp}`` is that folder.
COMMANDS = [
    ["demo", "--out", "{tmp}/demo"],
    ["datasets", "speckle", "{tmp}/pair", "--size", "256x256", "--field", "rigid"],
    [
        "dic",
        "correlate",
        "{tmp}/pair/reference.png",
        "{tmp}/pair/deformed.png",
        "--subset",
        "31",
        "--step",
        "8",
        "--out",
        "{tmp}/c1.nc",
    ],  # fmt: skip
    [
        "dic",
        "correlate",
        "{tmp}/pair/reference.png",
        "{tmp}/pair/deformed.png",
        "--shape",
        "quadratic",
        "--interpolation",
        "cubic",
        "--threads",
        "2",
        "--out",
        "{tmp}/c2.nc",
    ],  # fmt: skip
    [
        "dic",
        "field",
        "{tmp}/pair/reference.png",
        "{tmp}/pair/deformed.png",
        "--subset",
        "31",
        "--step",
        "16",
        "--out",
        "{tmp}/f.nc",
    ],  # fmt: skip
]

#: Loaded in every process of a recorded command (``sitecustomize``): writes one JSON line per
#: outermost compilation to the file ``JOINTWEAR_RECORD_KERNELS`` names.
LISTENER = """
import json, os, time
from numba.core import event

_depth = []


class _Record(event.Listener):
    def on_start(self, ev):
        _depth.append(time.process_time())

    def on_end(self, ev):
        start = _depth.pop()
        if _depth:
            return
        fn = ev.data["dispatcher"].py_func
        row = {"module": fn.__module__, "name": fn.__qualname__,
               "args": repr(tuple(ev.data["args"])), "cpu_s": time.process_time() - start}
        with open(os.environ["JOINTWEAR_RECORD_KERNELS"], "a") as fh:
            fh.write(json.dumps(row) + "\\n")


event.register("numba:compile", _Record())
"""

HEADER = '''"""The numba kernels the command line calls from Python, with their argument types: what the
compile-once warm-up (:mod:`jointwear._compile`) compiles. Written by
``docs/scripts/kernel_manifest.py`` (do not edit by hand); ``cpu_s`` is the CPU time each
compilation took when it was recorded ({when}), the warm-up's estimate of what is left.
"""

#: (module, function, argument types as numba writes them, CPU seconds when recorded)
KERNELS: tuple[tuple[str, str, str, float], ...] = (
'''


def record(folder: Path) -> list[dict]:
    """Run :data:`COMMANDS` on an empty kernel cache; the outermost compilations, in order."""
    site = folder / "site"
    site.mkdir()
    (site / "sitecustomize.py").write_text(LISTENER)
    rows = folder / "kernels.jsonl"
    env = {
        **os.environ,
        "PYTHONPATH": os.pathsep.join([str(site), os.environ.get("PYTHONPATH", "")]),
        "JOINTWEAR_RECORD_KERNELS": str(rows),
        "NUMBA_CACHE_DIR": str(folder / "cache"),
        "JOINTWEAR_WARM_UP": "0",
    }
    for command in COMMANDS:
        args = [a.replace("{tmp}", str(folder)) for a in command]
        t0 = time.perf_counter()
        run = subprocess.run([sys.executable, "-m", "jointwear", *args], env=env, cwd=folder)
        print(f"jointwear {' '.join(command)}: exit {run.returncode}, "
              f"{time.perf_counter() - t0:.0f} s", flush=True)  # fmt: skip
        if run.returncode not in (0, 1):  # the demo's synthetic data fail one criterion
            raise SystemExit(f"jointwear {' '.join(command)} failed")
    return [json.loads(line) for line in rows.read_text().splitlines()]


def write(rows: list[dict]) -> None:
    """The manifest module from the recorded rows (one entry per kernel and argument types)."""
    seen: dict[tuple[str, str, str], float] = {}
    for r in rows:
        key = (r["module"], r["name"], r["args"])
        seen[key] = max(seen.get(key, 0.0), r["cpu_s"])
    text = HEADER.format(when=time.strftime("%Y-%m-%d", time.gmtime()))
    for (module, name, args), cpu in sorted(seen.items()):
        text += f"    ({module!r}, {name!r}, {args!r}, {cpu:.1f}),\n"
    OUT.write_text(text + ")\n")
    subprocess.run(["ruff", "format", str(OUT)], check=False)
    print(f"{OUT}: {len(seen)} kernel signatures, {sum(seen.values()):.0f} CPU s when recorded")


def main() -> None:
    with tempfile.TemporaryDirectory() as tmp:
        write(record(Path(tmp)))


if __name__ == "__main__":
    main()
