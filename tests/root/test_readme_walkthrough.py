"""The README's walk-through runs as written, in a fresh folder, one console block after another.

Every ``$ ...`` line of the README's ``console`` blocks (with ``\\`` continuations) is run by the
shell in one temporary folder, in order, with the ``jointwear`` of this environment; each must
exit 0 (``compare`` and ``report`` may exit 1: a failed criterion is their verdict, as the README
says), and every file a command is told to write (``--out``, ``--table``, ``--csv``, ``--plot``,
``--figure``) must exist afterwards. A
block whose commands need inputs that no earlier block creates fails here, which is the point: a
reader following the README meets the same error.
"""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def readme_commands(text: str) -> list[str]:
    """The shell commands of the ``console`` blocks, continuations joined, comments dropped."""
    commands: list[str] = []
    for block in re.findall(r"```console\n(.*?)```", text, re.S):
        pending = ""
        for line in block.splitlines():
            if pending:
                pending += " " + line.strip()
            elif line.startswith("$ "):
                pending = line[2:].strip()
            else:
                continue  # output shown in the block
            if pending.endswith("\\"):
                pending = pending[:-1].rstrip()
                continue
            commands.append(_strip_comment(pending))
            pending = ""
    return commands


def _strip_comment(command: str) -> str:
    """Cut a shell comment (`` #`` outside quotes) off a command line."""
    quote = ""
    for k, char in enumerate(command):
        if quote:
            quote = "" if char == quote else quote
        elif char in "'\"":
            quote = char
        elif char == "#" and (k == 0 or command[k - 1].isspace()):
            return command[:k].rstrip()
    return command


def _outputs(command: str) -> list[str]:
    words = shlex.split(command)
    flags = ("--out", "-o", "--table", "--csv", "--plot", "--figure")
    return [words[i + 1] for i, w in enumerate(words[:-1]) if w in flags]


#: commands whose exit 1 is a verdict (a validation criterion failed), not a failure
VERDICT_COMMANDS = ("jointwear compare", "jointwear report")


def test_commands_are_extracted_with_continuations_and_comments():
    text = "```console\n$ a --x 1 \\\n      --out f.nc   # note\nshown output\n$ b 'p*#q'\n```\n"
    assert readme_commands(text) == ["a --x 1 --out f.nc", "b 'p*#q'"]


def test_readme_walkthrough_runs_as_written(tmp_path):
    commands = readme_commands((ROOT / "README.md").read_text(encoding="utf-8"))
    assert commands, "the README has no console blocks"
    env = dict(os.environ)
    env["PATH"] = f"{Path(sys.executable).parent}{os.pathsep}{env.get('PATH', '')}"
    env.setdefault("MPLBACKEND", "Agg")
    for command in commands:
        assert command.split()[0] == "jointwear", f"README command is not jointwear: {command}"
        done = subprocess.run(
            ["bash", "-c", command],
            cwd=tmp_path,
            env=env,
            capture_output=True,
            text=True,
            timeout=900,
            stdin=subprocess.DEVNULL,
        )
        allowed = (0, 1) if command.startswith(VERDICT_COMMANDS) else (0,)
        if done.returncode not in allowed:
            pytest.fail(
                f"README command failed (exit {done.returncode}): {command}\n"
                f"stdout:\n{done.stdout[-2000:]}\nstderr:\n{done.stderr[-3000:]}"
            )
        for out in _outputs(command):
            assert (tmp_path / out).exists(), f"{command!r} did not write {out}"
