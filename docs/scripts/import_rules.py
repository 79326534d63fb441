"""List the library's imports that break the house rules on public faces and layering.

``python docs/scripts/import_rules.py`` prints every import (module level or inside a function)
of the library that

- reaches a private module or name (a path component or imported name starting with ``_``)
  of another top-level package (``cross-package``; the root package ``jointwear`` is the
  project's shared base and is exempt),
- reaches a private module or name of a sibling subpackage within one package (``sibling``:
  ``jointwear.dic.field`` using ``jointwear.dic.footage._video``); a package re-exporting its
  own subpackages' private modules (``jointwear.dic`` from ``jointwear.dic.icgn._solve``) and a
  module using its own folder's are the intended uses and are not listed,
- runs against the layering rule of docs/development.md (``layering``: a package importing one
  it may not, or the library importing a command-line module).

``tests/root/test_import_rules.py`` holds the counts (0 cross-package, 0 layering, at most 10
sibling) so that a new violation fails.
"""

from __future__ import annotations

import ast
import tomllib
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

#: top-level folder -> import package (pyproject's package-dir)
FOLDERS = {
    folder: package
    for package, folder in tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"][
        "setuptools"
    ]["package-dir"].items()
    if "/" not in folder
}

#: top-level package -> the packages it may import (besides itself and the root), from
#: docs/development.md "Who may import whom"
MAY_IMPORT = {
    "jointwear": set(),
    "sim": set(),
    "dic": set(),
    "metrology": set(),
    "compare": set(),
    "datasets": {"sim", "dic", "metrology", "compare"},
    "reports": {"compare", "sim", "dic", "metrology", "datasets"},
}


#: what ``sim`` may use of ``metrology``: its form assessment (the cylindricity of a simulated bore
#: is assessed as a measured one's), by module or by public name
SIM_USES_FORM = tuple(
    f"jointwear.metrology.{name}"
    for name in ("form", "cylindricity", "cylinder_zone", "roundness", "circle_zone")
)


@dataclass(frozen=True)
class Violation:
    kind: str  # "cross-package", "sibling" or "layering"
    path: str  # file, relative to the repository
    line: int
    importer: str  # module name
    target: str  # what is imported: module or module.name

    def __str__(self) -> str:
        return f"{self.kind:13} {self.path}:{self.line}  {self.importer} -> {self.target}"


def _module_name(path: Path) -> tuple[str, bool]:
    """The import name of a library file, and whether it is a package's ``__init__``."""
    rel = path.relative_to(ROOT)
    parts = [FOLDERS[rel.parts[0]], *rel.parts[1:]]
    parts[-1] = parts[-1].removesuffix(".py")
    is_init = parts[-1] == "__init__"
    if is_init:
        parts.pop()
    return ".".join(parts).replace("/", "."), is_init


def _top(name: str) -> str:
    """The top-level package (folder name) of a ``jointwear.*`` module name."""
    parts = name.split(".")
    return parts[1] if len(parts) > 1 and parts[1] in FOLDERS else "jointwear"


def _is_cli(name: str) -> bool:
    """Whether a module name is (or lies in) a command-line module: ``cli``, ``cli_*``, ``_cli*``
    or ``__main__``."""
    return any(
        part in ("cli", "__main__") or part.startswith(("cli_", "_cli"))
        for part in name.split(".")[1:]
    )


#: the application shell: it registers every command group and may import anything
SHELL = {"jointwear.cli", "jointwear.__main__", "jointwear.cli_import"}


def _targets(node: ast.AST, module: str, is_init: bool) -> list[str]:
    """Fully qualified targets of an import node: modules, or ``module.name`` for names."""
    if isinstance(node, ast.Import):
        return [a.name for a in node.names]
    assert isinstance(node, ast.ImportFrom)
    if node.level:
        package = module if is_init else module.rsplit(".", 1)[0]
        for _ in range(node.level - 1):
            package = package.rsplit(".", 1)[0]
        base = f"{package}.{node.module}" if node.module else package
    else:
        base = node.module or ""
    return [f"{base}.{a.name}" for a in node.names if a.name != "*"] or [base]


def _private_owner(target: str) -> str | None:
    """The package whose private module or name ``target`` is, or None if it is public."""
    parts = target.split(".")
    for i, part in enumerate(parts):
        if part.startswith("_") and not part.startswith("__"):
            return ".".join(parts[:i])
    return None


def _within(name: str, package: str) -> bool:
    return name == package or name.startswith(package + ".")


def check_file(path: Path) -> list[Violation]:
    module, is_init = _module_name(path)
    package = module if is_init else module.rsplit(".", 1)[0]
    top = _top(module)
    rel = str(path.relative_to(ROOT))
    found = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if not isinstance(node, ast.Import | ast.ImportFrom):
            continue
        for target in _targets(node, module, is_init):
            if not target.startswith("jointwear"):
                continue
            other = _top(target)
            kind = None
            if module in SHELL:
                pass
            elif top == "sim" and any(_within(target, form) for form in SIM_USES_FORM):
                pass
            elif other not in (top, "jointwear") and other not in MAY_IMPORT[top]:
                kind = "layering"
            elif _is_cli(target) and not _is_cli(module):
                kind = "layering"  # the library importing the command line
            else:
                owner = _private_owner(target)
                if owner is not None and not (_within(package, owner) or _within(owner, package)):
                    if other != top:
                        kind = None if other == "jointwear" else "cross-package"
                    else:
                        kind = "sibling"
            if kind:
                found.append(Violation(kind, rel, node.lineno, module, target))
    return found


def library_files() -> list[Path]:
    return sorted(p for folder in FOLDERS for p in (ROOT / folder).rglob("*.py"))


def violations() -> list[Violation]:
    return [v for path in library_files() for v in check_file(path)]


if __name__ == "__main__":
    from collections import Counter

    found = violations()
    for v in found:
        print(v)
    print(dict(Counter(v.kind for v in found)))
