"""Frozen parameter dataclasses from TOML and mappings."""

from __future__ import annotations

import dataclasses
import math
from typing import Literal

import pytest

from jointwear.errors import BadInputError, ParameterError
from jointwear.params import (
    check_fields,
    checked,
    finite,
    from_mapping,
    non_negative,
    positive,
    read_toml,
    replace_nested,
    to_jsonable,
    within,
)


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


def test_replace_nested_checks_literal_fields_as_the_toml_reader_does():
    # the same message as from_mapping's, naming the dotted field and the allowed values
    with pytest.raises(
        ParameterError, match=r"joint.model: expected one of \['line', 'point'\], got 'area'"
    ):
        replace_nested(Params(), **{"joint.model": "area"})
    with pytest.raises(ParameterError, match=r"^model: expected one of"):
        replace_nested(Joint(), model="x")
    assert replace_nested(Params(), **{"joint.model": "point"}).joint.model == "point"


def test_replace_nested_refuses_an_unknown_simulator_formulation():
    from jointwear.sim import PARAMETER_SETS

    base = PARAMETER_SETS["zhang2023"]
    with pytest.raises(
        ParameterError, match=r"contact.formulation: expected one of \['slice', 'per_point'\]"
    ):
        replace_nested(base, **{"contact.formulation": "x"})
    assert (
        replace_nested(base, **{"contact.formulation": "per_point"}).contact.formulation
        == "per_point"
    )


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


def _as_int(where: str, name: str, value: float) -> int:
    if value != int(value):
        raise ParameterError(f"{where}.{name} must be whole, got {value!r}")
    return int(value)


@dataclasses.dataclass(frozen=True)
class Declared:
    length: float = positive(1.0)
    play: float = non_negative(0.0, unit="m")
    offset: float = finite(0.0)
    share: float = within(0.5, "(0, 1]")
    poisson: float = within(0.3, "[-1, 0.5)")
    count: int = checked(2, _as_int)
    free: float = -3.0  # no check declared: anything goes

    def __post_init__(self) -> None:
        check_fields(self, "part")


@pytest.mark.parametrize(
    ("values", "message"),
    [
        ({"length": 0.0}, r"part\.length must be a positive finite number, got 0\.0"),
        ({"length": math.inf}, r"part\.length must be a positive finite number"),
        ({"play": -1e-9}, r"part\.play must be >= 0 m, got -1e-09"),
        ({"play": math.nan}, r"part\.play must be >= 0 m"),
        ({"offset": -math.inf}, r"part\.offset must be finite"),
        ({"share": 0.0}, r"part\.share must be in \(0, 1\], got 0\.0"),
        ({"share": 1.0 + 1e-12}, r"part\.share must be in \(0, 1\]"),
        ({"share": math.nan}, r"part\.share must be in \(0, 1\]"),
        ({"poisson": 0.5}, r"part\.poisson must be in \[-1, 0\.5\), got 0\.5"),
        ({"count": 2.5}, r"part\.count must be whole, got 2\.5"),
        # two wrong fields: the first in field order is named
        ({"share": 2.0, "length": -1.0}, r"part\.length"),
    ],
)
def test_declared_field_checks_refuse_naming_the_field(values, message):
    with pytest.raises(ParameterError, match=message):
        Declared(**values)


def test_declared_field_checks_accept_the_bounds_and_keep_converted_values():
    d = Declared(play=0.0, share=1.0, poisson=-1.0, count=3.0, free=-7.0)
    assert (d.share, d.poisson, d.free) == (1.0, -1.0, -7.0)
    assert d.count == 3 and type(d.count) is int  # the check's conversion is stored
    assert Declared().count == 2 and Declared.length == 1.0  # defaults as declared
    # from TOML tables too, and replace() checks again
    assert from_mapping(Declared, {"share": 0.25}).share == 0.25
    with pytest.raises(ParameterError, match=r"part\.share"):
        dataclasses.replace(Declared(), share=0.0)


@dataclasses.dataclass(frozen=True)
class Chosen:
    model: Literal["line", "point"] = "line"
    maybe: Literal["a", "b"] | None = None
    length: float = positive(1.0)

    def __post_init__(self) -> None:
        check_fields(self, "part")


def test_check_fields_refuses_a_literal_field_outside_its_choices_by_construction():
    with pytest.raises(
        ParameterError, match=r"^part\.model: expected one of \['line', 'point'\], got 'area'$"
    ):
        Chosen(model="area")
    with pytest.raises(ParameterError, match=r"part\.maybe: expected one of \['a', 'b'\]"):
        dataclasses.replace(Chosen(), maybe="c")
    with pytest.raises(ParameterError, match=r"^model: expected one of"):  # replace_nested's
        replace_nested(Chosen(), model="x")
    assert (Chosen(model="point", maybe="b").model, Chosen().maybe) == ("point", None)


def test_a_malformed_interval_is_refused_at_declaration():
    with pytest.raises(ValueError, match="interval '0, 1'"):
        within(0.5, "0, 1")


def test_check_known_keys_names_each_unknown_key_and_the_closest_known_one():
    from jointwear.params import check_known_keys

    check_known_keys("sweep", ["seed", "run"], ["run", "method", "seed"])  # all known: no error
    with pytest.raises(ParameterError) as info:
        check_known_keys("sweep", ["run", "sead", "zzz"], ["run", "method", "seed"])
    assert str(info.value) == (
        "[sweep]: unknown key(s) sead (did you mean seed?), zzz; known: run, method, seed"
    )
