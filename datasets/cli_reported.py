"""``jointwear datasets reported``: the reference study's reported measurements as a TOML file."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from jointwear._cli import Overwrite


def register(app: typer.Typer) -> None:
    """Add ``reported`` to the ``jointwear datasets`` group."""

    @app.command("reported")
    def reported_cmd(
        out: Annotated[Path, typer.Argument(help="TOML file to write.")],
        overwrite: Overwrite = False,
    ) -> None:
        """Write the reference study's reported values (Zhang et al. 2023) as a reported-measurement file."""
        from jointwear import io
        from jointwear.datasets.reference_study import reference_file

        text = reference_file().read_text(encoding="utf-8")
        with io.atomic_path(out) as tmp:
            tmp.write_text(text, encoding="utf-8")
        typer.echo(f"wrote {out}: edit it or pass it to 'jointwear import reported'")
