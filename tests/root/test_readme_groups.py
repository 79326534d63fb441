"""README names exactly the command groups the command line registers."""

from __future__ import annotations

import re
from pathlib import Path

from jointwear.cli import GROUPS

ROOT = Path(__file__).resolve().parents[2]

_WORDS = {"seven": 7, "eight": 8, "six": 6}


def test_readme_lists_every_command_group():
    text = " ".join((ROOT / "README.md").read_text(encoding="utf-8").split())
    match = re.search(r"lists the (\w+) command groups \(([^)]*)\)", text)
    assert match, "README: 'jointwear --help lists the N command groups (...)' not found"
    listed = re.findall(r"`([\w-]+)`", match.group(2))
    assert listed == list(GROUPS)
    assert _WORDS[match.group(1)] == len(GROUPS)


def test_readme_gives_the_api_reference_command():
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    assert "python docs/build_api.py build/api" in text
    assert (ROOT / "docs" / "build_api.py").is_file()
