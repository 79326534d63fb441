"""``jointwear metrology``: command-line interface of :mod:`jointwear.metrology` (a thin layer over the library)."""

from __future__ import annotations

import typer

from jointwear._cli import discover_commands

app = typer.Typer(
    help="Import roundness/cylindricity scans, assess form (ISO), compute wear maps.",
    no_args_is_help=True,
)
discover_commands(app, "jointwear.metrology")
