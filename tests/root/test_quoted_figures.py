"""Figures quoted in README.md and docs/*.md agree with benchmarks/results/*.json."""

from __future__ import annotations

import importlib.util
import json
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def _script():
    path = ROOT / "docs" / "scripts" / "quoted_figures.py"
    spec = importlib.util.spec_from_file_location("quoted_figures", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up there
    spec.loader.exec_module(module)
    return module


qf = _script()


def test_every_marked_figure_agrees_with_its_benchmark():
    figures = qf.check()
    bad = [f"{f.doc}:{f.line}: {f.source}: {f.problem}" for f in figures if not f.ok]
    assert not bad, "\n".join(bad)
    sources = {(f.doc, f.source) for f in figures}
    # the figures issue 24 found wrong stay tied to their results
    assert ("README.md", "compare_report.json:figures/demo_full/wall_s") in sources
    assert ("docs/sim.md", "sim_cycle.json:figures/cpu_per_step_ratio_40x400_to_20x200") in sources
    assert ("docs/compare-report.md", "compare_report.json:figures/demo_full/exit_code") in sources
    assert len(figures) >= 30


@pytest.fixture
def results(tmp_path):
    (tmp_path / "bench.json").write_text(
        json.dumps(
            {
                "figures": {
                    "ratio": 1.7067,
                    "runs": [0.1, 0.25],
                    "a.b c": 2.0,
                    "rigs": {
                        "slow": {"cpu_s": 27.7},
                        "mid": {"cpu_s": 20.5},
                        "fast": {"cpu_s": 8.2},
                    },
                    "metrics": [
                        {"quantity": "c_4e5", "metric": "S", "value": 5.88e-6},
                        {"quantity": "c_4e5 [z = 0, +z]", "metric": "S", "value": 22.11e-6},
                        {"quantity": "c_4e5 [z = 0, +z]", "metric": "U", "value": 1.0},
                        {"quantity": "c_12e6", "metric": "S", "value": 40.0e-6},
                    ],
                }
            }
        )
    )
    return tmp_path


def test_paths_indices_factors_and_keys_with_dots(results):
    text = (
        "250 ms <!-- fig: bench.json:figures/runs/1 *1e3 -->; "
        "2.0 <!-- fig: bench.json:figures/a.b c -->; 0.1 s <!-- fig: bench.json:figures/runs/0 -->"
    )
    assert [f.ok for f in qf.check_text(text, "doc.md", results)] == [True, True, True]


@pytest.mark.parametrize(
    ("text", "problem"),
    [
        ("1.71 <!-- fig: bench.json:figures/ratioo -->", "no numeric value"),
        ("1.71 <!-- fig: other.json:figures/ratio -->", "no file"),
        ("fast <!-- fig: bench.json:figures/ratio -->", "no number"),
        (
            "1.5 <!-- fig: bench.json:figures/ratio --> and 1.71 <!-- fig: bench.json:figures/ratio -->",
            "quoted 1.5",
        ),
    ],
)
def test_a_broken_marker_is_reported(results, text, problem):
    figures = qf.check_text(text, "doc.md", results)
    assert any(f.problem and problem in f.problem for f in figures), figures


_RATIO = "<!-- fig: bench.json:figures/ratio -->"


@pytest.mark.parametrize(
    ("text", "ok"),
    [
        *[
            (f"grows {q}× {_RATIO} per step", ok)
            for q, ok in [("1.71", 1), ("1.7", 1), ("2", 1), ("1.72", 0), ("1.70", 0), ("1.42", 0)]
        ],
        ("8 <!-- fig: bench.json:figures/rigs/*/cpu_s min -->", True),
        ("28 <!-- fig: bench.json:figures/rigs/*/cpu_s max -->", True),
        ("21 <!-- fig: bench.json:figures/rigs/(fast|mid)/cpu_s max -->", True),
        ("28 <!-- fig: bench.json:figures/rigs/(fast|mid)/cpu_s max -->", False),
        ("8.2 <!-- fig: bench.json:figures/rigs/(fast|mid)/cpu_s min -->", True),
        ("20.5 <!-- fig: bench.json:figures/rigs/(fast|mid)/cpu_s min -->", False),
        ("250 <!-- fig: bench.json:figures/runs/* max *1e3 -->", True),
        (
            "5.9 <!-- fig: bench.json:figures/metrics/[quantity^=c_4e5,metric=S]/value min *1e6 -->",
            True,
        ),
        (
            "22.1 <!-- fig: bench.json:figures/metrics/[quantity^=c_4e5,metric=S]/value max *1e6 -->",
            True,
        ),
        (
            "40.0 <!-- fig: bench.json:figures/metrics/[quantity^=c_4e5,metric=S]/value max *1e6 -->",
            False,
        ),
        ("5.9 <!-- fig: bench.json:figures/metrics/[quantity=c_4e5,metric=S]/value *1e6 -->", True),
    ],
)
def test_a_figure_agrees_only_within_its_rounding_and_with_the_end_it_names(results, text, ok):
    """Rounding: half a unit of the last digit shown. A range's end: the least or largest of
    the values the path selects."""
    (fig,) = qf.check_text(text, "doc.md", results)
    assert fig.ok is bool(ok), fig.problem


def test_each_end_of_a_range_has_its_own_marker(results):
    text = (
        "finish in 8 <!-- fig: bench.json:figures/rigs/*/cpu_s min -->–28 s"
        " <!-- fig: bench.json:figures/rigs/*/cpu_s max --> CPU"
    )
    figures = qf.check_text(text, "doc.md", results)
    assert [(f.quoted, f.ok) for f in figures] == [("8", True), ("28", True)]
    swapped = text.replace(" min -->", " MAX -->").replace(" max -->", " min -->")
    swapped = swapped.replace(" MAX -->", " max -->")
    assert [f.ok for f in qf.check_text(swapped, "doc.md", results)] == [False, False]


@pytest.mark.parametrize(
    ("text", "problem"),
    [
        ("8 <!-- fig: bench.json:figures/rigs/*/cpu_s -->", "names 3 values: add min or max"),
        ("1.71 <!-- fig: bench.json:figures/ratio max -->", "max of a path that names 1"),
        ("8 <!-- fig: bench.json:figures/rigs/(fast|none)/cpu_s min -->", "no numeric value"),
        ("8 <!-- fig: bench.json:figures/metrics/[metric=V]/value min -->", "names no value"),
        ("8 <!-- fig: bench.json:figures/metrics/[metric]/value min -->", "no numeric value"),
    ],
)
def test_a_selection_without_its_end_or_an_end_without_a_selection_is_reported(
    results, text, problem
):
    (fig,) = qf.check_text(text, "doc.md", results)
    assert fig.problem and problem in fig.problem, fig.problem
