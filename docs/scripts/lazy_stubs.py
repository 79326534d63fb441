"""(Re)write the ``__init__.pyi`` stub of every package whose public names ``lazy_loader`` serves.

``python docs/scripts/lazy_stubs.py`` (``--check`` lists the stubs that are out of date and exits
1). Such a package's ``__init__.py`` declares what it exports in ``_EXPORTS`` (module, relative
to the package -> ``None`` for the names in that module's ``__all__``, or a tuple of names,
in which ``"*"`` stands for that ``__all__``) and
calls ``lazy_loader.attach_stub(__name__, __file__)``, which reads the stub at import time and
imports a name's module on first use (the script imports the listed modules to read their
``__all__``; the package's own ``__init__`` only reads its stub). The stub lists every public name explicitly, as
``from .<module> import <name> as <name>`` (an explicit re-export for type checkers, PEP 484),
pointing at the module that defines it (followed through one ``from ... import`` of the listed
module, so that ``jointwear.sim.run_cycles`` loads ``sim.dynamics``, not everything
``_api_dynamics`` gathers). ``tests/root/test_lazy_api.py`` checks each stub against this.
"""

from __future__ import annotations

import ast
import importlib
import subprocess
import sys
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


CONFIG = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]


def _folder(package: str) -> Path:
    """A package's folder, from pyproject's ``package-dir`` (nothing is imported: a stub out of
    date must not stop its package from being rewritten)."""
    dirs = CONFIG["package-dir"]
    base = max((p for p in dirs if package == p or package.startswith(p + ".")), key=len)
    return ROOT / dirs[base] / Path(*package[len(base) :].split(".")[1:])


def _exports(init: Path) -> dict[str, tuple[str, ...] | None] | None:
    """The ``_EXPORTS`` literal of a package's ``__init__.py``, or None if it has none."""
    for node in ast.parse(init.read_text()).body:
        if isinstance(node, ast.Assign) and [getattr(t, "id", "") for t in node.targets] == [
            "_EXPORTS"
        ]:
            value = ast.literal_eval(node.value)
            return {m: None if n is None else tuple(n) for m, n in value.items()}
    return None


def _names(package: str, module: str, wanted: tuple[str, ...] | None) -> dict[str, str]:
    """Public name -> module (relative to ``package``, dotted) the stub imports it from.

    The listing module, so that a name moved between private modules stays served; except a
    name that is also a submodule's (the function ``assess`` of the module ``assess``): it is
    taken from the module that defines it, where lazy_loader keeps the import system from
    replacing the function by the module (a function's or class's own module, else the module
    the listing module imports it from, by name or by a star-import of its ``__all__``)."""
    listing = importlib.import_module(f"{package}.{module}")
    names = [n for w in wanted or ("*",) for n in (listing.__all__ if w == "*" else [w])]
    imported, stars = {}, []
    for node in ast.parse(Path(listing.__file__).read_text()).body:
        if isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            for alias in node.names:
                if alias.name == "*":
                    stars.append(node.module)
                elif alias.asname in (None, alias.name):
                    imported[alias.name] = node.module
    where = {}
    folder = _folder(package)
    for name in names:
        obj = getattr(listing, name)
        if not ((folder / f"{name}.py").exists() or (folder / name).is_dir()):
            where[name] = module
            continue
        candidates = [
            getattr(obj, "__module__", None) if callable(obj) else None,
            imported.get(name),
            *(m for m in stars if name in importlib.import_module(m).__all__),
        ]
        origin = next(
            (
                c
                for c in candidates
                if c
                and c.startswith(package + ".")
                and getattr(importlib.import_module(c), name, None) is obj
            ),
            f"{package}.{module}",
        )
        where[name] = origin.removeprefix(package + ".")
    return where


def stub_text(package: str, exports: dict[str, tuple[str, ...] | None]) -> str:
    """The ``__init__.pyi`` of ``package`` exporting ``exports`` (see the module docstring)."""
    where: dict[str, str] = {}
    # names listed one by one come after whole modules' __all__: an entry that names an object
    # the package exports already says where to load it from (a lighter module than the list)
    for module, wanted in sorted(exports.items(), key=lambda kv: kv[1] is not None):
        for name, origin in _names(package, module, wanted).items():
            if name in where and (
                wanted is None
                or getattr(importlib.import_module(f"{package}.{origin}"), name)
                is not getattr(importlib.import_module(f"{package}.{where[name]}"), name)
            ):
                raise ValueError(f"{package}: {name} exported twice")
            where[name] = origin
    return _format(package, where)


def _listed(stub: Path) -> dict[str, str]:
    """Name -> module of an existing stub (empty if there is none)."""
    if not stub.exists():
        return {}
    return {
        alias.name: node.module
        for node in ast.parse(stub.read_text()).body
        if isinstance(node, ast.ImportFrom) and node.module
        for alias in node.names
    }


def _format(package: str, where: dict[str, str]) -> str:
    by_module: dict[str, list[str]] = {}
    for name, origin in where.items():
        by_module.setdefault(origin, []).append(name)
    lines = [
        f'"""Public names of {package}, loaded on first use: ``lazy_loader.attach_stub`` reads',
        "this stub at import time, type checkers and editors read it instead of the package.",
        "",
        "Generated by ``python docs/scripts/lazy_stubs.py`` from ``_EXPORTS`` in ``__init__.py``;",
        'do not edit."""',
        "",
    ]
    for origin in sorted(by_module):
        names = sorted(by_module[origin], key=lambda n: (n.lower(), n))
        lines.append(f"from .{origin} import (")
        lines.extend(f"    {name} as {name}," for name in names)
        lines.append(")")
    return "\n".join(lines) + "\n"


def lazy_packages() -> dict[str, Path]:
    """Package name -> its ``__init__.py``, for every package of pyproject.toml with ``_EXPORTS``."""
    found = {}
    for name in CONFIG["packages"]:
        init = _folder(name) / "__init__.py"
        if _exports(init) is not None:
            found[name] = init
    return found


def _ruff(text: str, stub: Path) -> str:
    """``text`` as ruff formats it (CI checks the format; the imports are sorted here, one block
    per module, which ruff's isort would split into one statement per ``as`` name)."""
    for args in (["format"],):
        out = subprocess.run(
            [sys.executable, "-m", "ruff", *args, "--stdin-filename", str(stub), "-"],
            input=text,
            capture_output=True,
            text=True,
            check=True,
            cwd=ROOT,
        )
        text = out.stdout
    return text


def write_stubs(check: bool = False) -> list[Path]:
    """Write (or with ``check``, compare) every stub; return the ones that changed."""
    changed = []
    packages = lazy_packages()
    before = {
        n: i.with_suffix(".pyi").read_text() if i.with_suffix(".pyi").exists() else None
        for n, i in packages.items()
    }
    if not check:
        # lazy_loader reads the stubs when the listing modules are imported below: first serve
        # what the stubs served and every name _EXPORTS lists one by one (no import needed)
        for name, init in packages.items():
            stub = init.with_suffix(".pyi")
            where = _listed(stub)
            for module, wanted in _exports(init).items():
                where.update({n: module for n in wanted or () if n != "*"})
            stub.write_text(_format(name, where))
    # subpackages first: a package's listing modules may use its subpackages' new names
    for name, init in sorted(packages.items(), key=lambda kv: -kv[0].count(".")):
        stub = init.with_suffix(".pyi")
        text = _ruff(stub_text(name, _exports(init)), stub)
        if before[name] != text:
            changed.append(stub)
        if not check:
            stub.write_text(text)
    return changed


if __name__ == "__main__":
    check = "--check" in sys.argv[1:]
    stale = write_stubs(check=check)
    for path in stale:
        print(path)
    sys.exit(1 if check and stale else 0)
