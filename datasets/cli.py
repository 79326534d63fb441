"""``jointwear datasets``: command-line interface of :mod:`jointwear.datasets` (a thin layer over the library)."""

from __future__ import annotations

import typer

from jointwear._cli import discover_commands

app = typer.Typer(help="Sample data and generators with ground truth.", no_args_is_help=True)
discover_commands(app, "jointwear.datasets")
