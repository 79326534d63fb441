"""Command options generated from a parameter dataclass: one source for a field's default,
help text and limits, in the library and on the command line.

A command that takes a parameter set declares it as one parameter annotated with the
dataclass, and :func:`options_from` expands that parameter into one option per field::

    @options_from("params", CorrelationParams, Opt("subset_size", "--subset"), "step", "shape")
    def correlate_cmd(reference: Path, params: CorrelationParams) -> None: ...

- the option's **default** is the field's default (the help shows it from there);
- its **help** is the first sentence of the field's entry in the dataclass's numpydoc
  ``Parameters`` section (parsed by ``docstring_parser``), unless :class:`Opt` gives one;
- its **limits** are the dataclass's own: the command builds the dataclass from the options,
  and a value its ``__post_init__`` refuses is refused with the library's message, which
  :class:`jointwear._cli.Command` rewrites with the flag (``subset_size=8`` → ``--subset 8``);
- a length in SI shown in millimetres or micrometres says so in its flag (``Opt("z_amplitude",
  unit="mm")`` is ``--z-amplitude-mm``, converted to metres for the field);
- a variable-length tuple field (``tuple[int, ...]``) is a repeatable option;
- a field annotated with a declared option (``workers: Workers = None``, where ``Workers`` is
  ``Annotated[int | None, typer.Option("--workers", help=...)]``) is offered as declared: its
  flags and help are the declaration's, its default the field's. A dataclass of such fields is
  an option group several commands share (``jointwear.sim._cli_options.SweepRun``).

Light: imports typer, ``docstring_parser`` and the standard library only, so the CLI's start-up
does not pay for numpy.
"""

from __future__ import annotations

import dataclasses
import functools
import inspect
import re
import typing
from collections.abc import Callable
from dataclasses import dataclass
from typing import Annotated, Any, TypeVar

import typer

__all__ = ["Opt", "options_from", "field_help"]

F = TypeVar("F", bound=Callable[..., Any])

#: the units an option may show a SI length field in, with the factor to metres
UNIT_FACTORS = {"mm": 1e-3, "um": 1e-6}


@dataclass(frozen=True)
class Opt:
    """How one dataclass field is offered as an option.

    Parameters
    ----------
    field : str
        Name of the dataclass field.
    flag : str or None
        The option's flags (``"--noise"``, ``"--video/--no-video"``); default ``--`` and the
        field's name with dashes (with the unit appended when ``unit`` is given; typer adds
        the ``--no-`` form of a boolean).
    help : str or None
        Help text; default the first sentence of the field's docstring entry.
    unit : str or None
        Show a length field [m] in this unit (``"mm"`` or ``"um"``).
    name : str or None
        The command's parameter name; default the field's (with ``_unit`` appended).
    min, max : float or None
        Bounds typer enforces and the help shows (``[1<=x<=16]``), where the command's use is
        narrower than the field's range (a PNG's bit depth); the library's constants.
    """

    field: str
    flag: str | None = None
    help: str | None = None
    unit: str | None = None
    name: str | None = None
    min: float | None = None
    max: float | None = None

    @property
    def param_name(self) -> str:
        if self.name:
            return self.name
        return f"{self.field}_{self.unit}" if self.unit else self.field

    @property
    def factor(self) -> float:
        return UNIT_FACTORS[self.unit] if self.unit else 1.0


def field_help(cls: type) -> dict[str, str]:
    """First sentence of each parameter's entry in ``cls``'s numpydoc ``Parameters`` section."""
    from docstring_parser import DocstringStyle, parse

    doc = parse(inspect.getdoc(cls) or "", style=DocstringStyle.NUMPYDOC)
    out = {}
    for p in doc.params:
        text = " ".join((p.description or "").split())
        first = re.split(r"(?<=[.;])\s+(?=[A-Z(`])|;\s", text, maxsplit=1)[0]
        for name in p.arg_name.split(","):  # "width, height : int" documents both
            out[name.strip()] = first if first.endswith(".") else first + "."
    return out


def _declared(hint: Any) -> tuple[Any, Any]:
    """A field's type without ``Annotated``, and the typer option it declares (or None)."""
    from typer.models import OptionInfo

    if typing.get_origin(hint) is not Annotated:
        return hint, None
    option = next((m for m in hint.__metadata__ if isinstance(m, OptionInfo)), None)
    return hint.__origin__, option


def _option_type(hint: Any) -> tuple[Any, bool]:
    """The option's type for a field's type, and whether it is a repeatable tuple."""
    if typing.get_origin(hint) is tuple:
        args = typing.get_args(hint)
        if len(args) == 2 and args[1] is Ellipsis:
            return list[args[0]] | None, True
    return hint, False


@dataclass(frozen=True)
class _Expanded:
    """One offered field: how it is offered, the command's parameter, the field's own default,
    and whether the option repeats (a ``tuple[T, ...]`` field)."""

    spec: Opt
    parameter: inspect.Parameter
    field_default: Any
    repeatable: bool

    def to_field(self, value: Any) -> Any:
        """The option's value as the field's: a repeatable option's list as a tuple, a length
        in its unit in metres (the shown, rounded default as the field's exact default)."""
        if self.repeatable:
            return tuple(value or ())
        if self.spec.unit and value is not None:
            if value == self.parameter.default:
                return self.field_default
            return value * self.spec.factor
        return value


def _expanded(cls: type, specs: tuple[str | Opt, ...]) -> list[_Expanded]:
    hints = typing.get_type_hints(cls, include_extras=True)
    fields = {f.name: f for f in dataclasses.fields(cls)}
    helps = functools.cache(lambda: field_help(cls))
    out = []
    for spec in (s if isinstance(s, Opt) else Opt(s) for s in specs):
        if spec.field not in fields:
            raise TypeError(f"{cls.__name__} has no field {spec.field!r}")
        field_default = default = fields[spec.field].default
        if default is dataclasses.MISSING:
            raise TypeError(f"{cls.__name__}.{spec.field} has no default to show")
        hint, declared = _declared(hints[spec.field])
        if declared is not None:  # offered as declared: one declaration, flags and help
            if spec != Opt(spec.field):
                raise TypeError(f"{cls.__name__}.{spec.field}: its option is declared already")
            keyword = inspect.Parameter.KEYWORD_ONLY
            parameter = inspect.Parameter(
                spec.field, keyword, default=default, annotation=hints[spec.field]
            )
            out.append(_Expanded(spec, parameter, default, False))
            continue
        kind, repeatable = _option_type(hint)
        if spec.unit:  # shown rounded; to_field maps it back to the exact field default
            kind = float if default is not None else float | None
            default = None if default is None else float(f"{default / spec.factor:.12g}")
        help_text = spec.help or helps().get(spec.field)
        if help_text is None:
            raise TypeError(
                f"{cls.__name__}.{spec.field}: no help (give Opt(help=...) or document it)"
            )
        if spec.unit:
            help_text = re.sub(r"\[m\]", f"[{spec.unit}]", help_text)
        if repeatable:
            help_text = help_text.rstrip(".") + " (repeatable)."
        flags = spec.flag.split() if spec.flag else []
        if spec.unit and not flags:
            flags = ["--" + spec.param_name.replace("_", "-")]
        bounds = {k: v for k, v in (("min", spec.min), ("max", spec.max)) if v is not None}
        option = typer.Option(*flags, help=help_text, **bounds)
        parameter = inspect.Parameter(
            spec.param_name,
            inspect.Parameter.KEYWORD_ONLY,
            default=None if repeatable else default,
            annotation=Annotated[kind, option],
        )
        out.append(_Expanded(spec, parameter, field_default, repeatable))
    return out


def options_from(param: str, cls: type, *fields: str | Opt) -> Callable[[F], F]:
    """Expand the command parameter ``param`` (a ``cls`` instance) into one option per field.

    Parameters
    ----------
    param : str
        Name of the command function's parameter that receives the dataclass instance.
    cls : type
        The frozen parameter dataclass.
    *fields : str or Opt
        The fields offered, in help order: a field's name or an :class:`Opt`. The
        other fields keep their defaults; none given: every field, by its own name.

    Returns
    -------
    callable
        A decorator; the decorated command has the fields' options where ``param`` stood, and
        is called with the dataclass built from them.
    """

    def decorate(func: F) -> F:
        signature = inspect.signature(func)
        if param not in signature.parameters:
            raise TypeError(f"{func.__name__} has no parameter {param!r} to expand")
        expanded = _expanded(cls, fields or tuple(f.name for f in dataclasses.fields(cls)))
        hints = typing.get_type_hints(func, include_extras=True)
        taken = set(signature.parameters) - {param}
        clash = taken & {e.parameter.name for e in expanded}
        if clash:
            raise TypeError(f"{func.__name__}: options {sorted(clash)} clash with parameters")
        params: list[inspect.Parameter] = []
        for p in signature.parameters.values():
            if p.name == param:
                params.extend(e.parameter for e in expanded)
            else:
                kind = inspect.Parameter.KEYWORD_ONLY
                params.append(p.replace(kind=kind, annotation=hints.get(p.name, p.annotation)))

        @functools.wraps(func)
        def command(**kwargs: Any) -> Any:
            values = {e.spec.field: e.to_field(kwargs.pop(e.parameter.name)) for e in expanded}
            kwargs[param] = cls(**values)
            return func(**kwargs)

        command.__signature__ = inspect.Signature(params)  # type: ignore[attr-defined]
        command.__annotations__ = {p.name: p.annotation for p in params}
        return command  # type: ignore[return-value]

    return decorate
