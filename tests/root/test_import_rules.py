"""Public faces and layering (docs/development.md): no import reaches another package's private
module or name, at most a few reach a sibling subpackage's, and none runs against the layering
rule. The checker is ``docs/scripts/import_rules.py`` (run it to list the offending imports)."""

from __future__ import annotations

import importlib.util
import sys
import textwrap
from collections import Counter
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
_spec = importlib.util.spec_from_file_location(
    "import_rules", ROOT / "docs/scripts/import_rules.py"
)
rules = importlib.util.module_from_spec(_spec)
sys.modules[_spec.name] = rules  # dataclasses look their module up there
_spec.loader.exec_module(rules)

#: import statements allowed per kind (lower these as imports are fixed; never raise them)
ALLOWED = {"cross-package": 0, "layering": 0, "sibling": 2}


def test_no_new_import_of_private_names_or_against_the_layering():
    found = rules.violations()
    statements = Counter(kind for kind, *_ in {(v.kind, v.path, v.line) for v in found})
    listing = "\n".join(str(v) for v in found)
    for kind, allowed in ALLOWED.items():
        assert statements[kind] <= allowed, f"{kind}: {statements[kind]} > {allowed}\n{listing}"


@pytest.mark.parametrize(
    ("where", "code", "kind"),
    [
        # a sibling subpackage's private module and a private name of a public module
        ("dic/field/_x.py", "from jointwear.dic.footage._video import open_frames", "sibling"),
        ("dic/field/_x.py", "from jointwear.dic.footage.video import _natural_key", "sibling"),
        # inside a function counts too; another package's private module
        (
            "reports/x.py",
            "def f():\n    from jointwear.sim.sweep._run import evaluate_run",
            "cross-package",
        ),
        # a package it may not import, and the library importing the command line
        ("datasets/x.py", "from jointwear.reports.demo_studies import ENSEMBLE_INPUTS", "layering"),
        ("compare/x.py", "import jointwear.sim", "layering"),
        ("sim/x.py", "from jointwear.metrology.readers import read_scan", "layering"),
        ("jointwear/x.py", "from jointwear.metrology.readers.table import sniff", "layering"),
        ("sim/x.py", "from jointwear.dic._cli_options import CORRELATION", "layering"),
        ("sim/x.py", "from jointwear._cli import Overwrite", "layering"),
    ],
)
def test_the_checker_finds_each_kind(tmp_path, monkeypatch, where, code, kind):
    path = tmp_path / where
    path.parent.mkdir(parents=True)
    path.write_text(textwrap.dedent(code) + "\n")
    monkeypatch.setattr(rules, "ROOT", tmp_path)
    assert [v.kind for v in rules.check_file(path)] == [kind]


@pytest.mark.parametrize(
    ("where", "code"),
    [
        ("dic/__init__.py", "from jointwear.dic.icgn._solve import solve"),  # a parent's re-export
        ("dic/icgn/_drive.py", "from jointwear.dic.icgn._solve import solve"),  # own folder
        ("dic/icgn/_drive.py", "from ._solve import solve"),
        ("sim/x.py", "from jointwear._netcdf import Record"),  # the root is the shared base
        ("sim/x.py", "from jointwear.metrology import cylindricity"),  # the form assessment
        ("reports/x.py", "from jointwear.compare import compare"),  # a public face
        ("sim/cli_x.py", "from jointwear._cli import Overwrite"),  # a CLI module
        ("jointwear/cli.py", "from jointwear.reports.demo import run_demo"),  # the shell
    ],
)
def test_the_checker_passes_the_intended_uses(tmp_path, monkeypatch, where, code):
    path = tmp_path / where
    path.parent.mkdir(parents=True)
    path.write_text(code + "\n")
    monkeypatch.setattr(rules, "ROOT", tmp_path)
    assert rules.check_file(path) == []
