"""What the demo and its docs say agree with what it does (#37)."""

from __future__ import annotations

import re
from pathlib import Path

from jointwear.reports.demo import PHASES

ROOT = Path(__file__).resolve().parents[2]
NUMBERS = ("zero", "one", "two", "three", "four", "five", "six", "seven", "eight", "nine")


def test_the_docs_count_the_demos_phases():
    said = 0
    for doc in ("README.md", "docs/compare-report.md"):
        text = (ROOT / doc).read_text(encoding="utf-8")
        # "[1/2]" markers: every one out of the demo's number of phases
        for _, total in re.findall(r"\[(\d)/(\d)\]", text):
            assert int(total) == PHASES, f"{doc}: [k/{total}], the demo has {PHASES} phases"
            said += 1
        # "in five announced phases", "runs in two phases"
        for word in re.findall(r"\b(\w+) (?:announced )?phases\b", text):
            if word.lower() in NUMBERS:
                assert NUMBERS.index(word.lower()) == PHASES, f"{doc}: {word} phases"
                said += 1
    assert said >= 2  # the docs do say it
