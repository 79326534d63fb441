"""Frozen parameter dataclasses from TOML and mappings."""

from __future__ import annotations

import dataclasses
from typing import Literal

import pytest

from jointwear.errors import BadInputError, ParameterError
from jointwear.params import from_mapping, read_toml, replace_nested, to_jsonable


@dataclasses.dataclass(frozen=True)
class Joint:
    radius: float = 7.5e-3
    layers: int = 20
    model: Literal["line", "point"] = "line"


@dataclasses.dataclass(frozen=True)
class Params:
    joint: Joint = Joint()
    gravity: bool = True


def test_nested_mapping_and_defaults():
    p = from_mapping(Params, {"joint": {"radius": 8e-3, "layers": 40}})
    assert p.joint == Joint(radius=8e-3, layers=40)
    assert p.gravity is True


def test_unknown_names_are_listed():
    with pytest.raises(
        ParameterError,
        match=r"unknown parameter\(s\) joint.radus; known names in \[joint\]: radius, layers, model",
    ):
        from_mapping(Params, {"joint": {"radus": 1.0}})


def test_type_errors_name_the_parameter():
    with pytest.raises(ParameterError, match="joint.layers: expected an integer"):
        from_mapping(Params, {"joint": {"layers": "many"}})
    with pytest.raises(ParameterError, match=r"joint.model: expected one of \['line', 'point'\]"):
        from_mapping(Params, {"joint": {"model": "area"}})
    with pytest.raises(ParameterError, match="gravity: expected true or false"):
        from_mapping(Params, {"gravity": 1})


def test_toml_errors_name_the_file(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("[joint\nradius = 1")
    with pytest.raises(BadInputError, match="bad.toml' is not valid TOML"):
        read_toml(bad)
    good = tmp_path / "good.toml"
    good.write_text("[joint]\nradius = 0.008\n")
    assert from_mapping(Params, read_toml(good)).joint.radius == 0.008


def test_replace_nested_and_json():
    p = replace_nested(Params(), **{"joint.layers": 10, "gravity": False})
    assert p.joint.layers == 10 and p.gravity is False
    assert to_jsonable(p) == {
        "joint": {"radius": 7.5e-3, "layers": 10, "model": "line"},
        "gravity": False,
    }
    with pytest.raises(ParameterError, match="unknown parameter 'jiont'"):
        replace_nested(Params(), **{"jiont.layers": 1})


@dataclasses.dataclass(frozen=True)
class WithTuple:
    pair: tuple[int, float] = (1, 2.0)


def test_fixed_length_tuple_fields():
    p = from_mapping(WithTuple, {"pair": [3, 4.5]})
    assert p.pair == (3, 4.5)
    with pytest.raises(ParameterError, match="pair: expected 2 values, got 3"):
        from_mapping(WithTuple, {"pair": [1, 2.0, 3.0]})
    with pytest.raises(ParameterError, match=r"pair\[0\]: expected an integer"):
        from_mapping(WithTuple, {"pair": ["a", 2.0]})


def test_binary_or_folder_toml_is_refused_naming_the_file(tmp_path):
    from jointwear.errors import BadInputError
    from jointwear.params import read_toml

    binary = tmp_path / "criteria.toml"
    binary.write_bytes(b"\xff\xfe\x00\x81binary")
    with pytest.raises(BadInputError, match="criteria.toml' is not UTF-8"):
        read_toml(binary)
    with pytest.raises(BadInputError, match="is a folder"):
        read_toml(tmp_path)
