"""Helpers shared by the CLI groups: command classes that make every command behave alike.

Every command and group of ``jointwear`` is built with :class:`Command` / :class:`CommandGroup`
(:func:`apply_classes` sets them on the whole tree), which

- claim the outputs of a command that declares ``overwrite: Overwrite = False`` for its whole
  run (:func:`jointwear.outputs.claim`): the options named in :data:`OUTPUT_PARAMS` are locked
  against a second writer, and an existing output is refused unless ``--overwrite`` (or
  ``--resume`` for the commands that continue a partial result) is given;
- speak in flags: a message raised by the library that quotes a Python keyword
  (``units='um'``, ``layer_spacing=<m>``) is rewritten with the command's flag
  (``--units um``, ``--layer-spacing-mm <mm>``);
- warn on stderr when a netCDF input is the partial result of an interrupted run
  (:func:`jointwear.conventions.describe_status`);
- show no ``<bool>`` after flags and ``<path>`` rather than ``<list[Path]>`` for repeatable
  options in the help, ``FILE`` rather than ``{file}`` in usage lines, and keep units in brackets (``[mm]``), which rich markup would eat.
"""

from __future__ import annotations

import importlib
import pkgutil
import re
from enum import Enum
from pathlib import Path
from typing import Annotated, Any, get_args, get_origin

import typer
from typer._typing import is_literal_type, literal_values
from typer.core import TyperArgument, TyperCommand, TyperGroup, TyperOption

__all__ = [
    "discover_commands",
    "apply_classes",
    "Command",
    "CommandGroup",
    "Overwrite",
    "OUTPUT_PARAMS",
    "speak_flags",
    "plain_value",
    "DECLINED",
    "lazy_groups",
    "AngleZero",
    "AngleDirection",
    "FigureOut",
    "NetcdfOut",
    "Scheduler",
]

Overwrite = Annotated[
    bool,
    typer.Option(
        "--overwrite",
        help="Replace existing output files (otherwise an existing output is refused).",
    ),
]
"""The ``--overwrite`` option of every command that writes files."""

OUTPUT_PARAMS = ("out", "checkpoint", "figure", "plot", "csv", "table", "pdf", "truth")
"""Names of the parameters that are output paths (claimed by :class:`Command`)."""

_UNIT_SUFFIXES = ("mm", "um", "m", "deg", "rad", "s", "ms", "px", "nm", "mm3")


# --- help: no <bool>, no <list[...]> ------------------------------------------------------
def _element_label(param: Any) -> str:
    from typing import get_args

    args = get_args(param.type_descriptor.annotation)
    label = param._bare_type(args[0]) if args else "value"
    return label.lower()


def _refuse_empty_path(param: Any, value: Any, positional: bool = False) -> None:
    """An empty path (``''``, often an unset shell variable) would read as the current folder
    ``.``: a usage error naming the parameter instead. ``positional``: every positional
    argument of jointwear names files or images, whatever its declared type."""
    described = param.type_descriptor
    is_path = described.is_path or "pathlib.Path" in str(described.annotation)
    if value is None or not (is_path or positional):
        return
    values = value if isinstance(value, list | tuple) else [value]
    if any(isinstance(v, str) and not v.strip() for v in values):
        raise typer.BadParameter(
            "an empty path '' was given (an unset shell variable?); give a file or folder "
            "name (. for the current folder)",
            param=param,
        )


# --- values: plain ones without pydantic ----------------------------------------------------
# typer converts every option value through a pydantic ``TypeAdapter`` it builds per parameter
# (``typer._adapters``): importing pydantic and building the adapters costs about 0.1 CPU s of a
# command's start-up, more than a ``dic correlate`` on a small pair computes in. The values of
# jointwear's options are almost all plain: a ``str``, a ``Path``, an ``int`` or a ``float``
# written in decimal, one of a command's choices, lists and pairs of these. :func:`plain_value`
# converts exactly those, with typer's own path and choice functions, to the value typer would
# give; anything else (a number written otherwise, a value out of its range, a wrong choice, a
# custom parser) it declines, and typer converts it as always, with its own message.
# ``tests/root/test_cli_coerce.py`` holds the two equal on every parameter of the command line.

#: Returned when a value is not plain: typer converts it.
DECLINED = object()

_INT = re.compile(r"[+-]?[0-9]+\Z")
_FLOAT = re.compile(r"[+-]?([0-9]+\.?[0-9]*|\.[0-9]+)([eE][+-]?[0-9]+)?\Z")


def plain_value(param: Any, ctx: Any, value: Any) -> Any:
    """``value`` of ``param`` (a typer option or argument) as typer's conversion gives it, or
    :data:`DECLINED` where the conversion is not plain."""
    described = getattr(param, "type_descriptor", None)
    if described is None or described.file_annotation is not None:
        return DECLINED
    info = described.parameter_info
    if info.parser is not None or getattr(info, "click_type", None) is not None:
        return DECLINED
    multi = param.multiple or param.nargs == -1
    if value is None:
        return () if multi else None
    annotation = described.annotation
    if multi:
        if isinstance(value, str) or get_origin(annotation) is not list:
            return DECLINED
    origin = get_origin(annotation)
    if origin is list:
        if not isinstance(value, list | tuple):
            value = [value]
        items = [_leaf(get_args(annotation)[0], info, param, ctx, v) for v in value]
        return DECLINED if any(v is DECLINED for v in items) else items
    if origin is tuple:
        kinds = get_args(annotation)
        if not isinstance(value, list | tuple) or len(value) != len(kinds) or ... in kinds:
            return DECLINED
        items = [_leaf(k, info, param, ctx, v) for k, v in zip(kinds, value, strict=True)]
        return DECLINED if any(v is DECLINED for v in items) else tuple(items)
    return _leaf(annotation, info, param, ctx, value)


def _leaf(annotation: Any, info: Any, param: Any, ctx: Any, value: Any) -> Any:
    if annotation is str:
        return value if isinstance(value, str) else DECLINED
    if annotation is bool:
        return value if isinstance(value, bool) else DECLINED
    if annotation is int or annotation is float:
        return _number(annotation, info, value)
    if annotation is Path:
        return _path(info, param, ctx, value)
    if (isinstance(annotation, type) and issubclass(annotation, Enum)) or is_literal_type(
        annotation
    ):
        return _choice(annotation, info, ctx, value)
    return DECLINED


def _number(kind: type, info: Any, value: Any) -> Any:
    if getattr(info, "clamp", False):
        return DECLINED
    if isinstance(value, str):
        if not (_INT if kind is int else _FLOAT).match(value):
            return DECLINED
        number = kind(value)
    elif isinstance(value, int | float) and not isinstance(value, bool):
        if kind is int and not isinstance(value, int):
            return DECLINED
        number = kind(value)
    else:
        return DECLINED
    if (info.min is not None and number < info.min) or (info.max is not None and number > info.max):
        return DECLINED  # typer's range message
    return number


def _path(info: Any, param: Any, ctx: Any, value: Any) -> Any:
    from typer._param_types import coerce_cli_path

    if info.path_type is not None and info.path_type is not Path:
        return DECLINED
    if isinstance(value, str):
        if "\x00" in value:
            return DECLINED
        value = Path(value)
    if not isinstance(value, Path):
        return DECLINED
    # typer's own checks (exists, file or folder, readable ...), with its messages
    return coerce_cli_path(value, info, path_type=Path, param=param, ctx=ctx)


def _choice(annotation: Any, info: Any, ctx: Any, value: Any) -> Any:
    from typer._param_types import coerce_cli_choice

    choices = list(annotation) if isinstance(annotation, type) else literal_values(annotation)
    try:
        return coerce_cli_choice(
            value, choices=choices, case_sensitive=info.case_sensitive, ctx=ctx
        )
    except ValueError:
        return DECLINED  # typer's "not one of" message


def _process(param: Any, ctx: Any, value: Any, typer_process: Any) -> Any:
    """typer's ``process_value`` with a plain value converted without pydantic
    (:func:`plain_value`); any other value as typer converts it."""
    from typer._click.exceptions import MissingParameter

    plain = plain_value(param, ctx, value)
    if plain is DECLINED:
        return typer_process(ctx, value)
    if param.required and param.value_is_missing(plain):
        raise MissingParameter(ctx=ctx, param=param)
    return param.callback(ctx, param, plain) if param.callback is not None else plain


class _TidyOption(TyperOption):
    def process_value(self, ctx: Any, value: Any) -> Any:
        _refuse_empty_path(self, value)
        return _process(self, ctx, value, super().process_value)

    def display_type(self, ctx: Any) -> str:
        if self.is_flag and not self.count:
            return ""
        if self.type_descriptor.is_choice:  # the help text lists them; keep the column narrow
            return "<choice>"
        if self.type_descriptor.is_ranged:  # "<int range>": the range follows as [x>=1]
            return f"<{self.bare_type()}>"
        if self.type_descriptor.is_list and not self.type_descriptor.is_choice:
            return f"<{_element_label(self)}>"
        return super().display_type(ctx)


class _TidyArgument(TyperArgument):
    def process_value(self, ctx: Any, value: Any) -> Any:
        _refuse_empty_path(self, value, positional=True)
        return _process(self, ctx, value, super().process_value)

    def _usage_display_name(self) -> str:
        # FILE, [DEFORMED], PATHS... (click's convention) rather than {file}
        name = (self.metavar or self.name or "arg").upper()
        name = name if self.required else f"[{name}]"
        return name + ("..." if self.nargs != 1 else "")

    def display_type(self, ctx: Any) -> str:
        if self.type_descriptor.is_list and not self.type_descriptor.is_choice:
            return f"<{_element_label(self)}>"
        return super().display_type(ctx)


def escape_brackets(text: str | None) -> str | None:
    """Escape ``[`` so rich markup keeps units such as ``[mm]`` in help texts (idempotent)."""
    return re.sub(r"(?<!\\)\[", r"\\[", text) if text else text


def _tidy(params: list[Any]) -> list[Any]:
    for p in params:
        if getattr(p, "help", None):
            p.help = escape_brackets(p.help)
        if type(p) is TyperOption:
            p.__class__ = _TidyOption
        elif type(p) is TyperArgument:
            p.__class__ = _TidyArgument
    return params


# --- errors: flags, not keywords ----------------------------------------------------------
def _flag_of(param: Any) -> str | None:
    longs = [o for o in getattr(param, "opts", []) if o.startswith("--")]
    return longs[0] if longs else None


def _keywords(params: list[Any]) -> dict[str, tuple[str, str | None, Any]]:
    """Library keyword -> (flag, unit of the flag, parameter) for the options of a command."""
    out: dict[str, tuple[str, str | None, Any]] = {}
    for p in params:
        flag = _flag_of(p)
        if flag is None or flag == "--help":
            continue
        name = flag[2:].replace("-", "_")
        unit = None
        for suffix in _UNIT_SUFFIXES:
            if name.endswith("_" + suffix):
                name, unit = name[: -len(suffix) - 1], suffix
                break
        out.setdefault(name, (flag, unit, p))
        if p.name and p.name != name:
            out.setdefault(p.name, (flag, unit, p))
    return out


_VALUE = r"""('[^']*'|"[^"]*"|<[^>]*>|\([^)]*\)|\[[^\]]*\]|\.\.\.|[\w.+-]+)?"""


def speak_flags(message: str, params: list[Any]) -> str:
    """Rewrite ``keyword=value`` in a library message as the command's ``--flag value``."""
    table = _keywords(params)
    if not table:
        return message
    names = "|".join(sorted(map(re.escape, table), key=len, reverse=True))
    pattern = re.compile(rf"(?<![\w\-.'\"])({names})={_VALUE}")

    def repl(m: re.Match) -> str:
        flag, unit, param = table[m.group(1)]
        value = m.group(2)
        is_flag = bool(getattr(param, "is_flag", False))
        secondary = getattr(param, "secondary_opts", None) or []
        if value in (None, "", "..."):
            return flag if is_flag else f"{flag} ..."
        if value == "True" and is_flag:
            return flag
        if value in ("False", "None"):
            if is_flag and secondary:
                return secondary[0]
            return f"without {flag}"
        if value[0] in "'\"" and value[-1] == value[0]:
            value = value[1:-1]
        elif value[0] == "<" and unit is not None:
            value = f"<{unit}>"
        elif value[0] in "([" and value[-1] in ")]":
            inner = value[1:-1].strip()
            value = "..." if inner in ("", "...") else inner.replace(", ", " ").replace(",", " ")
        return f"{flag} {value}"

    return pattern.sub(repl, message)


# --- outputs: lock, refuse existing ---------------------------------------------------------
def _output_paths(cmd: Any, ctx: Any) -> dict[str, Path]:
    paths: dict[str, Path] = {}
    for p in cmd.params:
        if p.name in OUTPUT_PARAMS and ctx.params.get(p.name) is not None:
            value = ctx.params[p.name]
            if isinstance(value, (str, Path)):
                label = _flag_of(p) or p.name.upper()
                paths[label] = Path(value)
    return paths


def _input_status(path: Path) -> str | None:
    """describe_status of a netCDF input, from its global attributes only (cheap)."""
    try:
        import netCDF4

        with netCDF4.Dataset(path) as nc:
            attrs = {
                k: nc.getncattr(k)
                for k in ("status", "cycles_done", "cycles_target", "frames_processed")
                if k in nc.ncattrs()
            }
    except Exception:  # unreadable inputs are the command's to report
        return None
    from jointwear.conventions import describe_status

    return describe_status(attrs)


def _flag_partial_inputs(cmd: Any, ctx: Any) -> None:
    """A warning on stderr for every netCDF input that is a partial result of a stopped run
    (``jointwear info`` says it in its summary instead)."""
    if cmd.name == "info":
        return
    for p in cmd.params:
        if p.name in OUTPUT_PARAMS:
            continue
        values = ctx.params.get(p.name)
        values = values if isinstance(values, (list, tuple)) else [values]
        for v in values:
            if isinstance(v, Path) and v.suffix == ".nc" and _is_file(str(v)):
                status = _input_status(v)
                if status:
                    typer.echo(f"warning: {v}: {status}", err=True)


def _invoke(cmd: Any, ctx: Any, invoke: Any) -> Any:
    from jointwear.errors import JointwearError

    try:
        _flag_partial_inputs(cmd, ctx)
        if "overwrite" not in ctx.params:
            return invoke(ctx)
        from jointwear import outputs

        with outputs.claim(
            _output_paths(cmd, ctx),
            overwrite=bool(ctx.params["overwrite"]),
            resume=bool(ctx.params.get("resume")),
            resumable="resume" in ctx.params,
        ) as removed:
            for tmp in removed:
                typer.echo(f"note: removed {tmp}, left by an interrupted write", err=True)
            return invoke(ctx)
    except JointwearError as exc:
        if exc.args and isinstance(exc.args[0], str):
            message = _name_the_input(speak_flags(exc.args[0], cmd.params), cmd, ctx)
            exc.args = (message, *exc.args[1:])
        raise


def _is_file(text: str) -> bool:
    try:
        return Path(text).is_file()
    except (OSError, ValueError):
        return False


def _name_the_input(message: str, cmd: Any, ctx: Any) -> str:
    """Prefix ``'<file>': `` to a message that names nothing given on the command line, when
    the command was given exactly one existing input file (so it can only be about that)."""
    given = []
    for p in cmd.params:
        values = ctx.params.get(p.name)
        for v in values if isinstance(values, (list, tuple)) else [values]:
            if isinstance(v, (str, Path)) and str(v):
                given.append((p, str(v)))
            flag = _flag_of(p)
            if flag and v not in (None, False, (), []) and v != p.default:
                given.append((p, flag))
    if any(text in message for _, text in given if len(text) > 1):
        return message
    inputs = {
        text
        for p, text in given
        if p.name not in OUTPUT_PARAMS and not text.startswith("-") and _is_file(text)
    }
    return f"'{inputs.pop()}': {message}" if len(inputs) == 1 else message


class _Tidied:
    """Help text with its brackets escaped and tidied parameters (see the module docstring);
    the base of :class:`Command` and :class:`CommandGroup`, which also claim their outputs."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.help = escape_brackets(self.help)
        _tidy(self.params)

    def get_params(self, ctx: Any) -> list[Any]:
        return _tidy(super().get_params(ctx))

    def invoke(self, ctx: Any) -> Any:
        return _invoke(self, ctx, super().invoke)


class Command(_Tidied, TyperCommand):
    """A jointwear command (see the module docstring)."""


class CommandGroup(_Tidied, TyperGroup):
    """A group; when its callback is the command itself (``jointwear compare A B``), it claims
    outputs like :class:`Command` and, while it has no sub-commands, its usage line shows no
    ``COMMAND [ARGS]...``."""

    def collect_usage_pieces(self, ctx: Any) -> list[str]:
        # (Click itself is not imported: Typer >= 0.26 vendors it and no longer installs it)
        pieces = super().collect_usage_pieces(ctx)
        if not self.commands and pieces and pieces[-1] == self.subcommand_metavar:
            pieces = pieces[:-1]
        return pieces


def apply_classes(app: typer.Typer) -> None:
    """Build every command of ``app`` (recursively) with :class:`Command`/:class:`CommandGroup`."""
    for info in app.registered_commands:
        if info.cls is None or info.cls is TyperCommand:
            info.cls = Command
    for group in app.registered_groups:
        group.cls = CommandGroup
        if group.typer_instance is not None:
            group.typer_instance.info.cls = CommandGroup
            apply_classes(group.typer_instance)


def discover_commands(app: typer.Typer, package: str) -> None:
    """Let every module ``<package>.cli_*`` add its commands to ``app``.

    Each such module defines ``register(app: typer.Typer) -> None`` and keeps heavy imports
    inside the command functions, so ``jointwear --help`` stays fast.
    """
    pkg = importlib.import_module(package)
    names = sorted(m.name for m in pkgutil.iter_modules(pkg.__path__) if m.name.startswith("cli_"))
    for name in names:
        module = importlib.import_module(f"{package}.{name}")
        module.register(app)


# --- lazy groups: import a command group only when it is used ---------------------------------
class _LazyCommands(dict):
    """A group's ``commands``: entries that are ``_Pending`` are built on first access.

    Names (``keys``, ``in``, order) need no import; ``get``/``[]`` build one group,
    ``items``/``values`` (the help listing) build all.
    """

    def _build(self, name: str) -> Any:
        value = dict.get(self, name)
        if isinstance(value, _Pending):
            value = value.build(name)
            dict.__setitem__(self, name, value)
        return value

    def __getitem__(self, name: str) -> Any:
        if not dict.__contains__(self, name):
            raise KeyError(name)
        return self._build(name)

    def get(self, name: str, default: Any = None) -> Any:
        return self._build(name) if dict.__contains__(self, name) else default

    def values(self) -> Any:
        return [self._build(name) for name in list(self)]

    def items(self) -> Any:
        return [(name, self._build(name)) for name in list(self)]


class _Pending:
    """A command group not imported yet: ``module`` defines the ``typer.Typer`` named ``app``."""

    def __init__(self, module: str) -> None:
        self.module = module

    def build(self, name: str) -> Any:
        sub = importlib.import_module(self.module).app
        sub.info.cls = CommandGroup
        apply_classes(sub)
        group = _group_of(sub)
        group.name = name
        return group


class _PendingCommand(_Pending):
    """A command of a built group whose options are not read yet (typer reads them from the
    command function's signature)."""

    def __init__(self, info: Any, app: typer.Typer) -> None:
        self.info = info
        self.app = app

    def build(self, name: str) -> Any:
        return typer.main.get_command_from_info(
            self.info,
            pretty_exceptions_short=self.app.pretty_exceptions_short,
            rich_markup_mode=self.app.rich_markup_mode,
        )


def _group_of(app: typer.Typer) -> Any:
    """``typer.main.get_group(app)``, whose commands are built when first used: ``jointwear dic
    correlate`` reads the options of ``correlate`` alone (those of the group's seven commands
    cost 10 ms); the help listing builds them all. Same names in the same order: the commands,
    then the sub-groups."""
    registered = app.registered_commands
    app.registered_commands = []
    try:
        group = typer.main.get_group(app)  # the group, its options and its sub-groups
    finally:
        app.registered_commands = registered
    commands = _LazyCommands()
    for info in registered:
        name = info.name or typer.main.get_command_name(info.callback.__name__)
        commands[name] = _PendingCommand(info, app)
    commands.update(group.commands)
    group.commands = commands
    return group


def lazy_groups(groups: dict[str, str]) -> type:
    """A root group class whose sub-command groups ``{name: module}`` are imported when used.

    ``jointwear dic correlate`` then imports and builds only the ``dic`` group; ``--help``
    (which lists every group's help line) builds them all.
    """

    class LazyGroups(CommandGroup):
        def __init__(self, *args: Any, **kwargs: Any) -> None:
            super().__init__(*args, **kwargs)
            commands = _LazyCommands(self.commands)
            for name, module in groups.items():
                commands.setdefault(name, _Pending(module))
            self.commands = commands

    return LazyGroups


# options shared by the commands of several groups -------------------------------------------------------
def _angle_direction(value: str | None) -> str | None:
    """Check ``--angle-direction`` at parse time (a bad value is a usage error, exit 2); the
    value is passed on as given (the library accepts ``clockwise``, ``counterclockwise``,
    ``cw``, ``ccw``, ...)."""
    if value is None:
        return None
    from jointwear.conventions import AngleConvention
    from jointwear.errors import ConventionError

    try:
        AngleConvention("-x", value)
    except ConventionError:
        raise typer.BadParameter(
            f"{value!r} is not a direction; use clockwise or counterclockwise (seen from +z)"
        ) from None
    return value


AngleZero = Annotated[
    str | None,
    typer.Option(
        "--angle-zero",
        help="Where the angle's 0 points in the bearing frame: +x, +y, -x, -y or degrees "
        "counter-clockwise from +x. Required (never guessed).",
    ),
]
"""``--angle-zero`` of the commands that read angles in a file's own convention."""

AngleDirection = Annotated[
    str | None,
    typer.Option(
        "--angle-direction",
        help="clockwise or counterclockwise, seen from +z. Required (never guessed).",
        callback=_angle_direction,
    ),
]
"""``--angle-direction`` of the commands that read angles in a file's own convention."""

FigureOut = Annotated[
    Path, typer.Option("--out", "-o", help="Figure file (PNG, PDF or SVG, by its suffix).")
]
"""``--out`` of the commands that draw one figure."""

NetcdfOut = Annotated[Path, typer.Option("--out", help="Output netCDF file.")]
"""``--out`` of the commands that write one netCDF file and say no more about it."""

Scheduler = Annotated[
    str | None,
    typer.Option("--scheduler", help="Address of a running dask scheduler, e.g. tcp://host:8786."),
]
"""``--scheduler`` of the commands that can run their tasks on a dask cluster (None: local)."""
