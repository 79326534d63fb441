"""Subpackages re-export their public API lazily; the CLI starts without heavy imports."""

from __future__ import annotations

import importlib
import inspect
import subprocess
import sys

import pytest

PACKAGES = [
    "jointwear.sim",
    "jointwear.sim.wear",
    "jointwear.sim.sweep",
    "jointwear.dic",
    "jointwear.metrology",
    "jointwear.compare",
    "jointwear.reports",
]


def test_cli_starts_without_numerical_stack():
    code = (
        "import sys, jointwear.cli; "
        "print(sorted(m for m in ('numba', 'scipy', 'xarray', 'cv2', 'matplotlib') if m in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


@pytest.mark.parametrize("package", PACKAGES)
def test_every_exported_name_resolves_to_the_api_object(package):
    pkg = importlib.import_module(package)
    names = pkg.__all__
    assert names and len(names) == len(set(names))
    for name in names:
        obj = getattr(pkg, name)
        # a public name never resolves to a submodule that happens to share it
        assert not inspect.ismodule(obj), f"{package}.{name} is a module"
    assert set(names) <= set(dir(pkg))
    with pytest.raises(AttributeError, match="has no attribute 'no_such_name'"):
        pkg.no_such_name  # noqa: B018


def test_function_shadowing_a_submodule():
    from jointwear.metrology import assess

    assert callable(assess) and not inspect.ismodule(assess)
    import jointwear.metrology as m

    assert m.assess is assess


def test_function_wins_when_the_submodule_was_imported_first():
    # a fresh interpreter: importing the module ``assess`` binds it on the package before the
    # lazy API has loaded; the public function must still be what the name gives
    code = (
        "import inspect, jointwear.metrology.assess; "
        "from jointwear.metrology import assess; "
        "import sys; "
        "print(inspect.isfunction(assess), "
        "inspect.ismodule(sys.modules['jointwear.metrology.assess']))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["True", "True"]


@pytest.mark.parametrize("package", PACKAGES)
def test_the_static_stub_lists_exactly_the_lazy_api(package):
    """``__init__.pyi`` (what type checkers and editors read) star-imports the modules whose
    ``__all__`` (PEP 484: what a star-import in a stub re-exports) is exactly the public API the
    package's ``__getattr__`` serves, each name once, and holds nothing else."""
    import ast
    from pathlib import Path

    pkg = importlib.import_module(package)
    stub = Path(pkg.__file__).with_suffix(".pyi")
    tree = ast.parse(stub.read_text())
    docstring, *imports = tree.body
    assert isinstance(docstring, ast.Expr) and isinstance(docstring.value, ast.Constant)
    assert imports and all(
        isinstance(node, ast.ImportFrom) and [a.name for a in node.names] == ["*"]
        for node in imports
    )
    modules = [importlib.import_module(node.module) for node in imports]
    exported = [(name, module) for module in modules for name in module.__all__]
    assert sorted(name for name, _ in exported) == sorted(pkg.__all__)
    for name, module in exported:
        assert getattr(module, name) is getattr(pkg, name)
