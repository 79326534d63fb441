"""``jointwear import`` on tables as labs write them (#37): the metrology readers' sniffer
decides the delimiter and the decimal mark, a stated uncertainty reaches V&V 20, and a CF file
that cannot be read unambiguously is refused naming its variable and the missing attribute."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from jointwear import io
from jointwear.cli import main
from jointwear.compare import load_comparison

THETA = np.arange(0.0, 360.0, 10.0)  # canonical degrees
Z = np.linspace(-6e-3, 6e-3, 5)


def _run(*args) -> int:
    return main([str(a) for a in args])


def _depth(scale: float) -> np.ndarray:
    """Wear [m]: a peak at 240 degree, deeper towards +z."""
    return scale * 8e-6 * np.exp(-(((THETA - 240.0) / 35.0) ** 2))[None, :] * (1 + 30 * Z)[:, None]


def _motion_rows(decimal: str, sep: str) -> tuple[list[str], np.ndarray, np.ndarray]:
    t = np.linspace(0.0, 1.0, 41)
    v = np.column_stack([123.456 * np.sin(4 * np.pi * t), 80.25 * np.cos(4 * np.pi * t)])
    rows = [sep.join(["time", "vx", "vy"])]
    for ti, (x, y) in zip(t, v, strict=True):
        rows.append(sep.join(f"{a:.6f}".replace(".", decimal) for a in (ti, x, y)))
    return rows, t, v


@pytest.mark.parametrize(("decimal", "sep"), [(",", ";"), (",", "\t"), (".", ",")])
def test_a_decimal_comma_motion_table_reads_as_numbers(tmp_path, decimal, sep, capsys):
    rows, t, v = _motion_rows(decimal, sep)
    src = tmp_path / "motion.csv"
    src.write_text("# exported by a spreadsheet\n" + "\n".join(rows) + "\n", encoding="utf-8")
    out = tmp_path / "m.nc"
    assert _run("import", "motion", src, "--origin", "measured", "--velocity-unit", "mm/s",
                "--velocity-columns", "vx,vy", "--out", out) == 0  # fmt: skip
    ds = io.load(out)
    np.testing.assert_allclose(ds["time"].values, t, atol=1e-9)
    np.testing.assert_allclose(ds["follower_velocity"].values, v * 1e-3, rtol=1e-6, atol=1e-12)
    said = capsys.readouterr()
    assert f"decimal {'comma' if decimal == ',' else 'point'} (sniffed)" in said.out
    # no uncertainty stated: what that means for V&V 20, and how to state one
    assert "NOT ASSESSED" in said.err and "--u VALUE[unit]" in said.err


def test_given_delimiter_and_decimal_are_used_and_a_bad_one_is_refused(tmp_path, capsys):
    rows, _, v = _motion_rows(",", ";")
    src = tmp_path / "motion.csv"
    src.write_text("\n".join(rows) + "\n", encoding="utf-8")
    out = tmp_path / "m.nc"
    opts = ["--origin", "measured", "--velocity-unit", "mm/s", "--velocity-columns", "vx,vy"]
    assert _run("import", "motion", src, *opts, "--delimiter", "semicolon", "--decimal",
                "comma", "--out", out) == 0  # fmt: skip
    np.testing.assert_allclose(io.load(out)["follower_velocity"].values, v * 1e-3, atol=1e-12)
    assert "decimal comma (given)" in capsys.readouterr().out
    # a decimal point stated for a decimal-comma file: refused, naming the option that fixes it
    assert _run("import", "motion", src, *opts, "--delimiter", "semicolon", "--decimal",
                "point", "--out", tmp_path / "x.nc") == 3  # fmt: skip
    assert "--decimal comma" in capsys.readouterr().err
    assert (
        _run("import", "motion", src, *opts, "--decimal", "semi", "--out", tmp_path / "y.nc") == 3
    )
    assert "--decimal 'semi'" in capsys.readouterr().err


def _wear_csv(path, scale: float, u_column: float | None = None) -> None:
    head = "theta_deg;z_mm;depth_um" + (";u_um" if u_column is not None else "")
    rows = [head]
    d = _depth(scale)
    for i, zi in enumerate(Z):
        for j, th in enumerate(THETA):
            cells = [f"{th:.3f}", f"{zi * 1e3:.3f}", f"{d[i, j] * 1e6:.6f}"]
            cells += [f"{u_column:.3f}"] if u_column is not None else []
            rows.append(";".join(c.replace(".", ",") for c in cells))
    path.write_text("\n".join(rows) + "\n", encoding="utf-8")


_WEAR = ["--angle-zero", "-x", "--angle-direction", "clockwise", "--theta-unit", "deg",
         "--z-unit", "mm", "--depth-unit", "um", "--columns", "theta_deg,z_mm,depth_um",
         "--cycles", "1e6"]  # fmt: skip


def test_a_stated_u_makes_the_vv20_rows_assessed(tmp_path):
    _wear_csv(tmp_path / "sim.csv", 1.0)
    _wear_csv(tmp_path / "meas.csv", 1.1, u_column=0.4)
    sim = tmp_path / "sim.nc"
    assert _run("import", "wearmap", tmp_path / "sim.csv", *_WEAR, "--origin", "simulated",
                "--out", sim) == 0  # fmt: skip
    criteria = tmp_path / "criteria.toml"  # the simulation's own uncertainties, stated
    criteria.write_text("wear_u_input_rel = 0.05\nwear_u_num_rel = 0.02\n", encoding="utf-8")

    def compare(meas, name):
        out = tmp_path / f"metrics-{name}.nc"
        code = _run("compare", sim, meas, "--criteria", criteria, "--out", out)
        assert code in (0, 1)
        return load_comparison(out)

    bare = tmp_path / "bare.nc"
    assert _run("import", "wearmap", tmp_path / "meas.csv", *_WEAR, "--origin", "measured",
                "--out", bare) == 0  # fmt: skip
    c = compare(bare, "bare")
    row = c.decisions[c.decisions.key == "max_wear_depth"].iloc[0]
    assert row.state == "not_assessed" and "u_D not assessed" in row.reason

    for name, how in (
        ("value", ["--u", "0.8um", "--u-k", "2"]),  # expanded 0.8 um at k = 2: 0.4 um standard
        ("column", ["--u-column", "u_um", "--u-k", "1"]),  # 0.4 um per point, standard
    ):
        path = tmp_path / f"{name}.nc"
        assert _run("import", "wearmap", tmp_path / "meas.csv", *_WEAR, "--origin",
                    "measured", *how, "--u-covers", "probe noise and calibration",
                    "--out", path) == 0  # fmt: skip
        ds = io.load(path)
        np.testing.assert_allclose(ds["wear_depth_u"].values, 0.4e-6, rtol=1e-12)
        assert ds["wear_depth_u"].attrs["coverage_factor"] == 1.0
        assert "probe noise and calibration" in ds["wear_depth_u"].attrs["comment"]
        c = compare(path, name)
        assert c.state("maximum wear depth") in ("pass", "fail")  # decided by V&V 20
        assert c.value("max_wear_depth", "u_D") == pytest.approx(0.4e-6, rel=0.3)


def test_a_u_without_its_coverage_factor_is_refused_and_the_suggestion_runs(tmp_path, capsys):
    _wear_csv(tmp_path / "meas.csv", 1.0)
    base = ["import", "wearmap", tmp_path / "meas.csv", *_WEAR, "--origin", "measured"]
    assert _run(*base, "--u", "0.5um", "--out", tmp_path / "a.nc") == 3
    err = capsys.readouterr().err
    assert "--u-k" in err and "--u-covers" in err
    assert _run(*base, "--u", "0.5um", "--u-k", "1", "--u-covers", "probe noise and calibration",
                "--out", tmp_path / "a.nc") == 0  # fmt: skip
    assert _run(*base, "--u", "0.5 mm/s", "--u-k", "1", "--u-covers", "x",
                "--out", tmp_path / "b.nc") == 3  # fmt: skip
    assert "not a unit of length" in capsys.readouterr().err


def _cf(path, **extra) -> None:
    ds = xr.Dataset(
        {"wear_depth": (("z", "theta"), _depth(1.0) * 1e6, {"units": "um"}), **extra},
        coords={
            "z": ("z", Z, {"units": "m", "z_zero": "bearing mid-width"}),
            "theta": (
                "theta",
                THETA,
                {"units": "degree", "angle_zero": "-x", "angle_direction": "clockwise"},
            ),
        },  # fmt: skip
        attrs={"data_origin": "measured"},
    )
    ds.to_netcdf(path)


def test_a_cf_file_is_refused_naming_its_variable_and_the_missing_attribute(tmp_path, capsys):
    src = tmp_path / "cmm.nc"
    _cf(src, temperature=(("z",), np.full(Z.size, 20.0), {"units": "degC"}))
    assert _run("import", "wearmap", src, "--out", tmp_path / "w.nc") == 3
    err = capsys.readouterr().err
    assert "'temperature' has no 'long_name' attribute" in err and str(src) in err
    assert "w.nc" not in err  # the input is blamed, not the file being written
    # an uncertainty of a contract variable says what it is, and its unit is converted
    _cf(src, wear_depth_u=(("z", "theta"), np.full((Z.size, THETA.size), 0.25), {"units": "um"}))
    assert _run("import", "wearmap", src, "--out", tmp_path / "w.nc") == 0
    ds = io.load(tmp_path / "w.nc")
    np.testing.assert_allclose(ds["wear_depth_u"].values, 0.25e-6)
    np.testing.assert_allclose(ds["wear_depth"].max(), _depth(1.0).max(), rtol=1e-12)
    assert ds["wear_depth_u"].attrs["long_name"].startswith("standard uncertainty of")


def test_a_table_the_sniffer_cannot_decide_is_refused_and_the_suggested_options_read_it(
    tmp_path, capsys
):
    # a column of words beside the numbers: the sniffer cannot decide the decimal mark
    rows, t, v = _motion_rows(",", ";")
    rows = [rows[0] + ";note"] + [r + ";ok" for r in rows[1:]]
    src = tmp_path / "motion.csv"
    src.write_text("\n".join(rows) + "\n", encoding="utf-8")
    opts = ["--origin", "measured", "--velocity-unit", "mm/s", "--velocity-columns", "vx,vy"]
    assert _run("import", "motion", src, *opts, "--out", tmp_path / "a.nc") == 3
    err = capsys.readouterr().err
    assert "give --decimal comma (and --delimiter)" in err
    assert _run("import", "motion", src, *opts, "--decimal", "comma", "--delimiter", "semicolon",
                "--out", tmp_path / "a.nc") == 0  # fmt: skip
    np.testing.assert_allclose(
        io.load(tmp_path / "a.nc")["follower_velocity"].values, v * 1e-3, atol=1e-12
    )
