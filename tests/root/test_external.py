"""Bringing a user's own data in: CSV and foreign CF netCDF, units and conventions never guessed."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from jointwear import conventions as C
from jointwear import external, io
from jointwear.cli import main
from jointwear.errors import BadInputError, ParameterError

# ---------------------------------------------------------------------------------------------
# truth: a motion history and a wear map, written the way another tool would


def _motion_csv(path, *, unit_factor=1e3, sep=","):
    t = np.linspace(0.0, 0.5, 26) + 12.0  # a record that does not start at 0
    v = np.column_stack([np.sin(8 * t), np.cos(8 * t), 0.01 * t])  # m/s
    lines = [f"# exported by another simulator\nt{sep}vx{sep}vy{sep}vz"]
    lines += [
        sep.join(f"{x:.12g}" for x in (ti, *(vi * unit_factor)))
        for ti, vi in zip(t, v, strict=True)
    ]
    path.write_text("\n".join(lines) + "\n")
    return t - t[0], v


#: the file's convention: 0 along +x, counter-clockwise (the canonical one is -x, clockwise)
FILE_CONVENTION = C.AngleConvention("+x", "counterclockwise")


def _wear_truth():
    theta_c = np.arange(0.0, 360.0, 10.0)  # canonical degrees
    z = np.array([-4e-3, 0.0, 4e-3])
    depth = 5e-6 * np.exp(-(((theta_c - 60.0) / 30.0) ** 2))[None, :] * (1 + 100 * z)[:, None]
    return theta_c, z, depth


def _wear_csv(path):
    theta_c, z, depth = _wear_truth()
    theta_file = FILE_CONVENTION.from_physical(C.CANONICAL.to_physical(theta_c))
    rows = ["theta_deg;z_mm;depth_um"]
    for i, zi in enumerate(z):
        for j, th in enumerate(theta_file):
            rows.append(f"{th:.9f};{zi * 1e3:.6f};{depth[i, j] * 1e6:.9f}")
    path.write_text("\n".join(rows) + "\n")


# ---------------------------------------------------------------------------------------------
# motion


def test_motion_csv_converts_units_and_starts_time_at_zero(tmp_path):
    f = tmp_path / "adams.csv"
    t, v = _motion_csv(f)
    ds = external.import_motion(
        f, velocity_unit="mm/s", time_column="t", data_origin="simulated", tool="Adams"
    )
    np.testing.assert_allclose(ds["time"], t, atol=1e-12)
    np.testing.assert_allclose(ds["follower_velocity"], v, rtol=1e-10)
    assert ds["follower_velocity"].attrs["units"] == "m s-1"
    assert ds.attrs["data_origin"] == "simulated" and ds.attrs["external"] == "yes"
    assert "Adams" in ds.attrs["source"]


def test_motion_udunits_spelling_and_tab_separator(tmp_path):
    f = tmp_path / "m.tsv"
    t, v = _motion_csv(f, unit_factor=1.0, sep="\t")
    ds = external.import_motion(f, velocity_unit="m s-1", time_column="t", data_origin="measured")
    np.testing.assert_allclose(ds["follower_velocity"], v, rtol=1e-10)


@pytest.mark.parametrize(
    ("unit", "match"),
    [("mm", "not a unit of velocity"), ("bananas", "not a unit"), ("", "no unit")],
)
def test_motion_wrong_or_missing_unit_is_refused_naming_the_option(tmp_path, unit, match):
    f = tmp_path / "m.csv"
    _motion_csv(f)
    with pytest.raises(ParameterError, match=match) as info:
        external.import_motion(f, velocity_unit=unit, time_column="t", data_origin="simulated")
    assert "--velocity-unit" in str(info.value)


def test_motion_bad_rows_are_named(tmp_path):
    f = tmp_path / "m.csv"
    f.write_text("time,vx,vy\n0,1,2\n0.1,nan,2\n0.2,1,2\n")
    with pytest.raises(BadInputError, match="data row 2"):
        external.import_motion(
            f, velocity_unit="m/s", velocity_columns=("vx", "vy"), data_origin="simulated"
        )
    f.write_text("time,vx,vy\n0,1,2\n0.1,1,2\n0.1,1,2\n")
    with pytest.raises(BadInputError, match="time must increase"):
        external.import_motion(
            f, velocity_unit="m/s", velocity_columns=("vx", "vy"), data_origin="simulated"
        )
    f.write_text("time,vx,vy\n0,1,2\n0.1,1,2\n")
    with pytest.raises(BadInputError, match="no column 'speed_x'"):
        external.import_motion(
            f, velocity_unit="m/s", velocity_columns=("speed_x", "vy"), data_origin="simulated"
        )


def test_motion_origin_must_be_stated(tmp_path):
    f = tmp_path / "m.csv"
    _motion_csv(f)
    with pytest.raises(ParameterError, match="--origin"):
        external.import_motion(f, velocity_unit="mm/s", time_column="t", data_origin="model")


# ---------------------------------------------------------------------------------------------
# wear maps


def test_wear_map_csv_lands_on_the_canonical_convention(tmp_path):
    f = tmp_path / "wear.csv"
    _wear_csv(f)
    ds = external.import_wear_map(
        f,
        columns=("theta_deg", "z_mm", "depth_um"),
        theta_unit="deg",
        z_unit="mm",
        depth_unit="um",
        angle_zero="+x",
        angle_direction="counterclockwise",
        data_origin="measured",
    )
    theta_c, z, depth = _wear_truth()
    assert C.angle_convention_of(ds) == C.CANONICAL
    np.testing.assert_allclose(ds["theta"], theta_c, atol=1e-6)
    np.testing.assert_allclose(ds["z"], z, atol=1e-12)
    np.testing.assert_allclose(ds["wear_depth"], depth, rtol=1e-8, atol=1e-15)
    C.validate(ds)


def test_wear_map_read_with_the_wrong_convention_moves_the_peak(tmp_path):
    # the convention is what decides where the wear is: the same file with another stated zero
    # puts the maximum elsewhere, so it must be given, never assumed
    f = tmp_path / "wear.csv"
    _wear_csv(f)
    kw = dict(
        columns=("theta_deg", "z_mm", "depth_um"), theta_unit="deg", z_unit="mm", depth_unit="um"
    )
    right = external.import_wear_map(
        f, angle_zero="+x", angle_direction="counterclockwise", data_origin="measured", **kw
    )
    wrong = external.import_wear_map(
        f, angle_zero="-x", angle_direction="clockwise", data_origin="measured", **kw
    )
    peak = lambda d: float(d["theta"][d["wear_depth"].isel(z=1).argmax(dim="theta")])  # noqa: E731
    assert peak(right) == pytest.approx(60.0)
    assert peak(wrong) != pytest.approx(60.0)


def test_wear_map_incomplete_grid_and_duplicates_are_refused(tmp_path):
    f = tmp_path / "w.csv"
    f.write_text("theta,z,wear_depth\n0,0,1\n120,0,1\n240,0,1\n0,1,1\n120,1,1\n")
    args = dict(
        theta_unit="deg", z_unit="mm", depth_unit="um", angle_zero="-x",
        angle_direction="clockwise", data_origin="simulated",
    )  # fmt: skip
    with pytest.raises(BadInputError, match="1 point\\(s\\) missing"):
        external.import_wear_map(f, **args)
    f.write_text("theta,z,wear_depth\n0,0,1\n120,0,1\n240,0,1\n360,0,2\n")
    with pytest.raises(BadInputError, match="more than once"):
        external.import_wear_map(f, **args)


# ---------------------------------------------------------------------------------------------
# foreign CF netCDF


def _foreign_cf(path, *, with_convention=True, origin="simulated"):
    theta_c, z, depth = _wear_truth()
    theta_file = FILE_CONVENTION.from_physical(C.CANONICAL.to_physical(theta_c))
    order = np.argsort(theta_file)
    theta_attrs = {"units": "degrees"}
    if with_convention:
        theta_attrs.update(angle_zero="+x", angle_direction="counterclockwise")
    ds = xr.Dataset(
        {
            "wear_depth": (
                ("z", "theta"),
                depth[:, order] * 1e6,
                {"units": "um", "long_name": "wear"},
            )
        },
        coords={
            "z": ("z", z * 1e3, {"units": "mm"}),
            "theta": ("theta", theta_file[order], theta_attrs),
        },
        attrs={"Conventions": "CF-1.8", "source": "MATLAB wear script"},
    )
    if origin:
        ds.attrs["data_origin"] = origin
    ds.to_netcdf(path)


def test_foreign_cf_netcdf_is_converted_and_recorded_as_external(tmp_path):
    f = tmp_path / "matlab.nc"
    _foreign_cf(f)
    ds = external.import_cf(f)
    theta_c, z, depth = _wear_truth()
    np.testing.assert_allclose(ds["theta"], theta_c, atol=1e-6)
    np.testing.assert_allclose(ds["wear_depth"], depth, rtol=1e-8, atol=1e-15)
    assert ds["wear_depth"].attrs["units"] == "m" and ds["z"].attrs["units"] == "m"
    assert ds.attrs["data_origin"] == "simulated" and ds.attrs["external"] == "yes"
    out = io.save(ds, tmp_path / "imported.nc", inputs=[f])
    back = io.load(out)
    assert back.attrs["data_origin"] == "simulated"
    assert io.parse_provenance(back)["inputs"][0]["sha256"]


def test_foreign_cf_without_convention_or_origin_is_refused(tmp_path):
    f = tmp_path / "a.nc"
    _foreign_cf(f, with_convention=False)
    with pytest.raises(BadInputError, match="--angle-zero and --angle-direction"):
        external.import_cf(f)
    ds = external.import_cf(f, angle_zero="+x", angle_direction="counterclockwise")
    assert float(ds["theta"][ds["wear_depth"].isel(z=1).argmax(dim="theta")]) == pytest.approx(60.0)
    g = tmp_path / "b.nc"
    _foreign_cf(g, origin=None)
    with pytest.raises(ParameterError, match="--origin"):
        external.import_cf(g)
    with pytest.raises(BadInputError, match="states data_origin"):
        external.import_cf(
            f, data_origin="measured", angle_zero="+x", angle_direction="counterclockwise"
        )


# ---------------------------------------------------------------------------------------------
# command line


def test_cli_imports_csv_and_refuses_missing_units(tmp_path, capsys):
    f = tmp_path / "wear.csv"
    _wear_csv(f)
    out = tmp_path / "wear_imported.nc"
    base = ["import", "wearmap", str(f), "--out", str(out), "--columns", "theta_deg,z_mm,depth_um"]
    code = main([*base, "--origin", "measured", "--angle-zero", "+x"])
    assert code == 3
    err = capsys.readouterr().err
    assert "--angle-direction" in err and "--theta-unit" in err and not out.exists()
    code = main(
        [*base, "--origin", "measured", "--angle-zero", "+x", "--angle-direction",
         "counterclockwise", "--theta-unit", "deg", "--z-unit", "mm", "--depth-unit", "um"]
    )  # fmt: skip
    assert code == 0
    ds = io.load(out)
    assert ds.attrs["data_origin"] == "measured"
    assert float(ds["theta"][ds["wear_depth"].isel(z=1).argmax(dim="theta")]) == pytest.approx(60.0)


def test_cli_motion_csv_names_every_missing_flag_and_reads_once_given(tmp_path, capsys):
    f = tmp_path / "m.csv"
    t, v = _motion_csv(f)  # mm/s
    out = tmp_path / "m.nc"
    base = ["import", "motion", str(f), "--out", str(out), "--time-column", "t"]
    assert main(base) == 3
    err = capsys.readouterr().err
    assert "--origin" in err and "--velocity-unit" in err and not out.exists()
    assert main([*base, "--origin", "simulated"]) == 3
    err = capsys.readouterr().err
    assert "--velocity-unit" in err and "--origin" not in err
    assert main([*base, "--origin", "simulated", "--velocity-unit", "mm/s"]) == 0
    np.testing.assert_allclose(io.load(out)["follower_velocity"], v, rtol=1e-10)


def test_cli_netcdf_without_the_variable_is_refused(tmp_path, capsys):
    f = tmp_path / "force.nc"  # a CF record of something else
    xr.Dataset(
        {"contact_force": ("time", np.ones(3), {"units": "N"})},
        coords={"time": ("time", np.arange(3.0), {"units": "s"})},
        attrs={"data_origin": "simulated"},
    ).to_netcdf(f)
    out = tmp_path / "m.nc"
    assert main(["import", "motion", str(f), "--out", str(out)]) == 3
    assert "has no variable 'follower_velocity'" in capsys.readouterr().err
    assert not out.exists()


def test_cli_bad_origin_is_a_usage_error(tmp_path):
    f = tmp_path / "m.csv"
    _motion_csv(f)
    code = main(
        ["import", "motion", str(f), "--out", str(tmp_path / "m.nc"), "--origin", "model",
         "--velocity-unit", "mm/s", "--time-column", "t"]
    )  # fmt: skip
    assert code == 2


def _si_wear_file(path, attrs):
    """The true wear map in SI units (no angle convention), global ``attrs``, as netCDF."""
    theta_c, z, depth = _wear_truth()
    xr.Dataset(
        {"wear_depth": (("z", "theta"), depth, {"units": "m"})},
        coords={"z": ("z", z, {"units": "m"}), "theta": ("theta", theta_c, {"units": "degree"})},
        attrs=attrs,
    ).to_netcdf(path)


def test_loading_a_foreign_cf_file_points_to_jointwear_import(tmp_path):
    path = tmp_path / "foreign.nc"
    _si_wear_file(path, {"Conventions": "CF-1.11", "title": "wear from another tool"})
    with pytest.raises(BadInputError, match="jointwear import wearmap") as info:
        io.load(path)
    assert "not written by jointwear" in str(info.value)


def _foreign_wear(path, *, origin=None, convention=True, z_zero=True):
    theta_c, z, depth = _wear_truth()
    z_attrs = {"units": "mm", "z_zero": "bearing mid-width"} if z_zero else {"units": "mm"}
    theta_attrs = {"units": "degree"}
    if convention:
        theta_attrs.update(angle_zero="-x", angle_direction="clockwise")
    attrs = {"Conventions": "CF-1.11", "title": "wear from another tool", "source": "MATLAB"}
    if origin:
        attrs["data_origin"] = origin
    xr.Dataset(
        {"wear_depth": (("z", "theta"), depth * 1e6, {"units": "um"})},
        coords={"z": ("z", z * 1e3, z_attrs), "theta": ("theta", theta_c, theta_attrs)},
        attrs=attrs,
    ).to_netcdf(path)
    return depth


def test_foreign_cf_is_accepted_for_comparison_with_a_warning(tmp_path):
    path = tmp_path / "matlab.nc"
    depth = _foreign_wear(path)
    said: list[str] = []
    ds = external.load_for_comparison(path, role="measured", warn=said.append)
    np.testing.assert_allclose(ds["wear_depth"].transpose("z", "theta"), depth, rtol=1e-12)
    assert ds.attrs["external"] == "yes" and ds.attrs["data_origin"] == "measured"
    assert ds.attrs["data_origin_stated"] == "no"
    assert len(said) == 1 and "does not state what its numbers are" in said[0]
    assert "--origin" in said[0]


def test_foreign_cf_stating_its_origin_keeps_it(tmp_path):
    path = tmp_path / "synthetic.nc"
    _foreign_wear(path, origin="synthetic")
    with pytest.warns(UserWarning, match="not written by jointwear"):
        ds = external.load_for_comparison(path, role="measured")
    assert ds.attrs["data_origin"] == "synthetic" and ds.attrs["data_origin_stated"] == "yes"


def test_foreign_cf_without_angle_convention_is_refused_for_comparison(tmp_path):
    path = tmp_path / "noconv.nc"
    _foreign_wear(path, convention=False)
    with pytest.raises(BadInputError, match="jointwear import wearmap"):
        external.load_for_comparison(path, role="measured", warn=lambda s: None)


def test_foreign_cf_without_z_zero_is_refused_for_comparison(tmp_path):
    path = tmp_path / "noz.nc"
    _foreign_wear(path, z_zero=False)
    with pytest.raises(BadInputError, match="z_zero"):
        external.load_for_comparison(path, role="measured", warn=lambda s: None)


def test_a_broken_jointwear_file_is_not_taken_as_foreign(tmp_path):
    path = tmp_path / "broken.nc"
    _si_wear_file(path, {"provenance": "{}", "title": "t"})
    with pytest.raises(BadInputError, match="data contract"):
        external.load_for_comparison(path, role="simulated", warn=lambda s: None)
