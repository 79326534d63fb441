"""A user's own data - another simulator's CSV and another tool's measurements - goes through
``jointwear import``, ``compare`` and ``report`` like jointwear's own files.

Truth by construction: the "measured" wear map is the simulated one times 1.1 and the measured
velocities are the simulated ones times 1.05, so the relative errors are -1/11 and -0.05/1.05
exactly, whatever the grids.
"""

from __future__ import annotations

import csv

import numpy as np
import pytest

from jointwear import io
from jointwear.cli import main

THETA = np.arange(0.0, 360.0, 5.0)  # canonical degrees (0 along -x, clockwise)
Z = np.linspace(-6e-3, 6e-3, 7)


def _depth(scale: float) -> np.ndarray:
    return scale * 8e-6 * np.exp(-(((THETA - 240.0) / 35.0) ** 2))[None, :] * (1 + 30 * Z)[:, None]


def _wear_csv(path, scale):
    rows = ["theta_deg,z_mm,depth_um"]
    d = _depth(scale)
    for i, zi in enumerate(Z):
        rows += [f"{th:.6f},{zi * 1e3:.6f},{d[i, j] * 1e6:.9f}" for j, th in enumerate(THETA)]
    path.write_text("\n".join(rows) + "\n")


def _motion_csv(path, scale):
    t = np.linspace(0.0, 1.0, 101)
    w = 2 * np.pi * 2.0  # two crank cycles of 0.5 s
    rows = ["time,vx,vy,vz"]
    rows += [
        f"{ti:.6f},{scale * 100 * np.sin(w * ti):.9f},{scale * 80 * np.cos(w * ti):.9f},"
        f"{scale * 3 * np.sin(2 * w * ti):.9f}"
        for ti in t
    ]
    path.write_text("\n".join(rows) + "\n")


def _run(*args: str) -> int:
    return main([str(a) for a in args])


def test_csv_from_another_simulator_and_tool_reach_compare_and_report(tmp_path):
    _wear_csv(tmp_path / "adams_wear.csv", 1.0)
    _wear_csv(tmp_path / "cmm_wear.csv", 1.1)
    _motion_csv(tmp_path / "adams_motion.csv", 1.0)
    _motion_csv(tmp_path / "dic_motion.csv", 1.05)
    wear_opts = [
        "--angle-zero", "-x", "--angle-direction", "clockwise", "--theta-unit", "deg",
        "--z-unit", "mm", "--depth-unit", "um", "--columns", "theta_deg,z_mm,depth_um",
    ]  # fmt: skip
    sim_w, meas_w = tmp_path / "sim_wear.nc", tmp_path / "meas_wear.nc"
    sim_m, meas_m = tmp_path / "sim_motion.nc", tmp_path / "meas_motion.nc"
    assert _run("import", "wearmap", tmp_path / "adams_wear.csv", *wear_opts, "--origin",
                "simulated", "--cycles", "1e6", "--tool", "Adams 2024", "--out", sim_w) == 0  # fmt: skip
    assert _run("import", "wearmap", tmp_path / "cmm_wear.csv", *wear_opts, "--origin",
                "measured", "--cycles", "1e6", "--tool", "CMM", "--out", meas_w) == 0  # fmt: skip
    assert _run("import", "motion", tmp_path / "adams_motion.csv", "--origin", "simulated",
                "--velocity-unit", "mm/s", "--tool", "Adams 2024", "--out", sim_m) == 0  # fmt: skip
    assert _run("import", "motion", tmp_path / "dic_motion.csv", "--origin", "measured",
                "--velocity-unit", "mm/s", "--tool", "VIC-3D", "--out", meas_m) == 0  # fmt: skip
    assert io.load(meas_w).attrs["data_origin"] == "measured"

    table = tmp_path / "metrics.csv"
    code = _run("compare", sim_w, meas_w, "--sim", sim_m, "--meas", meas_m, "--period", "0.5",
                "--out", tmp_path / "metrics.nc", "--table", table)  # fmt: skip
    assert code in (0, 1)  # 1 only if a default criterion fails; the numbers are what we check
    with table.open(encoding="utf-8", newline="") as fh:
        rows = {(r["quantity"], r["metric"]): r for r in csv.DictReader(fh)}
    assert float(rows[("max_wear_depth", "relative_error")]["value"]) == pytest.approx(
        -1 / 11, rel=1e-6
    )
    assert float(rows[("max_wear_depth", "value_meas")]["value"]) == pytest.approx(
        1.1 * _depth(1.0).max(), rel=1e-6
    )
    assert float(rows[("follower_velocity_x_rms", "relative_error")]["value"]) == pytest.approx(
        -0.05 / 1.05, rel=1e-3
    )
    assert float(rows[("wear_depth", "max_angle_error")]["value"]) == pytest.approx(0.0, abs=1e-9)

    report = tmp_path / "report.html"
    code = _run("report", "--sim", sim_w, "--sim", sim_m, "--metrology", meas_w, "--dic", meas_m,
                "--period", "0.5", "--out", report)  # fmt: skip
    assert code in (0, 1)
    html = report.read_text(encoding="utf-8")
    for tool in ("Adams 2024", "CMM", "VIC-3D"):
        assert f"external: {tool}" in html


def test_foreign_cf_netcdf_goes_to_compare_with_a_warning(tmp_path, capsys):
    import xarray as xr

    # another tool's wear map in CF netCDF: contract names, its own units, a stated convention,
    # but no jointwear provenance and no data_origin
    theta_file = np.mod(180.0 - THETA, 360.0)  # 0 along +x, counter-clockwise = canonical mirrored
    order = np.argsort(theta_file)
    foreign = xr.Dataset(
        {"wear_depth": (("z", "theta"), _depth(1.1)[:, order] * 1e6, {"units": "um"})},
        coords={
            "z": ("z", Z * 1e3, {"units": "mm", "z_zero": "bearing mid-width"}),
            "theta": (
                "theta",
                theta_file[order],
                {"units": "degree", "angle_zero": "+x", "angle_direction": "counterclockwise"},
            ),
        },
        attrs={"Conventions": "CF-1.11", "title": "CMM wear map", "source": "CMM export"},
    )
    meas = tmp_path / "cmm.nc"
    foreign.to_netcdf(meas)
    _wear_csv(tmp_path / "adams_wear.csv", 1.0)
    sim_w = tmp_path / "sim_wear.nc"
    assert _run("import", "wearmap", tmp_path / "adams_wear.csv", "--angle-zero", "-x",
                "--angle-direction", "clockwise", "--theta-unit", "deg", "--z-unit", "mm",
                "--depth-unit", "um", "--columns", "theta_deg,z_mm,depth_um", "--origin",
                "simulated", "--cycles", "1e6", "--out", sim_w) == 0  # fmt: skip
    capsys.readouterr()
    table = tmp_path / "m.csv"
    code = _run("compare", sim_w, meas, "--cycles", "1e6", "--out", tmp_path / "m.nc",
                "--table", table)  # fmt: skip
    assert code in (0, 1)
    err = capsys.readouterr().err
    assert "not written by jointwear" in err and "--origin" in err
    with table.open(encoding="utf-8", newline="") as fh:
        rows = {(r["quantity"], r["metric"]): r for r in csv.DictReader(fh)}
    # the convention was converted: same peak angle, depth ratio 1/1.1
    assert float(rows[("wear_depth", "max_angle_error")]["value"]) == pytest.approx(0.0, abs=1e-9)
    assert float(rows[("max_wear_depth", "relative_error")]["value"]) == pytest.approx(
        -1 / 11, rel=1e-6
    )
