"""``jointwear dic``: command-line interface of :mod:`jointwear.dic` (a thin layer over the library)."""

from __future__ import annotations

import typer

from jointwear._cli import discover_commands

app = typer.Typer(
    help="Digital image correlation: 2D subset DIC, stereo calibration, footage tracking.",
    no_args_is_help=True,
)
discover_commands(app, "jointwear.dic")
