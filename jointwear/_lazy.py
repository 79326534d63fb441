"""Lazy re-export of a subpackage's public API (PEP 562).

A subpackage's ``__init__`` re-exports the names listed in ``__all__`` of its ``_api*``
modules, but imports them only on first use, so that ``jointwear --help`` and the CLI groups
start without loading numba, scipy or xarray.
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.machinery
import sys
import types
from collections.abc import Callable, Sequence
from typing import Any

__all__ = ["lazy_api", "after_import", "stub_text"]


def lazy_api(
    package: str, api_modules: Sequence[str]
) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """Return ``(__getattr__, __dir__)`` for ``package`` re-exporting ``api_modules``.

    Parameters
    ----------
    package : str
        The subpackage's ``__name__``.
    api_modules : sequence of str
        Fully qualified names of the modules whose ``__all__`` is the public API.
    """

    def _load() -> dict[str, Any]:
        # Import the API modules and bind every public name in the package namespace, as a
        # star-import would. Binding after the imports matters: importing a submodule sets a
        # package attribute of the same name (e.g. module ``assess`` vs function ``assess``),
        # and the public function must win.
        modules = [importlib.import_module(name) for name in api_modules]
        names = [n for m in modules for n in m.__all__]
        public = {n: getattr(m, n) for m in modules for n in m.__all__}
        namespace = vars(sys.modules[package])
        namespace.update(public)
        namespace["__all__"] = names
        return namespace

    loading = False

    def __getattr__(name: str) -> Any:
        # Private names are submodules (``from jointwear.dic import _api2d``): answering
        # AttributeError lets the import system load them without pulling in the whole API,
        # and so does any lookup made while the API modules themselves are being imported.
        nonlocal loading
        if (name == "__all__" or not name.startswith("_")) and not loading:
            loading = True
            try:
                namespace = _load()
            finally:
                loading = False
            if name in namespace:
                return namespace[name]
        raise AttributeError(f"module {package!r} has no attribute {name!r}")

    def __dir__() -> list[str]:
        return sorted(set(__getattr__("__all__")))

    # The import system binds a freshly imported submodule on its package with ``setattr``
    # (``import jointwear.metrology.assess`` sets ``jointwear.metrology.assess`` to the module).
    # When the submodule exports a public name equal to its own name, bind that object
    # instead, so that ``from jointwear.metrology import assess`` gives the function whatever
    # was imported first.
    sys.modules[package].__class__ = _ShadowingModule
    return __getattr__, __dir__


class _ShadowingModule(types.ModuleType):
    """A package whose public names win over same-named submodules bound by the import system."""

    def __setattr__(self, name: str, value: Any) -> None:
        if (
            isinstance(value, types.ModuleType)
            and not name.startswith("_")
            and value.__name__ == f"{self.__name__}.{name}"
            # the module's own __all__ only: a lazy subpackage computes its __all__ on first
            # use, and binding it must not load it
            and name in vars(value).get("__all__", ())
        ):
            value = getattr(value, name)
        super().__setattr__(name, value)


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


def stub_text(package: str, api_modules: Sequence[str]) -> str:
    """The ``__init__.pyi`` of a package built with :func:`lazy_api`: one star-import per API
    module, which in a stub re-exports exactly that module's ``__all__`` (PEP 484), so that type
    checkers and editors see what ``__getattr__`` serves (``tests/root/test_lazy_api.py`` checks
    every stub against its package)."""
    lines = [
        f'"""Static view of {package}\'s lazily loaded public API (generated by',
        '``jointwear._lazy.stub_text``; do not edit)."""',
        "",
        "# In a stub, a star-import re-exports exactly the names in the module's __all__.",
        *(f"from {name} import *  # noqa: F403" for name in sorted(api_modules)),
        "",
    ]
    return "\n".join(lines)
