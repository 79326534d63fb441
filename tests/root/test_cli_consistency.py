"""CLI consistency: --overwrite on every writing command, help without <bool>/<list[...]> and
with its units, bad option values exit 2, errors speak in flags, SIGTERM like Ctrl-C (143),
a closed pipe exits 0 quietly, partial results are flagged."""

from __future__ import annotations

import re
import subprocess
import sys

import numpy as np
import pytest
import typer
import xarray as xr

from jointwear import io
from jointwear._cli import OUTPUT_PARAMS, speak_flags
from jointwear.cli import app, main


def _commands():
    """(path, click command) of every command and group callback of the jointwear CLI."""
    root = typer.main.get_command(app)
    out = []

    def walk(cmd, path):
        out.append((path, cmd))
        for name, sub in (getattr(cmd, "commands", None) or {}).items():
            walk(sub, [*path, name])

    walk(root, [])
    return out


COMMANDS = _commands()


def _command(*path):
    return next(c for p, c in COMMANDS if p == list(path))


def test_every_command_that_writes_files_has_overwrite():
    writers = [p for p, c in COMMANDS if any(prm.name in OUTPUT_PARAMS for prm in c.params) and p]
    assert len(writers) >= 18  # sim, dic, metrology, datasets, compare, report, import, demo
    missing = [
        " ".join(p) for p in writers if "overwrite" not in {prm.name for prm in _command(*p).params}
    ]
    assert not missing, f"commands writing files without --overwrite: {missing}"


@pytest.mark.parametrize("path", [p for p, _ in COMMANDS], ids=lambda p: " ".join(p) or "root")
def test_help_has_no_python_type_names_and_keeps_units(path, capsys, monkeypatch):
    monkeypatch.setenv("COLUMNS", "200")
    assert main([*path, "--help"]) == 0
    text = capsys.readouterr().out
    assert "<bool>" not in text and "<list[" not in text, text
    usage = next(line for line in text.splitlines() if "Usage:" in line)
    assert "{" not in usage, usage  # FILE, not {file}
    # every unit in brackets written in the help source is shown
    for prm in _command(*path).params:
        for unit in re.findall(r"\\\[([^\]]+)\]", prm.help or ""):
            assert f"[{unit}]" in text, (prm.name, unit)


def test_units_in_help_survive_rich_markup(capsys, monkeypatch):
    monkeypatch.setenv("COLUMNS", "200")
    assert main(["metrology", "import", "--help"]) == 0
    text = capsys.readouterr().out
    assert "Layer spacing [mm]." in text
    assert "mid-width [mm]" in text


@pytest.mark.parametrize(
    "argv",
    [
        ["sim", "wear", "--out", "x.nc", "--contact", "rigid"],
        ["sim", "wear", "--out", "x.nc", "--scheme", "fast"],
        ["datasets", "speckle", "sp", "--field", "wavy"],
        ["datasets", "rig", "--out", "r", "--codec", "h264"],
        ["metrology", "import", "a.txt", "--layout", "diagonal"],
        ["dic", "correlate", "a.png", "b.png", "--shape", "cubic"],
        ["metrology", "assess", "a.nc", "--filter-kind", "spline"],
        ["sim", "cycle", "--cycles", "many"],
        ["dic", "correlate", "a.png", "b.png", "--subset", "1"],
        ["datasets", "speckle", "sp", "--bit-depth", "17"],
        ["dic", "correlate", "a.png", "b.png", "--step", "0"],
    ],
    ids=lambda a: " ".join(a[:2] + a[-2:-1]),
)
def test_bad_option_values_are_usage_errors_naming_the_flag(argv, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert argv[-2] in err and "Traceback" not in err
    assert not list(tmp_path.iterdir())  # nothing written


def _empty_path_cases():
    """(argv, parameter name) giving '' to every path parameter and positional argument of
    every command: '' would read as the current folder '.'."""
    cases = []
    for path, cmd in COMMANDS:
        arguments = [p for p in cmd.params if p.param_type_name == "argument"]
        for prm in cmd.params:
            described = getattr(prm, "type_descriptor", None)
            positional = prm.param_type_name == "argument"
            if positional and prm is not arguments[0]:
                continue  # '' would be read as the first argument
            if described is None or not (positional or "Path" in str(described.annotation)):
                continue
            flag = None if positional else next(o for o in prm.opts if o.startswith("--"))
            cases.append(([*path, ""] if positional else [*path, flag, ""], flag or prm.name))
    return cases


EMPTY_PATH_CASES = _empty_path_cases()


def test_an_empty_path_is_a_usage_error_naming_the_parameter(capsys, tmp_path, monkeypatch):
    # an unset shell variable ('jointwear info "$F"') must not read the current folder
    monkeypatch.chdir(tmp_path)
    assert len(EMPTY_PATH_CASES) >= 60
    wrong = []
    for argv, name in EMPTY_PATH_CASES:
        code = main(argv)
        err = re.sub(r"[\s│]+", " ", capsys.readouterr().err)  # unwrap the rich box
        if code != 2 or "empty path" not in err or name not in err:
            wrong.append((argv, code, err[-300:]))
    assert not wrong, wrong
    assert not list(tmp_path.iterdir())  # nothing was written


def test_one_name_per_concept():
    # a frame rate is --fps everywhere (--frame-rate only as the old second name of it)
    rates = [
        (p, prm.opts)
        for p, c in COMMANDS
        for prm in c.params
        if {"--fps", "--frame-rate"} & set(prm.opts)
    ]
    assert len(rates) >= 3 and all(opts[0] == "--fps" for _, opts in rates), rates
    # --reference is the ISO reference circle/cylinder of metrology assess, nothing else
    users = [" ".join(p) for p, c in COMMANDS for prm in c.params if "--reference" in prm.opts]
    assert users == ["metrology assess"], users


@pytest.mark.parametrize(
    "flag",
    ["--overwrite", "--progress", "--scheduler", "--calibration", "--criteria", "--sim", "--tool"],
)
def test_an_option_of_several_commands_is_declared_once(flag):
    # the same flag with the same meaning shows the same names and help everywhere (declared
    # once as an Annotated alias), so the commands cannot drift apart
    users = [(p, prm) for p, c in COMMANDS for prm in c.params if flag in prm.opts]
    assert len(users) >= 2, users
    declarations = {(tuple(prm.opts), tuple(prm.secondary_opts), prm.help) for _, prm in users}
    assert len(declarations) == 1, declarations


def _speckle(tmp_path, *extra):
    return main(["datasets", "speckle", str(tmp_path / "sp"), "--size", "32x32", *extra])


def test_existing_output_is_refused_unless_overwrite(tmp_path, capsys):
    assert _speckle(tmp_path) == 0
    truth = tmp_path / "sp" / "truth.nc"
    first = truth.stat().st_mtime_ns
    capsys.readouterr()
    assert _speckle(tmp_path, "--u", "0.5") == 3
    err = capsys.readouterr().err
    assert "--overwrite" in err and str(tmp_path / "sp") in err
    assert truth.stat().st_mtime_ns == first
    assert _speckle(tmp_path, "--u", "0.5", "--overwrite") == 0
    assert float(io.load(truth)["u"].isel(x=16, y=16)) == pytest.approx(0.5)


def test_stale_temporary_of_a_killed_run_is_removed_and_reported(tmp_path, capsys):
    stale = tmp_path / ".sp.abcd1234.tmp"
    stale.write_text("left by a SIGKILL")
    assert _speckle(tmp_path) == 0
    assert not stale.exists()
    assert f"removed {stale}" in capsys.readouterr().err


class _Param:
    """Enough of a click option for speak_flags."""

    def __init__(self, opts, name, is_flag=False, secondary=()):
        self.opts, self.name, self.is_flag, self.secondary_opts = opts, name, is_flag, secondary


def test_library_keywords_become_the_commands_flags():
    params = _command("metrology", "import").params
    cases = {
        "the length unit is not stated in the header; pass units='um' (or 'mm')": (
            "pass --units um (or 'mm')"
        ),
        "no z in the file names; pass layer_spacing=<m> or z=[...]": (
            "pass --layer-spacing-mm <mm> or"
        ),
        "re-export it or pass expected_points=None / allow_partial=True": (
            "pass without --expected-points / --allow-partial"
        ),
        "check the column meaning (columns=...)": "(--columns ...)",
        "fix the line or pass delimiter=/decimal=": "pass --delimiter .../--decimal ...",
        "import with resample=True": "import with --resample",
    }
    for message, expected in cases.items():
        spoken = speak_flags(message, params)
        assert expected in spoken, spoken
    # words that merely contain a keyword, and values in quotes, are left alone
    assert speak_flags("subunits='x' and 'units=mm'", params) == "subunits='x' and 'units=mm'"
    prm = [_Param(["--progress"], "progress", True, ["--no-progress"])]
    assert speak_flags("progress=False", prm) == "--no-progress"


def test_error_from_the_library_names_the_flag_end_to_end(tmp_path, capsys):
    scan = tmp_path / "layer.txt"
    theta = np.arange(0, 360, 2.0)
    scan.write_text("angle;value\n" + "".join(f"{t:.1f};{np.sin(t):.4f}\n" for t in theta))
    convention = "--angle-zero +x --angle-direction counterclockwise".split()
    code = main(["metrology", "import", str(scan), *convention, "--out", str(tmp_path / "s.nc")])
    err = capsys.readouterr().err
    assert code == 3, err
    assert "--units" in err and "units=" not in err and "Traceback" not in err


def _big_file(path):
    n = 1500
    ds = xr.Dataset(
        {
            f"v{i:04d}": ("x", [1.0], {"units": "m", "long_name": "a long name " * 6})
            for i in range(n)
        },
        coords={"x": ("x", [0.0], {"units": "m", "long_name": "x"})},
    )
    io.save(ds, path)


def _closed_pipe(*argv):
    """Run jointwear with a stdout pipe whose reader is gone before the first write."""
    proc = subprocess.Popen(
        [sys.executable, "-m", "jointwear", *argv],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
    )
    proc.stdout.close()  # long before the command has imported what it needs
    _, err = proc.communicate(timeout=120)
    return proc.returncode, err.decode()


def test_closed_pipe_exits_0_quietly(tmp_path):
    path = tmp_path / "big.nc"
    _big_file(path)
    assert _closed_pipe("info", str(path)) == (0, "")
    # help is written by rich, which has its own way of meeting a closed pipe
    assert _closed_pipe("sim", "wear", "--help") == (0, "")
    # an error is still an error
    assert _closed_pipe("info", str(tmp_path / "missing.nc"))[0] == 3


SMALL = ["--contact", "winkler", "--layers", "6", "--points", "48", "--kw", "1e-13"]


def test_describe_status_of_partial_results():
    from jointwear.conventions import describe_status, is_partial

    assert not is_partial({}) and describe_status({"status": "complete"}) is None
    wear = {"status": "partial", "cycles_done": 30000, "cycles_target": 1e6}
    assert describe_status(wear).startswith(
        "PARTIAL result: the run stopped after 30000 of 1e+06 cycles"
    )
    track = {"status": "stopped after 7 frames: unreadable frame", "frames_processed": 7}
    assert is_partial(track) and "after 7 frames" in describe_status(track)


@pytest.fixture
def small_disk(tmp_path):
    """A 64 kB tmpfs that can be enlarged ("free space"); needs root, skipped elsewhere."""
    mnt = tmp_path / "disk"
    mnt.mkdir()
    cmd = ["mount", "-t", "tmpfs", "-o", "size=64k", "tmpfs", str(mnt)]
    if subprocess.run(cmd, capture_output=True, check=False).returncode != 0:
        pytest.skip("cannot mount a small tmpfs here (needs root)")
    try:
        yield mnt
    finally:
        subprocess.run(["umount", str(mnt)], check=False)


def test_wear_run_on_a_full_disk_names_the_file_and_resumes_identically(
    small_disk, tmp_path, capsys
):
    run = ["sim", "wear", *SMALL, "--scheme", "fixed", "--dn", "200", "--cycles", "3e4"]
    ref = tmp_path / "ref.nc"
    assert main([*run, "--out", str(ref)]) == 0
    out = small_disk / "w.nc"
    capsys.readouterr()
    assert main([*run, "--out", str(out)]) == 3
    err = capsys.readouterr().err
    ckpt = small_disk / "w.nc.ckpt"
    assert f"'{ckpt}'" in err and "disk is full" in err and "--resume" in err
    assert "Traceback" not in err
    assert sorted(p.name for p in small_disk.iterdir()) == ["w.nc.ckpt"]  # no temporaries
    # free space, then continue: the result is the one of the uninterrupted run
    remount = ["mount", "-o", "remount,size=1m", str(small_disk)]
    subprocess.run(remount, check=True)
    assert main([*run, "--out", str(out), "--resume"]) == 0
    full, resumed = io.load(ref), io.load(out)
    assert resumed.attrs["status"] == "complete"
    for name in ("wear_depth", "worn_volume", "normal_work", "update_dn"):
        np.testing.assert_array_equal(resumed[name].values, full[name].values)


def test_an_unexpected_exception_is_reported_without_traceback(tmp_path, capsys, monkeypatch):
    import jointwear.summary

    def broken(path, validate=True):
        raise ZeroDivisionError("deep inside a library")

    monkeypatch.setattr(jointwear.summary, "summarise", broken)
    assert main(["info", str(tmp_path / "x.nc")]) == 3
    err = capsys.readouterr().err
    assert "unexpected ZeroDivisionError: deep inside a library" in err
    assert "--debug" in err and "Traceback" not in err
    with pytest.raises(ZeroDivisionError):
        main(["--debug", "info", str(tmp_path / "x.nc")])


def test_checkpoint_of_a_killed_wear_run_is_not_thrown_away_unasked(tmp_path, capsys):
    out = tmp_path / "w.nc"
    ckpt = tmp_path / "w.nc.ckpt"
    ckpt.write_bytes(b"state of a run killed before it wrote --out")
    run = ["sim", "wear", *SMALL, "--cycles", "1e3", "--out", str(out)]
    assert main(run) == 3
    err = capsys.readouterr().err
    assert f"'{ckpt}'" in err and "--resume" in err and "--overwrite" in err
    assert ckpt.read_bytes().startswith(b"state of a run killed")
    assert main([*run, "--overwrite"]) == 0
    assert io.load(out).attrs["status"] == "complete"
