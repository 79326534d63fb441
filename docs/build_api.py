"""Build the API reference (HTML) from the numpydoc docstrings with pdoc.

Usage: ``python docs/build_api.py [OUT_DIR]`` (default ``build/api``); open ``OUT_DIR/index.html``.
CI builds it through ``tests/root/test_api_reference.py``.
"""

from __future__ import annotations

import sys
from pathlib import Path

#: The public packages, in the order the reference lists them.
PACKAGES = (
    "jointwear",
    "jointwear.sim",
    "jointwear.dic",
    "jointwear.metrology",
    "jointwear.compare",
    "jointwear.reports",
    "jointwear.datasets",
)


def build(out: Path) -> Path:
    """Write the reference for :data:`PACKAGES` into ``out``; return its ``index.html``."""
    import pdoc
    import pdoc.render

    pdoc.render.configure(docformat="numpy", show_source=False, search=True)
    pdoc.pdoc(*PACKAGES, output_directory=out)
    return out / "index.html"


if __name__ == "__main__":
    target = Path(sys.argv[1]) if len(sys.argv) > 1 else Path("build/api")
    print(build(target))
