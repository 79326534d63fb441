"""``jointwear compare``: command-line interface of :mod:`jointwear.compare` (a thin layer over the library)."""

from __future__ import annotations

import typer

from jointwear._cli import CommandGroup, discover_commands

app = typer.Typer(
    help="Compare simulation and measurement on a common grid.",
    no_args_is_help=True,
    cls=CommandGroup,
)
discover_commands(app, "jointwear.compare")
