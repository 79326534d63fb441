"""Every module imports on its own, first thing in a fresh interpreter (no circular imports)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PACKAGES = {
    "sim": "jointwear.sim",
    "dic": "jointwear.dic",
    "metrology": "jointwear.metrology",
    "compare": "jointwear.compare",
    "reports": "jointwear.reports",
    "datasets": "jointwear.datasets",
    "jointwear": "jointwear",
}


def _modules() -> list[str]:
    names = []
    for folder, package in PACKAGES.items():
        for path in sorted((ROOT / folder).rglob("*.py")):
            rel = path.relative_to(ROOT / folder).with_suffix("")
            parts = [p for p in rel.parts if p != "__init__"]
            if parts and parts[-1] == "__main__":
                continue
            names.append(".".join([package, *parts]))
    return names


#: Imports each module named on stdin first thing in a forked copy of an interpreter that has
#: imported only the third-party libraries jointwear's modules use (numba excepted: the CLI hooks
#: its import), never a jointwear module; prints one line per module that fails.
FORKER = r"""
import importlib
import os
import sys

SKIP = ("jointwear", "numba", "llvmlite", "__main__", "__mp_main__")


def fork(job):
    r, w = os.pipe()
    pid = os.fork()
    if pid == 0:
        os.close(r)
        try:
            said = job() or ""
            code = 0
        except BaseException as exc:
            said, code = f"{type(exc).__name__}: {exc}", 1
        os.write(w, said.encode()[:200000])
        os._exit(code)
    os.close(w)
    return pid, r


def wait(pid, r):
    with os.fdopen(r) as f:
        said = f.read()
    return os.waitpid(pid, 0)[1], said


def import_all():
    before = set(sys.modules)
    for m in modules:
        try:
            importlib.import_module(m)
        except BaseException:
            pass
    return "\n".join(n for n in sys.modules if n not in before)


modules = sys.stdin.read().split()
status, found = wait(*fork(import_all))
for name in found.split():
    top = name.split(".")[0]
    if top in SKIP or top in sys.stdlib_module_names or top.startswith("_"):
        continue
    try:
        importlib.import_module(name)
    except BaseException:
        pass
assert not any(n.split(".")[0] in SKIP[:3] for n in sys.modules), "jointwear preloaded"
running = []
for m in [*modules, None]:
    if m is not None:
        running.append((m, *fork(lambda m=m: importlib.import_module(m) and None)))
    while running and (m is None or len(running) >= 2):
        name, pid, r = running.pop(0)
        status, said = wait(pid, r)
        if status:
            print(f"{name}: {said or status}")
"""


def _failures(modules: list[str]) -> list[str]:
    run = subprocess.run(
        [sys.executable, "-c", FORKER],
        input="\n".join(modules),
        capture_output=True,
        text=True,
        timeout=600,
        cwd=ROOT,
    )
    assert run.returncode == 0, run.stderr[-2000:]
    return run.stdout.splitlines()


@pytest.mark.skipif(not hasattr(os, "fork"), reason="needs fork")
def test_each_module_imports_first_in_a_fresh_interpreter():
    """Forked from one interpreter with the third-party libraries loaded (5x less CPU than an
    interpreter per module): what is checked, jointwear's own import order, starts empty."""
    modules = _modules()
    assert len(modules) > 40
    failures = _failures(modules)
    assert not failures, "\n".join(failures)


@pytest.mark.skipif(not hasattr(os, "fork"), reason="needs fork")
def test_a_circular_import_is_found(tmp_path, monkeypatch):
    """The check can fail: two modules that import each other's names at import time."""
    pkg = tmp_path / "circ"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    (pkg / "a.py").write_text("from circ.b import B\nA = 1\n")
    (pkg / "b.py").write_text("from circ.a import A\nB = 2\n")
    monkeypatch.setenv(
        "PYTHONPATH", os.pathsep.join([str(tmp_path), os.environ.get("PYTHONPATH", "")])
    )
    failures = _failures(["circ.a", "circ.b", "json"])
    assert [f.split(":")[0] for f in failures] == ["circ.a", "circ.b"]
    assert "ImportError" in failures[0] and "circular" in failures[0]
