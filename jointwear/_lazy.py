"""Import hooks of the start-up: :func:`after_import` prepares a heavy dependency when (and only
if) it is imported.

Subpackages serve their public names lazily with ``lazy_loader.attach_stub`` (their
``__init__.pyi`` lists every name; ``docs/scripts/lazy_stubs.py`` writes it).
"""

from __future__ import annotations

import importlib.abc
import importlib.machinery
import importlib.util
import sys
from collections.abc import Callable
from typing import Any

__all__ = ["after_import"]


def after_import(name: str, callback: Callable[[], None]) -> None:
    """Run ``callback()`` right after the top-level module ``name`` has been imported.

    At once if it is imported already; otherwise from a one-shot import hook (nothing is
    imported here), so that start-up code can prepare a heavy dependency without loading it.
    """
    if name in sys.modules:
        callback()
        return
    waiting = next(
        (f for f in sys.meta_path if isinstance(f, _AfterImport) and f.name == name), None
    )
    if waiting is not None:  # one hook per module (the first finder to answer is the only one)
        waiting.callbacks.append(callback)
        return
    sys.meta_path.insert(0, _AfterImport(name, callback))


class _AfterImport(importlib.abc.MetaPathFinder):
    """Runs callbacks right after the module ``name`` itself has been imported, then leaves."""

    def __init__(self, name: str, callback: Callable[[], None]) -> None:
        self.name = name
        self.callbacks = [callback]

    def find_spec(self, name: str, path: Any, target: Any = None) -> Any:
        # the hook leaves when the module is executed, not when it is found: a mere look-up
        # (importlib.util.find_spec) must not use it up
        if name != self.name:
            return None
        spec = importlib.machinery.PathFinder.find_spec(name, path)
        if spec is None or spec.loader is None:
            return spec
        loader = spec.loader
        exec_module = loader.exec_module

        def exec_then_notify(module: Any) -> None:
            exec_module(module)
            if self not in sys.meta_path:  # notified already
                return
            sys.meta_path.remove(self)
            for callback in self.callbacks:
                callback()

        loader.exec_module = exec_then_notify  # type: ignore[method-assign]
        return spec
