"""Options generated from a parameter dataclass (jointwear._cli_dataclass): the command gets the
dataclass the options describe, with the field's default, help, unit and limits."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Annotated, Literal

import pytest
import typer
from typer.main import get_command
from typer.testing import CliRunner

from jointwear._cli_dataclass import Opt, field_help, options_from
from jointwear.cli import main


@dataclass(frozen=True)
class _Rig:
    """A toy parameter set.

    Parameters
    ----------
    gap : float
        Radial clearance [m]; measured cold. Not shown.
    kind : {"a", "b"}
        Which kind.
    frames, views : tuple of int
        Frame indices to skip.
    quiet : bool
        Say less.
    """

    gap: float = 2.5e-4
    kind: Literal["a", "b"] = "a"
    frames: tuple[int, ...] = ()
    views: tuple[int, ...] = (1,)
    quiet: bool = False

    def __post_init__(self) -> None:
        if self.gap is not None and self.gap <= 0:
            raise ValueError(f"gap={self.gap!r}: expected > 0 m")


@dataclass(frozen=True)
class _Bore:
    """Parameters
    ----------
    radius : float or None
        Bore radius [m]; None: from the file.
    """

    radius: float | None = None


_Workers = Annotated[int | None, typer.Option("--workers", "-w", help="Worker processes.")]
_Resume = Annotated[bool, typer.Option("--resume", help="Continue.")]


@dataclass(frozen=True)
class _Run:
    """An option group: fields that are declared options (no numpydoc)."""

    workers: _Workers = None
    resume: _Resume = False


def _app(*fields):
    seen = []

    @options_from("rig", _Rig, *fields)
    def cmd(name: str = "x", rig: _Rig = _Rig()) -> None:
        seen.append((name, rig))

    app = typer.Typer(add_completion=False)
    app.command()(cmd)
    app.command("other")(lambda: None)  # a group, so that the command is named
    return app, seen


def test_help_is_the_first_sentence_of_the_fields_entry():
    helps = field_help(_Rig)
    assert helps["gap"] == "Radial clearance [m]."
    assert helps["frames"] == helps["views"] == "Frame indices to skip."
    assert helps["kind"] == "Which kind."


def test_options_carry_the_fields_defaults_units_and_help():
    app, seen = _app(Opt("gap", unit="um"), "kind", Opt("frames", "--skip"), "quiet")
    params = {p.name: p for p in get_command(app).commands["cmd"].params}
    assert set(params) == {"name", "gap_um", "kind", "frames", "quiet"}
    assert params["gap_um"].opts == ["--gap-um"]
    assert params["gap_um"].default == 250.0  # shown rounded (2.5e-4 / 1e-6 is not 250.0)
    assert params["gap_um"].help == "Radial clearance [um]."
    assert params["frames"].opts == ["--skip"]
    assert params["frames"].help == "Frame indices to skip (repeatable)."
    assert params["quiet"].secondary_opts == ["--no-quiet"]

    result = CliRunner().invoke(app, ["cmd", "--gap-um", "120", "--skip", "3", "--skip", "5"])
    assert result.exit_code == 0, result.output
    name, rig = seen[-1]
    assert name == "x"
    # the unit is converted to the field's SI value; the unoffered field keeps its default
    assert rig.gap == pytest.approx(1.2e-4, rel=1e-15)
    assert (rig.kind, rig.frames, rig.views, rig.quiet) == ("a", (3, 5), (1,), False)

    CliRunner().invoke(app, ["cmd"])
    assert seen[-1][1] == _Rig()  # no option given: exactly the library's default


def test_a_value_outside_the_choices_or_the_dataclass_range_is_refused():
    app, seen = _app("gap", "kind")
    result = CliRunner().invoke(app, ["cmd", "--kind", "c"])
    assert result.exit_code == 2 and not seen
    result = CliRunner().invoke(app, ["cmd", "--gap", "-1"])
    assert isinstance(result.exception, ValueError) and not seen  # the dataclass's own check


@pytest.mark.parametrize(
    ("fields", "message"),
    [(("nope",), "no field 'nope'"), (("name",), "no field 'name'")],
)
def test_a_spec_that_names_no_field_fails_at_declaration(fields, message):
    with pytest.raises(TypeError, match=message):
        _app(*fields)


def test_an_option_that_clashes_with_a_parameter_fails_at_declaration():
    with pytest.raises(TypeError, match="clash"):
        _app(Opt("gap", name="name"))


def test_a_length_whose_default_is_none_stays_none_unless_given():
    seen = []

    @options_from("bore", _Bore, Opt("radius", unit="mm"))
    def cmd(bore: _Bore = _Bore()) -> None:
        seen.append(bore)

    app = typer.Typer(add_completion=False)
    app.command()(cmd)
    app.command("other")(lambda: None)
    assert CliRunner().invoke(app, ["cmd"]).exit_code == 0
    assert CliRunner().invoke(app, ["cmd", "--radius-mm", "8"]).exit_code == 0
    assert seen[0].radius is None and seen[1].radius == pytest.approx(8e-3, rel=1e-15)


def test_undocumented_field_needs_a_help():
    @dataclass(frozen=True)
    class Bare:
        x: int = 1

    with pytest.raises(TypeError, match="no help"):
        options_from("b", Bare, "x")(lambda b=Bare(): None)
    options_from("b", Bare, Opt("x", help="X."))(lambda b=Bare(): None)


def test_rig_options_reach_the_library_in_si(monkeypatch, tmp_path):
    import jointwear.datasets.rig as rig_module

    got = {}

    def fake_generate(out, cfg, **kw):
        got["cfg"] = cfg
        return {}

    monkeypatch.setattr(rig_module, "generate_rig", fake_generate)
    args = ["datasets", "rig", "--out", str(tmp_path / "r"), "--z-amplitude-mm", "1.2"]
    args += ["--drop", "4", "--drop", "9", "--noise", "2.5", "--board", "charuco"]
    assert main(args) == 0
    cfg = got["cfg"]
    assert cfg.z_amplitude == pytest.approx(1.2e-3, rel=1e-15)
    assert (cfg.drop_frames, cfg.duplicate_frames) == ((4, 9), ())
    assert (cfg.noise_sigma, cfg.board_kind) == (2.5, "charuco")


def test_library_refusal_names_the_flag(capsys, tmp_path):
    # an even subset: the library's check, in the command's words
    out = tmp_path / "f.nc"
    code = main(["dic", "correlate", "a.png", "b.png", "--subset", "8", "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 3
    assert "--subset 8" in err and "use 9" in err and "subset_size" not in err
    code = main(["datasets", "speckle", str(tmp_path / "s"), "--speckle-size", "300"])
    err = capsys.readouterr().err
    assert code == 3 and "--speckle-size 300" in err and "expected 1 to 200 pixel" in err
    assert not (tmp_path / "s").exists()


def test_the_refusals_suggested_values_are_taken(capsys, tmp_path):
    # the fixes the two refusals above suggest, applied as given, run
    speckle = tmp_path / "s"
    args = ["datasets", "speckle", str(speckle), "--size", "96x96", "--speckle-size", "200"]
    assert main(args) == 0
    assert main(["datasets", "speckle", str(speckle), "--size", "96x96", "--overwrite"]) == 0
    out = tmp_path / "f.nc"
    ref, deformed = speckle / "reference.png", speckle / "deformed.png"
    args = ["dic", "correlate", str(ref), str(deformed), "--subset", "9", "--step", "16"]
    code = main([*args, "--out", str(out)])
    capsys.readouterr()
    assert code == 0 and out.exists()


def test_a_group_of_declared_options_is_offered_as_declared():
    seen = []

    @options_from("run", _Run)
    def cmd(name: str = "x", *, run: _Run, last: int = 0) -> None:
        seen.append((name, run, last))

    app = typer.Typer(add_completion=False)
    app.command()(cmd)
    app.command("other")(lambda: None)
    params = get_command(app).commands["cmd"].params
    # in the group's place, with the declaration's flags and help and the field's default
    assert [p.name for p in params] == ["name", "workers", "resume", "last"]
    assert params[1].opts == ["--workers", "-w"] and params[1].help == "Worker processes."
    assert (params[1].default, params[2].default, params[2].is_flag) == (None, False, True)
    assert CliRunner().invoke(app, ["cmd", "-w", "3", "--resume", "--last", "2"]).exit_code == 0
    assert CliRunner().invoke(app, ["cmd"]).exit_code == 0
    assert seen == [("x", _Run(workers=3, resume=True), 2), ("x", _Run(), 0)]
    # a declared option is not re-declared through Opt
    with pytest.raises(TypeError, match="declared already"):
        options_from("run", _Run, Opt("workers", "--jobs"))(cmd.__wrapped__)
