"""Every module imports on its own, first thing in a fresh interpreter (no circular imports)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

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


def test_each_module_imports_first_in_a_fresh_interpreter():
    modules = _modules()
    assert len(modules) > 40
    # one interpreter per module, a few at a time
    failures = []
    batch = 4
    for i in range(0, len(modules), batch):
        procs = [
            (
                m,
                subprocess.Popen(
                    [sys.executable, "-c", f"import {m}"],
                    stdout=subprocess.PIPE,
                    stderr=subprocess.PIPE,
                    text=True,
                ),
            )
            for m in modules[i : i + batch]
        ]
        for m, p in procs:
            _, err = p.communicate(timeout=120)
            if p.returncode != 0:
                failures.append(
                    f"{m}: {err.strip().splitlines()[-1] if err.strip() else p.returncode}"
                )
    assert not failures, "\n".join(failures)
