"""The ruff configuration bans importing the top-level folders bare (``import sim``)."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.skipif(shutil.which("ruff") is None, reason="ruff is part of the test extra")
def test_bare_top_level_imports_are_banned(tmp_path):
    bad = tmp_path / "bad.py"
    bad.write_text("import sim\nfrom dic import correlate\nimport jointwear.sim\n")
    res = subprocess.run(
        ["ruff", "check", "--config", str(ROOT / "pyproject.toml"), "--select", "TID251", str(bad)],
        capture_output=True,
        text=True,
        check=False,
    )
    assert res.returncode == 1
    assert res.stdout.count("TID251") == 2  # `import sim` and `from dic ...`, not jointwear.sim
    assert "import jointwear.sim, never the bare top-level folder" in res.stdout
