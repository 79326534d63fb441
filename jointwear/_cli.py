"""Helpers shared by the CLI groups."""

from __future__ import annotations

import importlib
import pkgutil
from typing import Any

import typer
from typer.core import TyperGroup

__all__ = ["discover_commands", "CommandGroup"]


class CommandGroup(TyperGroup):
    """A group whose callback is the command itself (``jointwear compare A B``): while it has
    no sub-commands its usage line shows no ``COMMAND [ARGS]...``."""

    def collect_usage_pieces(self, ctx: Any) -> list[str]:
        # (Click itself is not imported: Typer >= 0.26 vendors it and no longer installs it)
        pieces = super().collect_usage_pieces(ctx)
        if not self.commands and pieces and pieces[-1] == self.subcommand_metavar:
            pieces = pieces[:-1]
        return pieces


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
