"""``jointwear sim``: command-line interface of :mod:`jointwear.sim` (a thin layer over the library)."""

from __future__ import annotations

import typer

from jointwear._cli import discover_commands

app = typer.Typer(
    help="Simulate the four-bar linkage (or the slider-crank, --base slider_crank) with a 3D "
    "clearance joint: dynamics, contact, wear.",
    no_args_is_help=True,
)
discover_commands(app, "jointwear.sim")
