"""Fixtures of the metrology tests."""

from __future__ import annotations

import pytest


@pytest.fixture
def run_import():
    """``jointwear metrology import PATH --out OUT [extra]`` with the instrument convention
    (default +x, counterclockwise); returns the exit code."""
    from jointwear.cli import main

    def run(path, out, *extra, zero="+x", direction="counterclockwise") -> int:
        args = ["metrology", "import", str(path), "--out", str(out)]
        return main([*args, "--angle-zero", zero, "--angle-direction", direction, *extra])

    return run
