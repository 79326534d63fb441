"""Lazy re-export of a subpackage's public API (PEP 562).

A subpackage's ``__init__`` re-exports the names listed in ``__all__`` of its ``_api*``
modules, but imports them only on first use, so that ``jointwear --help`` and the CLI groups
start without loading numba, scipy or xarray.
"""

from __future__ import annotations

import importlib
import sys
import types
from collections.abc import Callable, Sequence
from typing import Any

__all__ = ["lazy_api"]


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
