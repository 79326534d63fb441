"""The size rules of docs/development.md hold: modules at most 800 lines, at most 5 functions
over 150 lines, at most 12 private modules to a folder (``docs/scripts/house_sizes.py``)."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
_spec = importlib.util.spec_from_file_location("house_sizes", ROOT / "docs/scripts/house_sizes.py")
sizes = importlib.util.module_from_spec(_spec)
sys.modules[_spec.name] = sizes  # dataclasses look their module up there
_spec.loader.exec_module(sizes)


@pytest.fixture(scope="module")
def measured():
    return sizes.measure()


def test_no_module_over_800_lines(measured):
    over = [(n, p) for n, p in measured.modules if n > sizes.MODULE_LINES]
    assert not over, f"modules over {sizes.MODULE_LINES} lines: {over}"


def test_at_most_five_functions_over_150_lines(measured):
    assert len(measured.functions) <= sizes.LONG_FUNCTIONS, measured.functions


def test_at_most_twelve_private_modules_to_a_folder(measured):
    over = [(n, f) for n, f in measured.private if n > sizes.PRIVATE_PER_FOLDER]
    assert not over, over


def test_the_measures_count_what_they_say(tmp_path, monkeypatch):
    pkg = tmp_path / "sim"
    pkg.mkdir()
    body = "\n".join(f"    x{i} = {i}" for i in range(151))
    (pkg / "_long.py").write_text(f"def f():\n{body}\n\n\ndef g():\n    pass\n")
    (pkg / "__init__.py").write_text("")
    monkeypatch.setattr(sizes, "ROOT", tmp_path)
    monkeypatch.setattr(sizes, "FOLDERS", ["sim"])
    got = sizes.measure()
    assert got.functions == [(152, "sim/_long.py:f")]  # the def line and 151 statements
    assert got.modules[0] == (156, "sim/_long.py")
    assert got.private == [(1, "sim")]  # __init__ is not a private module
