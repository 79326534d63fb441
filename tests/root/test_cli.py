"""The jointwear command line: version, help, groups, info, exit codes."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import xarray as xr

from jointwear import conventions as C
from jointwear import io
from jointwear._version import __version__
from jointwear.cli import main


def test_version(capsys):
    assert main(["--version"]) == 0
    assert capsys.readouterr().out.strip() == f"jointwear {__version__}"


def test_help_lists_groups(capsys):
    assert main(["--help"]) == 0
    out = capsys.readouterr().out
    for group in ("sim", "dic", "metrology", "compare", "report", "datasets", "info", "demo"):
        assert group in out


def test_single_command_groups_show_no_subcommand_usage(capsys):
    # `jointwear compare A B` and `jointwear report` are commands; groups with sub-commands
    # (sim) still say COMMAND
    for group, has_sub in (("compare", False), ("report", False), ("sim", True)):
        assert main([group, "--help"]) == 0
        usage = next(line for line in capsys.readouterr().out.splitlines() if "Usage:" in line)
        assert ("COMMAND [ARGS]" in usage) == has_sub, usage


def test_usage_error_exit_code(capsys):
    assert main(["no-such-command"]) == 2


def test_python_dash_m():
    res = subprocess.run(
        [sys.executable, "-m", "jointwear", "--version"],
        capture_output=True,
        text=True,
        check=False,
    )
    assert res.returncode == 0
    assert res.stdout.strip() == f"jointwear {__version__}"


def _write(path, *, units=True):
    ds = xr.Dataset(
        {"contact_force": ("time", np.array([1.0, 2.0, 3.0]), {"long_name": "force"})},
        coords={"time": ("time", [0.0, 0.1, 0.2], {"units": "s"})},
    )
    if units:
        ds["contact_force"].attrs["units"] = "N"
    io.save(ds, path, validate=units, parameters={"a": 1})


def test_info_summarises(tmp_path, capsys):
    path = tmp_path / "ok.nc"
    _write(path)
    assert main(["info", str(path)]) == 0
    out = capsys.readouterr().out
    assert "contact_force(time) [N]" in out
    assert "provenance:" in out and "jointwear" in out


def test_info_missing_units_exits_3_naming_variable(tmp_path, capsys):
    path = tmp_path / "bad.nc"
    _write(path, units=False)
    assert main(["info", str(path)]) == 3
    err = capsys.readouterr().err
    assert "'contact_force' has no 'units'" in err
    assert "Traceback" not in err


def test_info_missing_file_exits_3(tmp_path, capsys):
    assert main(["info", str(tmp_path / "nope.nc")]) == 3
    assert "does not exist" in capsys.readouterr().err


def test_theta_helper_attrs():
    th = C.theta_coord([0, 1], C.CANONICAL)
    assert th.attrs["units"] == "degree" and th.attrs["angle_zero"] == "-x"
