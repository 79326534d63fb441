"""The size rules of docs/development.md, measured over the library.

``python docs/scripts/house_sizes.py`` prints the largest modules, the functions over 150 lines
and the folders with the most private modules; ``tests/root/test_house_sizes.py`` holds the
limits (a module at most 800 lines, at most 5 functions over 150 lines, at most 12 private
modules to a folder).
"""

from __future__ import annotations

import ast
import tomllib
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
FOLDERS = [
    folder
    for folder in tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"][
        "package-dir"
    ].values()
    if "/" not in folder
]

MODULE_LINES = 800
FUNCTION_LINES = 150
LONG_FUNCTIONS = 5
PRIVATE_PER_FOLDER = 12


@dataclass(frozen=True)
class Sizes:
    modules: list[tuple[int, str]]  # (lines, path), longest first
    functions: list[tuple[int, str]]  # (lines, path:name) over FUNCTION_LINES, longest first
    private: list[tuple[int, str]]  # (private modules, folder), most first


def library_files() -> list[Path]:
    return sorted(p for folder in FOLDERS for p in (ROOT / folder).rglob("*.py"))


def measure() -> Sizes:
    modules, functions, private = [], [], {}
    for path in library_files():
        rel = str(path.relative_to(ROOT))
        text = path.read_text(encoding="utf-8")
        modules.append((len(text.splitlines()), rel))
        for node in ast.walk(ast.parse(text, rel)):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                length = node.end_lineno - node.lineno + 1
                if length > FUNCTION_LINES:
                    functions.append((length, f"{rel}:{node.name}"))
        if path.name.startswith("_") and not path.name.startswith("__"):
            folder = str(path.parent.relative_to(ROOT))
            private[folder] = private.get(folder, 0) + 1
    return Sizes(
        sorted(modules, reverse=True),
        sorted(functions, reverse=True),
        sorted(((n, f) for f, n in private.items()), reverse=True),
    )


if __name__ == "__main__":
    sizes = measure()
    print("largest modules:", *(f"  {n:4d} {p}" for n, p in sizes.modules[:5]), sep="\n")
    print(f"functions over {FUNCTION_LINES} lines: {len(sizes.functions)}")
    for n, f in sizes.functions:
        print(f"  {n:4d} {f}")
    print(
        "most private modules in a folder:",
        *(f"  {n:4d} {f}" for n, f in sizes.private[:3]),
        sep="\n",
    )
