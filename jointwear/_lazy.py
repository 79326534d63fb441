"""Import hooks of the start-up: :func:`after_import` prepares a heavy dependency when (and only
if) it is imported.

Subpackages serve their public names lazily with ``lazy_loader.attach_stub`` (their
``__init__.pyi`` lists every name; ``docs/scripts/lazy_stubs.py`` writes it).
:func:`lazy_api` is the former in-house loader's signature over ``lazy_loader.attach``, kept for
a package not yet given an ``_EXPORTS`` table and a stub; it reads the API modules' ``__all__``
from their source, so nothing is imported until a name is used.
"""

from __future__ import annotations

import ast
import importlib.abc
import importlib.machinery
import importlib.util
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import lazy_loader

__all__ = ["lazy_api", "after_import"]


def lazy_api(
    package: str, api_modules: Sequence[str]
) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """Return ``(__getattr__, __dir__)`` for ``package`` re-exporting ``api_modules``' ``__all__``
    (fully qualified module names), and set the package's ``__all__``."""
    attrs = {}
    for name in api_modules:
        spec = importlib.util.find_spec(name)
        tree = ast.parse(Path(spec.origin).read_text(encoding="utf-8"))
        names = next(
            ast.literal_eval(node.value)
            for node in tree.body
            if isinstance(node, ast.Assign) and getattr(node.targets[0], "id", "") == "__all__"
        )
        attrs[name.removeprefix(package + ".")] = list(names)
    getattr_, dir_, all_ = lazy_loader.attach(package, submod_attrs=attrs)
    sys.modules[package].__all__ = all_
    return getattr_, dir_


def after_import(name: str, callback: Callable[[], None]) -> None:
    """Run ``callback()`` right after the top-level module ``name`` has been imported.

    At once if it is imported already; otherwise from a one-shot import hook (nothing is
    imported here), so that start-up code can prepare a heavy dependency without loading it.
    """
    if name in sys.modules:
        callback()
        return
    sys.meta_path.insert(0, _AfterImport(name, callback))


class _AfterImport(importlib.abc.MetaPathFinder):
    """Runs a callback right after the module ``name`` itself has been imported, then leaves."""

    def __init__(self, name: str, callback: Callable[[], None]) -> None:
        self.name = name
        self.callback = callback

    def find_spec(self, name: str, path: Any, target: Any = None) -> Any:
        if name != self.name:
            return None
        sys.meta_path.remove(self)
        spec = importlib.machinery.PathFinder.find_spec(name, path)
        if spec is None or spec.loader is None:
            return spec
        loader = spec.loader
        exec_module = loader.exec_module
        callback = self.callback

        def exec_then_notify(module: Any) -> None:
            exec_module(module)
            callback()

        loader.exec_module = exec_then_notify  # type: ignore[method-assign]
        return spec
