"""Property-based fuzz test of the command line: whatever the options and files, a command
ends with exit 0, 1, 2 or 3, never a traceback, and a refusal names what it refuses (a flag,
a value or a file given on the command line).

Commands that compute for long on valid input (simulations, the rig renderer, calibration,
tracking, the demo) are left out: their option parsing is shared with the others (the same
command classes) and they are covered by their own tests.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

import pytest
import typer
from _small_map import small_wear_map
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st

from jointwear import io
from jointwear._cli import OUTPUT_PARAMS
from jointwear.cli import app, main

pytestmark = pytest.mark.filterwarnings("ignore")  # library warnings on absurd input are fine

SLOW = {
    ("sim", "cycle"),
    ("sim", "wear"),
    ("dic", "calibrate"),
    ("dic", "track"),
    ("dic", "correlate"),
    ("datasets", "rig"),
    ("datasets", "speckle"),
    ("datasets", "instruments"),
    ("demo",),
}


def _leaf_commands():
    """(path, command) of every command that does something (not the plain groups)."""
    out = []

    def walk(cmd, path):
        subs = getattr(cmd, "commands", None) or {}
        if path and not subs and cmd.callback is not None:
            out.append((tuple(path), cmd))
        for name, sub in subs.items():
            walk(sub, [*path, name])

    walk(typer.main.get_command(app), [])
    return [(p, c) for p, c in out if p not in SLOW]


COMMANDS = _leaf_commands()


def _command(argv):
    return next(c for p, c in COMMANDS if tuple(argv[: len(p)]) == p)


TEXTS = [
    "",
    "a",
    "auto",
    "+x",
    "-y",
    "clockwise",
    "1,2",
    "0,0,10,10",
    "um",
    "--",
    "é∂😀",
    "x" * 300,
]
INTS = ["0", "-1", "2", "abc", "", "3.5"]
FLOATS = ["0", "-1", "0.5", "nan", "inf", "-inf", "1e300", "x", ""]


def _files(folder: Path) -> dict[str, Path]:
    """Inputs of every kind: missing, empty, garbage, binary, a folder, valid netCDF."""
    wear = small_wear_map()
    files = {
        "missing": folder / "missing.nc",
        "empty": folder / "empty.txt",
        "garbage": folder / "garbage.nc",
        "binary": folder / "binary.bin",
        "text": folder / "scan.txt",
        "folder": folder / "folder",
        "wear": folder / "wear.nc",
        "toml": folder / "bad.toml",
    }
    files["empty"].write_text("")
    files["garbage"].write_text("CDF\x01 not really netCDF\n")
    files["binary"].write_bytes(bytes(range(256)) * 4)
    files["text"].write_text("angle;value\n" + "".join(f"{t};{t % 7}\n" for t in range(0, 360, 5)))
    files["folder"].mkdir()
    (files["folder"] / "layer1.txt").write_text("0 1\n180 2\n")
    files["toml"].write_text("[wear\nkw = \n")
    io.save(wear, files["wear"])
    return files


def _values(param, files):
    """A strategy of command-line values for one parameter."""
    if param.name in OUTPUT_PARAMS:  # relative: written into the example's own folder
        return st.sampled_from(["o.nc", "o.png", "o.csv", "outdir", str(files["wear"])])
    desc = getattr(param, "type_descriptor", None)
    ann = str(getattr(desc, "annotation", ""))
    if getattr(desc, "is_choice", False) and desc.choices:
        return st.sampled_from([*map(str, desc.choices), "bogus", ""])
    if getattr(desc, "is_path", False) or "Path" in ann:
        return st.sampled_from([str(p) for p in files.values()])
    if "int" in ann:
        return st.sampled_from(INTS)
    if "float" in ann:
        return st.sampled_from(FLOATS)
    return st.sampled_from(TEXTS + [str(files["text"])])


@st.composite
def _argv(draw, files):
    path, cmd = draw(st.sampled_from(COMMANDS))
    argv = list(path)
    for param in cmd.params:
        if param.name in ("help", "overwrite") or getattr(param, "hidden", False):
            continue
        opts = [o for o in param.opts if o.startswith("--")]
        if not opts:  # an argument
            if draw(st.booleans()) or param.required:
                n = 1 if param.nargs == 1 else draw(st.integers(1, 2))
                argv += [draw(_values(param, files)) for _ in range(n)]
            continue
        if not draw(st.integers(0, 3)) == 0:
            continue
        if getattr(param, "is_flag", False):
            argv.append(draw(st.sampled_from([*param.opts, *param.secondary_opts])))
        elif param.nargs > 1:
            argv += [opts[0], *(draw(_values(param, files)) for _ in range(param.nargs))]
        else:
            argv += [opts[0], draw(_values(param, files))]
    if draw(st.integers(0, 4)) == 0:
        argv.append(draw(st.sampled_from(["--no-such-option", "extra-argument", "--out"])))
    return argv


@pytest.fixture(scope="module")
def fuzz_files():
    with tempfile.TemporaryDirectory(prefix="jointwear-fuzz-") as d:
        yield Path(d), _files(Path(d))


def test_fuzz_found_the_commands():
    names = {" ".join(p) for p, _ in COMMANDS}
    assert {"info", "metrology import", "compare", "report", "import motion"} <= names


@settings(
    max_examples=25 if os.environ.get("CI") else 300,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
    derandomize=bool(os.environ.get("CI")),
    # shrinking re-runs whole commands for minutes; the failing argv is reported unshrunk
    phases=[Phase.explicit, Phase.reuse, Phase.generate],
)
@given(data=st.data())
def test_cli_never_crashes_and_names_what_it_refuses(data, fuzz_files, capsys, monkeypatch):
    folder, files = fuzz_files
    with tempfile.TemporaryDirectory(dir=folder) as d:
        monkeypatch.chdir(d)
        monkeypatch.setenv("COLUMNS", "2000")  # no wrapping of the messages
        argv = data.draw(_argv(files), label="argv")
        capsys.readouterr()
        code = main(argv)
        out, err = capsys.readouterr()
    assert code in (0, 1, 2, 3), (argv, code, err)
    assert "Traceback" not in err + out, (argv, err)
    if code == 2 and not err.strip():
        assert "Usage:" in out, argv  # a group called without a command shows its help
    elif code in (2, 3):
        assert "This is a bug in jointwear" not in err, (argv, err)
        # a value or file given, or one of the command's flags (e.g. the one that is missing)
        flags = [o for prm in _command(argv).params for o in prm.opts if o.startswith("--")]
        named = [a for a in [*argv, *flags] if len(a) > 1 and a in err]
        named += [w for w in ("Missing", "No such option", "Got unexpected extra") if w in err]
        assert named, (argv, err)
