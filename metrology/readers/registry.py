"""The reader of each preset, found by name (one registry, like pvlib's ``iotools``).

Every instrument family has one module under ``metrology/readers/`` with one reading function
taking ``(paths, *, convention, **options)`` and returning the contract Dataset; its name and
``"module:function"`` are listed once, in :data:`jointwear.metrology.choices.READERS` (light, so
the command line offers the names without importing a reader). :func:`reader_for` imports the
function when it is used; :func:`register` adds a preset at run time (a plug-in, a test).
"""

from __future__ import annotations

import importlib
from collections.abc import Callable

from jointwear.errors import BadInputError
from jointwear.metrology.choices import READERS

__all__ = ["reader_for", "register", "presets"]


def presets() -> dict[str, str]:
    """{preset name: what it reads} of every registered reader."""
    return {name: doc for name, (_, doc) in READERS.items()}


def reader_for(preset: str) -> Callable:
    """The reading function of ``preset`` (imported on first use).

    Raises
    ------
    BadInputError
        An unknown preset (the message lists the known ones).
    """
    if preset not in READERS:
        raise BadInputError(
            f"preset {preset!r} is not known; use one of {', '.join(READERS)} (--preset)"
        )
    if preset in _FUNCTIONS:
        return _FUNCTIONS[preset]
    module, _, name = READERS[preset][0].partition(":")
    return getattr(importlib.import_module(module), name)


def register(name: str, target: str | Callable, description: str) -> None:
    """Register a reader under ``name``.

    Parameters
    ----------
    name : str
        Preset name (``--preset NAME`` for a reader registered before the command line is
        built, ``import_scans(preset=NAME)`` always).
    target : str or callable
        ``"module:function"``, or the function itself (taking ``(paths, *, convention,
        **options)`` and returning a contract Dataset).
    description : str
        What it reads, for the help.
    """
    if not callable(target) and ":" not in str(target):
        raise BadInputError(f"reader {target!r} must be 'module:function' or a function")
    if callable(target):
        _FUNCTIONS[name] = target
        target = f"{target.__module__}:{target.__qualname__}"
    else:
        _FUNCTIONS.pop(name, None)
    READERS[name] = (str(target), description)


#: Readers registered as function objects (a local function cannot be imported by name).
_FUNCTIONS: dict[str, Callable] = {}
