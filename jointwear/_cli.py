"""Helpers shared by the CLI groups."""

from __future__ import annotations

import importlib
import pkgutil

import typer

__all__ = ["discover_commands"]


def discover_commands(app: typer.Typer, package: str) -> None:
    """Let every module ``<package>.cli_*`` add its commands to ``app``.

    Each such module defines ``register(app: typer.Typer) -> None`` and keeps heavy imports
    inside the command functions, so ``jointwear --help`` stays fast.
    """
    pkg = importlib.import_module(package)
    names = sorted(m.name for m in pkgutil.iter_modules(pkg.__path__) if m.name.startswith("cli_"))
    for name in names:
        module = importlib.import_module(f"{package}.{name}")
        module.register(app)
