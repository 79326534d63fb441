"""The API reference builds from the docstrings, and every public name is documented in it."""

from __future__ import annotations

import importlib
import importlib.util
import inspect
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def _builder():
    spec = importlib.util.spec_from_file_location("build_api", ROOT / "docs" / "build_api.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _public(package: str) -> dict[str, object]:
    module = importlib.import_module(package)
    return {name: getattr(module, name) for name in getattr(module, "__all__", [])}


@pytest.mark.parametrize("package", _builder().PACKAGES)
def test_every_public_callable_has_a_docstring(package):
    undocumented = [
        name
        for name, obj in _public(package).items()
        if (inspect.isfunction(obj) or inspect.isclass(obj)) and not inspect.getdoc(obj)
    ]
    assert not undocumented, f"{package}: public names without a docstring: {undocumented}"


def test_reference_builds_and_lists_the_public_api(tmp_path):
    builder = _builder()
    index = builder.build(tmp_path)
    assert index.is_file()
    for package in builder.PACKAGES[1:]:
        page = tmp_path / (package.replace(".", "/") + ".html")
        html = page.read_text(encoding="utf-8")
        missing = [
            name
            for name, obj in _public(package).items()
            if (inspect.isfunction(obj) or inspect.isclass(obj)) and f'id="{name}"' not in html
        ]
        assert not missing, f"{page.name}: public names missing from the reference: {missing}"
