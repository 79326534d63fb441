"""The ``Examples`` of the main entry points run as doctests: what a newcomer copies works.

Each example checks its result against a truth it states (Archard's law, an exact sub-pixel
shift, the generator's grid, a comparison built to fail), so a wrong answer fails here.
"""

from __future__ import annotations

import doctest
import importlib
import tempfile

import pytest

ENTRY_POINTS = {
    "simulate_wear": "jointwear.sim.wear._loop",
    "run_sweep": "jointwear.sim.sweep._driver",
    "read_scan": "jointwear.metrology.readers.scan",
    "correlate": "jointwear.dic._api2d",
    "measure_field": "jointwear.dic.field._measure",
    "compare": "jointwear.compare.comparison",
    "build_report": "jointwear.reports.builder",
}


@pytest.mark.parametrize("name", list(ENTRY_POINTS))
def test_examples_run(name, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))  # files the examples write
    obj = getattr(importlib.import_module(ENTRY_POINTS[name]), name)
    tests = doctest.DocTestFinder(recurse=False).find(obj, name, globs={})
    assert tests and tests[0].examples, f"{name}: no Examples section"
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    for test in tests:
        runner.run(test)
    result = runner.summarize(verbose=False)
    assert result.failed == 0, f"{name}: {result.failed} of {result.attempted} examples failed"


def test_a_wrong_example_fails():
    # the harness can fail: an example whose stated output is wrong
    def shift():
        """
        >>> 1.3 + 0.1
        1.5
        """

    (test,) = doctest.DocTestFinder().find(shift, "shift", globs={})
    runner = doctest.DocTestRunner()
    runner.run(test, out=lambda text: None)
    assert runner.summarize(verbose=False).failed == 1
