"""``jointwear report``: command-line interface of :mod:`jointwear.reports`."""

from __future__ import annotations

import typer

from jointwear._cli import CommandGroup, discover_commands

app = typer.Typer(
    help="Build validation reports (HTML with figures).", no_args_is_help=True, cls=CommandGroup
)
discover_commands(app, "jointwear.reports")
