"""(Re)write the ``__init__.pyi`` stub of every package that uses ``jointwear._lazy.lazy_api``.

``python docs/scripts/lazy_stubs.py``: the packages are those of ``pyproject.toml``; a stub
star-imports the API modules whose ``__all__`` the package's ``__getattr__`` serves, for type
checkers and editors (``tests/root/test_lazy_api.py`` checks each stub against its package).
"""

from __future__ import annotations

import ast
import importlib.util
import tomllib
from pathlib import Path

from jointwear._lazy import stub_text

ROOT = Path(__file__).resolve().parents[2]


def write_stubs() -> list[Path]:
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())
    written = []
    for name in config["tool"]["setuptools"]["packages"]:
        spec = importlib.util.find_spec(name)
        init = Path(spec.origin) if spec and spec.origin else None
        if init is None or init.name != "__init__.py":
            continue
        for node in ast.walk(ast.parse(init.read_text())):
            if isinstance(node, ast.Call) and getattr(node.func, "id", "") == "lazy_api":
                modules = [e.value for e in node.args[1].elts]
                stub = init.with_suffix(".pyi")
                stub.write_text(stub_text(name, modules))
                written.append(stub)
    return written


if __name__ == "__main__":
    for path in write_stubs():
        print(path)
