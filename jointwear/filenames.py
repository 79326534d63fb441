"""File names the readers share: glob patterns and the natural order of numbered files.

A path whose name holds a glob character (``*``, ``?``, ``[``) and that is not itself a file
is a pattern (``images/*_0.tif``); numbered files sort by the value of their digit groups
(``frame_2.png`` before ``frame_10.png``). Light (no numpy), for the command line too.
"""

from __future__ import annotations

import re
from pathlib import Path

__all__ = ["GLOB_CHARS", "natural_key"]

#: the characters that make a file name a glob pattern
GLOB_CHARS = re.compile(r"[*?\[]")


def natural_key(path: Path) -> list[int | str]:
    """Sort key of ``path`` by its name, digit groups compared as numbers.

    Examples
    --------
    >>> from pathlib import Path
    >>> sorted([Path("f_10.png"), Path("f_2.png")], key=natural_key)
    [PosixPath('f_2.png'), PosixPath('f_10.png')]
    """
    return [int(s) if s.isdigit() else s for s in re.split(r"(\d+)", path.name)]
