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
    "jointwear.sim.calibrate",
    "jointwear.dic",
    "jointwear.dic.icgn",
    "jointwear.dic.calibration",
    "jointwear.dic.footage",
    "jointwear.dic.subset",
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
    with pytest.raises(AttributeError, match="no_such_name"):
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


def _stubs():
    import importlib.util
    from pathlib import Path

    path = Path(__file__).resolve().parents[2] / "docs" / "scripts" / "lazy_stubs.py"
    spec = importlib.util.spec_from_file_location("lazy_stubs", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_every_lazy_package_is_tested_and_its_stub_is_up_to_date():
    stubs = _stubs()
    assert set(stubs.lazy_packages()) == set(PACKAGES)
    assert stubs.write_stubs(check=True) == []  # 'python docs/scripts/lazy_stubs.py' rewrites them


@pytest.mark.parametrize("package", PACKAGES)
def test_the_stub_lists_every_public_name_at_its_module(package):
    """``__init__.pyi`` (what lazy_loader and type checkers read) names every public name
    explicitly, once, as ``from .<module> import <name> as <name>``; each is the object of that
    name in the modules the package's ``_EXPORTS`` lists, and the public API is exactly those."""
    import ast
    from pathlib import Path

    pkg = importlib.import_module(package)
    stub = Path(pkg.__file__).with_suffix(".pyi")
    docstring, *imports = ast.parse(stub.read_text()).body
    assert isinstance(docstring, ast.Expr) and isinstance(docstring.value, ast.Constant)
    listed = {}
    for node in imports:
        assert isinstance(node, ast.ImportFrom) and node.level == 1 and node.module
        for alias in node.names:
            assert alias.name != "*" and alias.asname == alias.name
            assert alias.name not in listed
            listed[alias.name] = node.module
    assert sorted(listed) == sorted(pkg.__all__)
    expected = set()
    for module, names in pkg._EXPORTS.items():
        source = importlib.import_module(f"{package}.{module}")
        for name in [n for w in names or ("*",) for n in (source.__all__ if w == "*" else [w])]:
            expected.add(name)
            assert getattr(pkg, name) is getattr(source, name), name
    assert expected == set(listed)
    for name, module in listed.items():
        defining = importlib.import_module(f"{package}.{module}")
        assert getattr(defining, name) is getattr(pkg, name)


def test_every_stub_is_package_data():
    """lazy_loader reads the stub at import time: an installed package without it cannot start."""
    import tomllib
    from pathlib import Path

    config = tomllib.loads((Path(__file__).resolve().parents[2] / "pyproject.toml").read_text())
    data = config["tool"]["setuptools"]["package-data"]
    missing = [p for p in PACKAGES if not any(g.endswith(".pyi") for g in data.get(p, []))]
    assert not missing, f"add '*.pyi' to [tool.setuptools.package-data] of {missing}"
