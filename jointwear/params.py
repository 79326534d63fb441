"""Building frozen parameter dataclasses from TOML files and mappings, with clear errors."""

from __future__ import annotations

import dataclasses
import functools
import math
import numbers
import tomllib
import types
import typing
from collections.abc import Callable, Iterable, Mapping
from pathlib import Path
from typing import Any, TypeVar

from jointwear.errors import BadInputError, ParameterError

__all__ = [
    "from_mapping",
    "check_known_keys",
    "read_toml",
    "to_jsonable",
    "replace_nested",
    "check_positive",
    "check_non_negative",
    "checked",
    "positive",
    "non_negative",
    "finite",
    "within",
    "check_fields",
]

T = TypeVar("T")


def read_toml(path: str | Path) -> dict[str, Any]:
    """Read a TOML file into a dict, with an error that names the file on failure."""
    path = Path(path)
    try:
        with path.open("rb") as fh:
            return tomllib.load(fh)
    except FileNotFoundError:
        raise BadInputError(f"parameter file '{path}' does not exist") from None
    except tomllib.TOMLDecodeError as exc:
        raise BadInputError(
            f"parameter file '{path}' is not valid TOML: {exc} - fix the syntax at that line"
        ) from None
    except UnicodeDecodeError:
        raise BadInputError(
            f"parameter file '{path}' is not UTF-8 text (TOML files must be); is it the right file?"
        ) from None
    except IsADirectoryError:
        raise BadInputError(f"parameter file '{path}' is a folder; give a .toml file") from None


@functools.cache
def _field_types(cls: type) -> dict[str, Any]:
    return typing.get_type_hints(cls)


def _is_dataclass_type(tp: Any) -> bool:
    return isinstance(tp, type) and dataclasses.is_dataclass(tp)


def _coerce(value: Any, tp: Any, where: str) -> Any:
    origin = typing.get_origin(tp)
    if _is_dataclass_type(tp):
        if isinstance(value, tp):
            return value
        if not isinstance(value, Mapping):
            raise ParameterError(f"{where}: expected a table of parameters, got {value!r}")
        return from_mapping(tp, value, where=where)
    if origin in (typing.Union, types.UnionType):
        args = typing.get_args(tp)
        if value is None and type(None) in args:
            return None
        errors = []
        for arg in args:
            if arg is type(None):
                continue
            try:
                return _coerce(value, arg, where)
            except ParameterError as exc:
                errors.append(str(exc))
        raise ParameterError("; ".join(errors))
    if origin is typing.Literal:
        allowed = typing.get_args(tp)
        if value not in allowed:
            raise ParameterError(f"{where}: expected one of {list(allowed)}, got {value!r}")
        return value
    if origin in (tuple, list):
        if isinstance(value, (str, bytes)) or not hasattr(value, "__iter__"):
            raise ParameterError(f"{where}: expected a list, got {value!r}")
        args = typing.get_args(tp)
        if origin is tuple and args and args[-1] is not Ellipsis:
            if len(args) != len(value):
                raise ParameterError(f"{where}: expected {len(args)} values, got {len(value)}")
            return tuple(
                _coerce(v, a, f"{where}[{i}]")
                for i, (v, a) in enumerate(zip(value, args, strict=True))
            )
        inner = args[0] if args else Any
        out = [_coerce(v, inner, f"{where}[{i}]") for i, v in enumerate(value)]
        return tuple(out) if origin is tuple else out
    if tp is float:
        if isinstance(value, bool) or not isinstance(value, numbers.Real):
            raise ParameterError(f"{where}: expected a number, got {value!r}")
        value = float(value)
        if not math.isfinite(value):
            raise ParameterError(f"{where}: expected a finite number, got {value!r}")
        return value
    if tp is int:
        if isinstance(value, bool) or not isinstance(value, numbers.Integral):
            if isinstance(value, float) and value.is_integer():
                return int(value)
            raise ParameterError(f"{where}: expected an integer, got {value!r}")
        return int(value)
    if tp is bool:
        import numpy as np  # not at import time: the CLI reads parameter defaults at start-up

        if not isinstance(value, (bool, np.bool_)):
            raise ParameterError(f"{where}: expected true or false, got {value!r}")
        return bool(value)
    if tp is str:
        if not isinstance(value, str):
            raise ParameterError(f"{where}: expected a string, got {value!r}")
        return value
    return value


def _positive(where: str, name: str, value: float) -> float:
    if not (value > 0 and math.isfinite(value)):
        raise ParameterError(
            f"{where}.{name} must be a positive finite number, got {value!r}; "
            "set a physical (SI) value"
        )
    return value


def _non_negative(where: str, name: str, value: float, unit: str = "") -> float:
    if not (value >= 0 and math.isfinite(value)):
        unit = f" {unit}" if unit else ""
        raise ParameterError(f"{where}.{name} must be >= 0{unit}, got {value!r}")
    return value


def _finite(where: str, name: str, value: float) -> float:
    if not math.isfinite(value):
        raise ParameterError(f"{where}.{name} must be finite")
    return value


def _within(where: str, name: str, value: float, interval: str, lo: float, hi: float) -> float:
    above = value >= lo if interval[0] == "[" else value > lo
    below = value <= hi if interval[-1] == "]" else value < hi
    if not (above and below):
        raise ParameterError(f"{where}.{name} must be in {interval}, got {value!r}")
    return value


def check_positive(where: str, **values: float) -> None:
    """Raise :class:`~jointwear.errors.ParameterError` naming ``where.name`` unless every value
    is a positive finite number."""
    for name, value in values.items():
        _positive(where, name, value)


def check_non_negative(where: str, **values: float) -> None:
    """Raise :class:`~jointwear.errors.ParameterError` naming ``where.name`` unless every value
    is a finite number >= 0."""
    for name, value in values.items():
        _non_negative(where, name, value)


#: A field's check: ``check(where, name, value)`` returns the value to keep (possibly
#: converted) or raises :class:`~jointwear.errors.ParameterError` naming ``where.name``.
FieldCheck = Callable[[str, str, Any], Any]


def checked(default: Any, check: FieldCheck) -> Any:
    """A dataclass field with its default and the check its value must pass.

    The check is declared where the field is and run by :func:`check_fields` (from the
    dataclass's ``__post_init__``), so that no field is listed a second time to be checked.
    """
    return dataclasses.field(default=default, metadata={"check": check})


def positive(default: float) -> Any:
    """A field that must be a positive finite number."""
    return checked(default, _positive)


def non_negative(default: float, *, unit: str = "") -> Any:
    """A field that must be a finite number >= 0 (``unit``, if given, is named in the error)."""
    return checked(default, functools.partial(_non_negative, unit=unit))


def finite(default: float) -> Any:
    """A field that must be a finite number."""
    return checked(default, _finite)


def within(default: float, interval: str) -> Any:
    """A field that must lie in ``interval``, written as in the error: ``"(0, 1]"``, ``"[-1, 1)"``."""
    bounds = interval[1:-1].split(",")
    if interval[0] not in "([" or interval[-1] not in ")]" or len(bounds) != 2:
        raise ValueError(f"interval {interval!r}: expected '(lo, hi)' with ( or [ and ) or ]")
    lo, hi = (float(b) for b in bounds)
    return checked(default, functools.partial(_within, interval=interval, lo=lo, hi=hi))


def check_fields(obj: Any, where: str) -> None:
    """Run the checks the fields of the dataclass instance ``obj`` declare (:func:`checked`), in
    field order; errors name ``where.field``. A check's converted value replaces the field's.

    A ``Literal`` field (or a union holding one) is checked against its allowed values as the
    TOML reader and :func:`replace_nested` check it (the same message, naming ``where.field``
    and the allowed values), so a wrong value is refused by construction too.
    """
    literals = _literal_fields(type(obj))
    for f in dataclasses.fields(obj):
        if f.name in literals:
            _coerce(getattr(obj, f.name), literals[f.name], f"{where}.{f.name}")
        check = f.metadata.get("check")
        if check is not None:
            value = getattr(obj, f.name)
            kept = check(where, f.name, value)
            if kept is not value:
                object.__setattr__(obj, f.name, kept)


def from_mapping(cls: type[T], mapping: Mapping[str, Any], *, where: str | None = None) -> T:
    """Build the (possibly nested) frozen dataclass ``cls`` from a mapping.

    Unknown keys raise :class:`~jointwear.errors.ParameterError` naming the key and listing the
    known ones; values are checked against the field types (numbers, booleans, strings,
    literals, nested tables). Missing keys take the dataclass defaults.

    Parameters
    ----------
    cls : type
        A dataclass type.
    mapping : Mapping
        Values by field name (as read from TOML).
    where : str, optional
        Dotted prefix used in error messages (e.g. ``"joint"``).
    """
    prefix = f"{where}." if where else ""
    types_ = _field_types(cls)
    names = [f.name for f in dataclasses.fields(cls) if f.init]
    unknown = [k for k in mapping if k not in names]
    if unknown:
        raise ParameterError(
            f"unknown parameter(s) {', '.join(prefix + k for k in unknown)}; "
            f"known names{' in [' + where + ']' if where else ''}: {', '.join(names)}"
        )
    kwargs = {k: _coerce(v, types_[k], prefix + k) for k, v in mapping.items()}
    try:
        return cls(**kwargs)
    except ParameterError:
        raise
    except (TypeError, ValueError) as exc:
        raise ParameterError(f"{where or cls.__name__}: {exc}") from None


def check_known_keys(table: str, given: Iterable[str], known: Iterable[str]) -> None:
    """Refuse the keys of the TOML table ``[table]`` that are not ``known``.

    Parameters
    ----------
    table : str
        The table's name, as the message shows it (``"sweep"``: ``[sweep]``).
    given, known : iterable of str
        The keys the file gives; the keys the table takes (listed in this order).

    Raises
    ------
    ParameterError
        Naming each unknown key with the closest known one ("did you mean ...?") and the known
        keys.
    """
    known = list(known)
    bad = sorted(set(given) - set(known))
    if bad:
        import difflib

        hints = [
            k
            + (f" (did you mean {c[0]}?)" if (c := difflib.get_close_matches(k, known, 1)) else "")
            for k in bad
        ]
        raise ParameterError(
            f"[{table}]: unknown key(s) {', '.join(hints)}; known: {', '.join(known)}"
        )


def _is_literal(tp: Any) -> bool:
    """Whether the field type ``tp`` is a ``Literal`` (or a union holding one)."""
    if typing.get_origin(tp) is typing.Literal:
        return True
    if typing.get_origin(tp) in (typing.Union, types.UnionType):
        return any(_is_literal(arg) for arg in typing.get_args(tp))
    return False


@functools.cache
def _literal_fields(cls: type) -> dict[str, Any]:
    """The type of each field of the dataclass ``cls`` that is a ``Literal`` (:func:`_is_literal`)."""
    types_ = _field_types(cls)
    return {f.name: types_[f.name] for f in dataclasses.fields(cls) if _is_literal(types_[f.name])}


def replace_nested(obj: T, **changes: Any) -> T:
    """``dataclasses.replace`` that accepts dotted names (``"joint.radial_clearance"``).

    A ``Literal`` field's value is checked as the TOML reader checks it (:func:`from_mapping`):
    a value outside the allowed ones raises :class:`~jointwear.errors.ParameterError` naming the
    dotted field and the allowed values.
    """
    return _replace_nested(obj, changes, "")


def _replace_nested(obj: T, changes: Mapping[str, Any], prefix: str) -> T:
    direct: dict[str, Any] = {}
    nested: dict[str, dict[str, Any]] = {}
    for key, value in changes.items():
        head, _, rest = key.partition(".")
        if rest:
            nested.setdefault(head, {})[rest] = value
        else:
            direct[head] = value
    names = {f.name for f in dataclasses.fields(obj)}
    for head in list(direct) + list(nested):
        if head not in names:
            raise ParameterError(
                f"unknown parameter '{head}' for {type(obj).__name__}; known: {', '.join(sorted(names))}"
            )
    types_ = _field_types(type(obj))
    for head, value in direct.items():
        if _is_literal(types_.get(head)):
            direct[head] = _coerce(value, types_[head], prefix + head)
    for head, sub in nested.items():
        direct[head] = _replace_nested(getattr(obj, head), sub, f"{prefix}{head}.")
    return dataclasses.replace(obj, **direct)


def to_jsonable(obj: Any) -> Any:
    """Convert dataclasses, numpy scalars/arrays, paths and tuples into JSON-ready values."""
    import numpy as np

    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        return {f.name: to_jsonable(getattr(obj, f.name)) for f in dataclasses.fields(obj)}
    if isinstance(obj, Mapping):
        return {str(k): to_jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [to_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, Path):
        return str(obj)
    if isinstance(obj, float) and not math.isfinite(obj):
        return str(obj)
    return obj
