"""The README gives exactly two set-up commands; CI runs the same test command."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def _setup_commands() -> list[str]:
    text = (ROOT / "README.md").read_text()
    block = re.search(r"```bash\n(.*?)```", text, re.S).group(1)
    return [line for line in block.splitlines() if line.strip() and not line.startswith("#")]


def test_two_setup_commands_demo_and_tests():
    cmds = _setup_commands()
    assert len(cmds) == 2
    assert cmds[0].endswith("jointwear demo")
    assert cmds[1].endswith("python -m pytest")


def test_ci_runs_the_readme_test_command():
    test_cmd = _setup_commands()[1].split("&&")[-1].strip()
    ci = (ROOT / ".ci" / "run").read_text()
    ci_cmds = [
        line.strip() for line in ci.splitlines() if line.strip().startswith("python -m pytest")
    ]
    assert ci_cmds == [test_cmd]
