"""Keep xarray from importing dask, dask.distributed and pint for plain NumPy data.

xarray asks "is this a dask array / a pint quantity?" by importing the module: building any
DataArray imports ``dask.array`` and ``pint`` when they are installed (both are jointwear
dependencies), and every ``to_netcdf`` asks dask which scheduler is active, which imports
``distributed`` (tornado, ...): together about 0.5-1 s of CPU at every command's start, for
data that holds none of them.

The answers do not need the imports: no object can be a ``dask.array.Array`` or a
``pint.Quantity`` while that module has not been imported, and no dask scheduler can be set
while ``dask`` has not been imported. :func:`install` (run once, right after xarray is
imported, from :mod:`jointwear`) makes xarray answer so until the module is imported, and
hands over to xarray's own answer from then on. Only xarray internals that exist are touched;
on a version without them nothing changes (slower, never wrong).
"""

from __future__ import annotations

import sys
from typing import Any

__all__ = ["install"]

#: xarray's duck-array modules that jointwear never needs to import: module -> the module
#: whose presence in ``sys.modules`` decides (the duck type lives there)
_DUCK_MODULES = {"dask": "dask.array", "pint": "pint"}


class _UntilImported:
    """Stands in for xarray's ``DuckArrayModule(mod)`` while ``mod`` is not imported.

    ``type`` is empty (nothing can be an instance of a class never imported); any other
    attribute, or ``type`` once the module is imported, is xarray's own (and replaces this
    entry in xarray's cache).
    """

    def __init__(self, mod: str, probe: str, cache: dict, factory: Any) -> None:
        self._mod, self._probe, self._cache, self._factory = mod, probe, cache, factory

    def _real(self) -> Any:
        real = self._factory(self._mod)
        self._cache[self._mod] = real
        return real

    @property
    def type(self) -> tuple:
        if self._probe not in sys.modules:
            return ()
        return self._real().type

    def __getattr__(self, name: str) -> Any:
        return getattr(self._real(), name)


def _scheduler_unless_dask_imported(original: Any) -> Any:
    def get_dask_scheduler(get: Any = None, collection: Any = None) -> str | None:
        if "dask" not in sys.modules:  # no scheduler can have been set up
            return None
        return original(get, collection)

    get_dask_scheduler.__wrapped__ = original  # type: ignore[attr-defined]
    return get_dask_scheduler


def _collection_unless_dask_imported(original: Any) -> Any:
    def is_dask_collection(x: object) -> bool:
        # dask's own test starts with this attribute; the rest needs dask, which a dask
        # collection defined elsewhere (xarray's own objects) does not
        if not hasattr(x, "__dask_graph__"):
            return False
        return original(x)

    is_dask_collection.__wrapped__ = original  # type: ignore[attr-defined]
    return is_dask_collection


def _wrap(module_names: tuple[str, ...], name: str, wrapper: Any) -> None:
    for module_name in module_names:
        module = sys.modules.get(module_name)  # all imported by ``import xarray``
        original = getattr(module, name, None)
        if original is not None and not hasattr(original, "__wrapped__"):
            setattr(module, name, wrapper(original))


def install() -> None:
    """Patch the imported xarray (idempotent; a no-op where its internals differ)."""
    try:
        from xarray.namedarray import pycompat
    except ImportError:  # pragma: no cover - other xarray layout
        pycompat = None
    cache = getattr(pycompat, "_cached_duck_array_modules", None)
    factory = getattr(pycompat, "DuckArrayModule", None)
    if isinstance(cache, dict) and factory is not None:
        for mod, probe in _DUCK_MODULES.items():
            if mod not in cache and probe not in sys.modules:
                cache[mod] = _UntilImported(mod, probe, cache, factory)
    _wrap(
        ("xarray.backends.locks", "xarray.backends.writers", "xarray.backends.api"),
        "get_dask_scheduler",
        _scheduler_unless_dask_imported,
    )
    _wrap(
        ("xarray.namedarray.utils", "xarray.core.utils"),
        "is_dask_collection",
        _collection_unless_dask_imported,
    )
