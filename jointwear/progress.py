"""Progress bars on stderr (rich), switched off when stderr is not a terminal."""

from __future__ import annotations

import sys
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager

from rich.console import Console
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    TextColumn,
    TimeElapsedColumn,
    TimeRemainingColumn,
)

__all__ = ["progress_bar", "run_counter", "stderr_console"]


def stderr_console() -> Console:
    """A rich console on stderr."""
    return Console(stderr=True)


@contextmanager
def progress_bar(
    description: str, total: float | None, *, enabled: bool | None = None
) -> Iterator[Progress]:
    """Context manager yielding ``(progress, task_id)``-style rich Progress on stderr.

    Usage::

        with progress_bar("cycles", total=n) as bar:
            task = bar.tasks[0].id
            bar.update(task, advance=1, description="cycles (dN=100)")

    Disabled (no output) when stderr is not a terminal, unless ``enabled`` is given.
    """
    if enabled is None:
        enabled = sys.stderr.isatty()
    progress = Progress(
        TextColumn("[progress.description]{task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeElapsedColumn(),
        TimeRemainingColumn(),
        console=stderr_console(),
        disable=not enabled,
        transient=False,
    )
    with progress:
        progress.add_task(description, total=total)
        yield progress


def run_counter(bar: Progress, label: str) -> Callable[[Mapping[str, int]], None]:
    """An ``on_progress`` callback of a sweep (``{"total", "done", "failed"}`` runs) for ``bar``.

    Shows ``"<label>: N ok, M failed"`` on the bar's first task.
    """
    task = bar.tasks[0].id

    def on_progress(s: Mapping[str, int]) -> None:
        bar.update(
            task,
            total=s["total"],
            completed=s["done"],
            description=f"{label}: {s['done'] - s['failed']} ok, {s['failed']} failed",
        )

    return on_progress
