"""Plain command-line values converted without pydantic give what typer's conversion gives."""

from __future__ import annotations

import subprocess
import sys
from enum import Enum
from pathlib import Path
from typing import Literal, get_origin

import typer
from typer import _click as click
from typer._coercion import build_runtime_param

from jointwear._cli import DECLINED, plain_value
from jointwear.cli import app

#: Values a user types or a default holds, for each kind of parameter; plain or not.
SAMPLES = [None, "", "x", "a b", "12", "-3", "+4", "1.5", "-2.5e-3", ".5", "1e3", "1_000",
           " 7", "inf", "nan", "0x10", "deformed.png", "rigid", "RIGID", "none", 3, 0, -1,
           2.5, True, False, Path("f.nc"), ("1", "2"), ["3.5", "x"], ("a.png",), ()]  # fmt: skip


def _params():
    """Every option and argument of every command, lazy groups loaded."""
    root = typer.main.get_command(app)
    stack, seen = [root], []
    while stack:
        cmd = stack.pop()
        if hasattr(cmd, "list_commands"):
            ctx = click.Context(cmd)
            stack += [cmd.get_command(ctx, n) for n in cmd.list_commands(ctx)]
        else:
            seen += [(cmd, p) for p in cmd.params if hasattr(p, "type_descriptor")]
    return seen


def _typer(param, ctx, value):
    try:
        return "ok", build_runtime_param(param.type_descriptor).coerce(value, param=param, ctx=ctx)
    except click.exceptions.BadParameter as exc:
        return "refused", str(exc)


def test_a_plain_value_is_what_typer_makes_of_it_and_the_rest_is_typer_s(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "deformed.png").write_bytes(b"")
    params = _params()
    assert len(params) > 300
    plain = kinds = 0
    for cmd, param in params:
        ctx = click.Context(cmd)
        values = [*SAMPLES, param.default] + list(param.type_descriptor.choices or ())
        for value in values:
            try:
                mine = plain_value(param, ctx, value)
            except click.exceptions.BadParameter as exc:
                mine = ("refused", str(exc))
            else:
                if mine is DECLINED:
                    continue
                mine = ("ok", mine)
            plain += 1
            theirs = _typer(param, ctx, value)
            assert mine == theirs, (cmd.name, param.name, value)
            assert type(mine[1]) is type(theirs[1]), (cmd.name, param.name, value)
            if isinstance(mine[1], list | tuple):
                assert [type(v) for v in mine[1]] == [type(v) for v in theirs[1]]
        kinds += 1
    assert plain > 3000 and kinds == len(params)


def test_what_is_not_plain_is_declined():
    """A number written otherwise, out of range, a wrong choice: typer's messages."""
    cmd, step = next((c, p) for c, p in _params() if p.type_descriptor.parameter_info.min)
    ctx = click.Context(cmd)
    low = step.type_descriptor.parameter_info.min - 1
    assert plain_value(step, ctx, str(int(low))) is DECLINED
    assert _typer(step, ctx, str(int(low)))[0] == "refused"
    for kind in (Enum, Literal):  # a wrong choice declined, a right one converted
        cmd, param = next((c, p) for c, p in _params() if _is(p.type_descriptor.annotation, kind))
        choices = param.type_descriptor.choices
        assert plain_value(param, click.Context(cmd), "no such choice") is DECLINED
        assert (
            plain_value(param, click.Context(cmd), str(getattr(choices[0], "value", choices[0])))
            == choices[0]
        )


def _is(annotation, kind):
    if kind is Enum:
        return isinstance(annotation, type) and issubclass(annotation, Enum)
    return get_origin(annotation) is Literal


def test_dic_correlate_on_a_pair_does_not_import_pydantic(tmp_path):
    """The start-up of #37: the option values of a correlate are all plain (the pair does not
    exist: the command converts its options, then refuses the missing file)."""
    code = (
        "import sys\nfrom jointwear.cli import main\n"
        "code = main(['dic', 'correlate', 'ref.png', 'def.png', '--subset', '31', '--step', "
        "'8', '--out', 'f.nc', '--overwrite', '--origin', 'synthetic'])\n"
        "print('EXIT', code, 'PYDANTIC', 'pydantic' in sys.modules)\n"
    )
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=tmp_path)
    assert "EXIT 3 PYDANTIC False" in run.stdout, run.stdout + run.stderr[-2000:]
    assert "ref.png" in run.stderr
