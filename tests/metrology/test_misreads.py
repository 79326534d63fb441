"""Every input that used to be silently misread (issue 14) is refused with the settling option,
or read right once the option is given. Each file is built here with exactly that defect."""

from __future__ import annotations

import numpy as np
import pytest

from jointwear.cli import main
from jointwear.errors import BadInputError
from jointwear.metrology.readers import read_scan, read_talyrond

CONV = ("+x", "counterclockwise")


def _table(path, angles, values, head=""):
    path.write_text(
        head + "".join(f"{a:.9g}\t{v:.6f}\n" for a, v in zip(angles, values, strict=True))
    )
    return path


def _read(path, **options):
    """The file read in the test convention, values in µm unless ``units`` says otherwise."""
    return read_scan(path, convention=CONV, **{"units": "um", **options})


def _dev(n):
    """A deviation profile about zero [um] (second harmonic, 2 um)."""
    return 2.0 * np.cos(2 * np.linspace(0, 2 * np.pi, n, endpoint=False))


# --- angle unit and span ------------------------------------------------------------------


def test_half_turn_of_integer_degrees_is_not_taken_as_an_index(tmp_path):
    f = _table(tmp_path / "half.txt", np.arange(180), _dev(180))
    with pytest.raises(
        BadInputError,
        match=r"ambiguous.*as degrees: a partial arc of 180.*"
        r"as a point index: one full turn.*--arc.*--angle-unit",
    ) as exc:
        _read(f)
    assert "half.txt" in str(exc.value)
    ds = _read(f, angle_unit="deg")
    th = np.sort(ds["theta"].values)
    # a half turn at 1 degree, not 0..358 at 2 degree: consecutive angles 1 degree apart
    assert ds.sizes["theta"] == 180
    assert np.median(np.diff(th)) == pytest.approx(1.0)
    assert ds.attrs["reader_guesses"]["half.txt"]["angle"].startswith("angle unit deg (stated)")
    # --arc partial settles it as well (only degrees give a partial arc)
    ds2 = _read(f, arc="partial")
    np.testing.assert_allclose(ds2["theta"].values, ds["theta"].values)
    # and the index reading on request: a full turn of 2 degree steps
    ds3 = _read(f, angle_unit="index")
    assert np.median(np.diff(np.sort(ds3["theta"].values))) == pytest.approx(2.0)


def test_two_turns_of_integer_degrees_are_not_squeezed_into_one(tmp_path):
    f = _table(tmp_path / "two.txt", np.arange(720), _dev(720))
    with pytest.raises(BadInputError, match=r"ambiguous.*as degrees: 2 turns.*point index"):
        _read(f)
    with pytest.raises(BadInputError, match=r"2 full turns.*at most one turn.*split"):
        _read(f, angle_unit="deg")
    ds = _read(f, arc="full")  # only an index gives one turn
    assert np.median(np.diff(np.sort(ds["theta"].values))) == pytest.approx(0.5)


def test_radians_are_not_read_as_degrees(tmp_path):
    a = np.arange(8) * np.pi / 4  # 0 .. 7 pi / 4
    f = _table(tmp_path / "rad8.txt", a, _dev(8))
    with pytest.raises(
        BadInputError,
        match=r"ambiguous.*as degrees: a partial arc of 6.28.*"
        r"as radians: one full turn of 8 points",
    ):
        _read(f)
    ds = _read(f, arc="full")
    assert np.median(np.diff(np.sort(ds["theta"].values))) == pytest.approx(45.0)


def test_a_small_arc_in_degrees_is_not_read_as_radians(tmp_path):
    a = np.linspace(0.0, 6.0, 100)  # a 6 degree arc of 100 points
    f = _table(tmp_path / "arc6.txt", a, _dev(100))
    # both readings are partial arcs (6 degree, or 347 degree in radians): --arc cannot settle it
    with pytest.raises(
        BadInputError,
        match=r"as degrees: a partial arc of 6.06.*as radians: a "
        r"partial arc of 347.*--angle-unit",
    ) as exc:
        _read(f)
    assert "--arc" not in str(exc.value)
    ds = _read(f, angle_unit="deg")
    assert np.ptp(ds["theta"].values) == pytest.approx(6.0, abs=1e-6)


def test_unambiguous_angles_need_no_option(tmp_path):
    a = np.arange(3600) * 0.1  # 0.0 .. 359.9: only degrees give at most one turn
    f = _table(tmp_path / "deg.txt", a, _dev(3600))
    ds = _read(f)
    note = ds.attrs["reader_guesses"]["deg.txt"]["angle"]
    assert note.startswith("angle unit deg: the only reading")
    # 0..359 integers: degrees and index give the same angles - nothing to decide
    g = _table(tmp_path / "int.txt", np.arange(360), _dev(360))
    ds2 = read_scan(g, convention=CONV, units="um")
    np.testing.assert_allclose(np.sort(ds2["theta"].values), np.arange(360.0), atol=1e-9)


def test_header_states_the_angle_unit_and_contradiction_is_refused(tmp_path):
    f = _table(tmp_path / "h.txt", np.arange(180), _dev(180), head="Angle unit: deg\n")
    ds = _read(f)
    assert ds.sizes["theta"] == 180 and np.ptp(ds["theta"].values) == pytest.approx(179.0)
    with pytest.raises(BadInputError, match=r"--angle-unit\) contradicts the file.*'deg'"):
        _read(f, angle_unit="index")
    g = _table(
        tmp_path / "hn.txt", np.arange(180), _dev(180), head="Angle unit: rad\nAngle (deg)\tDev\n"
    )
    with pytest.raises(BadInputError, match=r"contradicts itself.*'deg'.*header.*'rad'"):
        read_scan(g, convention=CONV, units="um")


def test_values_without_angle_column_need_the_span(tmp_path):
    f = tmp_path / "vals.txt"
    f.write_text("".join(f"{v:.4f}\n" for v in _dev(90)))
    with pytest.raises(BadInputError, match=r"no angle column.*--arc full"):
        _read(f)
    ds = _read(f, arc="full")
    assert np.median(np.diff(np.sort(ds["theta"].values))) == pytest.approx(4.0)
    # the Talyrond preset states it (its traces are whole revolutions)
    read_talyrond(f, convention=CONV)


# --- value kind ---------------------------------------------------------------------------


def test_radius_deviation_column_is_a_deviation(tmp_path):
    f = _table(
        tmp_path / "rd.txt",
        np.arange(360) * 1.0,
        _dev(360) + 30.0,  # offset 30 um, 4 um ptp
        head="Angle (deg)\tRadius deviation (um)\n",
    )
    ds = read_scan(f, convention=CONV)
    assert "radial_deviation" in ds and "radius" not in ds
    assert float(ds["radial_deviation"].mean()) == pytest.approx(30e-6, rel=1e-6)


def test_one_corrupt_negative_radius_does_not_flip_the_column(tmp_path):
    v = 25000.0 + _dev(360)  # radius 25 mm in um
    v[100] = -25000.0
    f = _table(tmp_path / "neg.txt", np.arange(360) * 1.0, v)
    with pytest.raises(
        BadInputError,
        match=r"neg.txt.* line 101: the values look like radii.*"
        r"-25000.*--value-kind",
    ):
        _read(f)
    # even when the user says radius, a negative radius is refused naming the line
    with pytest.raises(BadInputError, match=r"line 101: radius -25000 is not positive"):
        _read(f, value="radius")
    # named 'Radius': same
    g = _table(tmp_path / "negn.txt", np.arange(360) * 1.0, v, head="Angle (deg)\tRadius (um)\n")
    with pytest.raises(BadInputError, match=r"line 102: radius -25000 is not positive"):
        read_scan(g, convention=CONV)
    # the clean column is a radius without asking
    v[100] = v[99]
    ds = read_scan(
        _table(tmp_path / "ok.txt", np.arange(360) * 1.0, v), convention=CONV, units="um"
    )
    assert "radius" in ds and float(ds["radius"].mean()) == pytest.approx(25e-3, rel=1e-6)


def test_value_kind_that_the_numbers_cannot_tell_is_refused(tmp_path):
    v = 100.0 + _dev(360)  # 100 um offset, 4 um spread: a 0.1 mm radius? a deviation?
    f = _table(tmp_path / "amb.txt", np.arange(360) * 1.0, v)
    with pytest.raises(BadInputError, match=r"cannot tell radius from deviation.*--value-kind"):
        _read(f)
    ds = _read(f, value="deviation")
    assert float(ds["radial_deviation"].mean()) == pytest.approx(100e-6, rel=1e-6)


def test_deviation_name_with_radius_numbers_is_refused(tmp_path):
    f = _table(
        tmp_path / "dn.txt",
        np.arange(360) * 1.0,
        25000.0 + _dev(360),
        head="Angle (deg)\tDeviation (um)\n",
    )
    with pytest.raises(BadInputError, match=r"name says deviation but the values.*look like radii"):
        read_scan(f, convention=CONV)


# --- units, magnitudes, manifests, truncation ----------------------------------------------


def test_units_option_contradicting_the_header_is_an_error(tmp_path):
    f = _table(
        tmp_path / "mm.txt", np.arange(360) * 1.0, 25.0 + _dev(360) * 1e-3, head="Units: mm\n"
    )
    with pytest.raises(BadInputError, match=r"mm.txt'.*--units um.*contradicts.*'mm' in line 1"):
        _read(f)
    ds = read_scan(f, convention=CONV, units="mm")  # agreeing is fine
    assert float(ds["radius"].mean()) == pytest.approx(25e-3, rel=1e-9)
    # a column name stating another unit than the header: the file contradicts itself
    g = _table(
        tmp_path / "self.txt",
        np.arange(360) * 1.0,
        _dev(360),
        head="Units: mm\nAngle (deg)\tDeviation [um]\n",
    )
    with pytest.raises(BadInputError, match=r"states different length units"):
        read_scan(g, convention=CONV)


@pytest.mark.parametrize("bad", ["1e300", "1e999", "-inf"])  # 'nan': a missing point (#38)
def test_absurd_or_non_finite_values_name_the_line(tmp_path, bad):
    lines = [f"{i}\t{v:.4f}" for i, v in enumerate(_dev(360) * 1.0)]
    lines[41] = f"41\t{bad}"
    f = tmp_path / "big.txt"
    f.write_text("Units: um\n" + "\n".join(lines) + "\n")
    with pytest.raises(BadInputError, match=r"big.txt' line 43"):
        read_scan(f, convention=CONV, angle_unit="deg")


def test_manifest_naming_an_absent_file_is_an_error(tmp_path):
    d = tmp_path / "scan"
    d.mkdir()
    for k in (1, 2, 4):
        _table(d / f"layer0{k}.txt", np.arange(360) * 1.0, _dev(360), head="Units: um\n")
    (d / "manifest.csv").write_text(
        "file,z_mm\nlayer01.txt,0\nlayer02.txt,1\nlayer03.txt,2\nlayer04.txt,3\n"
    )
    with pytest.raises(
        BadInputError,
        match=r"manifest.csv' line 4: names 'layer03.txt', which "
        r"is not in",
    ):
        read_scan(d, convention=CONV)
    (d / "manifest.csv").write_text("file,z_mm\nlayer01.txt,0\nlayer02.txt,1\nlayer04.txt,3\n")
    ds = read_scan(d, convention=CONV)
    np.testing.assert_allclose(ds["z"].values, np.array([-1.5, -0.5, 1.5]) * 1e-3, atol=1e-12)


def test_manifest_without_unit_is_not_read_in_metres(tmp_path):
    d = tmp_path / "scan"
    d.mkdir()
    for k in (1, 2):
        _table(d / f"layer0{k}.txt", np.arange(360) * 1.0, _dev(360), head="Units: um\n")
    (d / "manifest.csv").write_text("layer01.txt,0\nlayer02.txt,2\n")
    with pytest.raises(BadInputError, match=r"unit of z is not stated.*z_units="):
        read_scan(d, convention=CONV)
    ds = read_scan(d, convention=CONV, z_units="mm")
    assert float(np.ptp(ds["z"].values)) == pytest.approx(2e-3)


def test_last_number_cut_without_final_newline(tmp_path):
    body = "".join(f"{i}\t{v:.4f}\n" for i, v in enumerate(_dev(360)))
    f = tmp_path / "cut.txt"
    f.write_text("Units: um\n" + body[:-3])  # '...\t2.0000\n' cut to '...\t2.00'
    with pytest.raises(
        BadInputError,
        match=r"cut.txt' line 361: the file ends without a "
        r"newline.*2 decimal.*4.*cut off",
    ):
        read_scan(f, convention=CONV, angle_unit="deg")
    g = tmp_path / "whole.txt"
    g.write_text("Units: um\n" + body[:-1])  # complete, only the newline is missing
    ds = read_scan(g, convention=CONV, angle_unit="deg")
    assert ds.sizes["theta"] == 360
    assert "not cut" in ds.attrs["reader_guesses"]["whole.txt"]["last_line"]


def test_long_file_z_column_unit_is_not_borrowed_from_the_values(tmp_path):
    rows = [
        f"{z}\t{a}\t{v:.4f}" for z in (0, 2) for a, v in zip(range(360), _dev(360), strict=True)
    ]
    f = tmp_path / "long.txt"
    f.write_text("Units: um\nAngle unit: deg\n" + "\n".join(rows) + "\n")
    with pytest.raises(BadInputError, match=r"unit of the z column is not stated.*z_units="):
        read_scan(f, convention=CONV)
    ds = read_scan(f, convention=CONV, z_units="mm")
    assert float(np.ptp(ds["z"].values)) == pytest.approx(2e-3)


# --- the command line speaks the same options ------------------------------------------------


def test_cli_refuses_with_exit_3_and_accepts_with_the_flag(tmp_path, capsys, run_import):
    f = _table(tmp_path / "half.txt", np.arange(180), _dev(180))
    o = tmp_path / "o.nc"
    assert run_import(f, o, "--units", "um") == 3
    assert "--angle-unit" in capsys.readouterr().err
    assert run_import(f, o, "--units", "um", "--angle-unit", "degrees") == 2  # not a choice
    assert run_import(f, o, "--units", "um", "--layout", "diagonal") == 2
    assert run_import(f, o, "--units", "furlong") == 2
    assert run_import(f, o, "--units", "um", "--decimal", ";") == 2
    assert run_import(f, o, "--units", "um", direction="sideways") == 2  # a usage error too
    assert not o.exists()
    assert run_import(f, o, "--units", "um", "--angle-unit", "deg") == 0
    assert (tmp_path / "o.nc").exists()


def test_corrupt_first_row_is_not_taken_for_column_names(tmp_path):
    # found by the fuzz test: '0.0<TAB>n.a.' above the table was read as the names line and the
    # point silently dropped (an 18-point partial arc instead of a 19-point full turn)
    rows = [f"{a:.1f}\t{v:.4f}" for a, v in zip(np.arange(19) * 360 / 19, _dev(19), strict=True)]
    rows[0] = "0.0\tn.a."
    f = tmp_path / "first.txt"
    f.write_text("Units: um\n" + "\n".join(rows) + "\n")
    with pytest.raises(BadInputError, match=r"first.txt' line 2: .*looks like a row of the table"):
        read_scan(f, convention=CONV)


def test_off_centre_radius_trace_is_still_a_radius(tmp_path):
    # 8 mm bore, 50 um set-up eccentricity and 20 um of wear: spread ~100 um, no column names
    t = np.radians(np.arange(360) * 1.0)
    r = 8000.0 + 50.0 * np.cos(t) - 20.0 * np.exp(-((t - 2.0) ** 2) / 0.1)
    ds = read_scan(_table(tmp_path / "r.txt", np.arange(360) * 1.0, r), convention=CONV, units="um")
    assert "radius" in ds
    np.testing.assert_allclose(np.sort(ds["radius"].values[0]), np.sort(np.round(r, 6)) * 1e-6)


def test_point_numbers_from_one_start_at_zero_degree_and_say_so(tmp_path):
    f = _table(tmp_path / "one.txt", np.arange(1, 721), _dev(720), head="Point\tDeviation [um]\n")
    ds = read_scan(f, convention=("-x", "clockwise"))
    assert float(ds["theta"].min()) == 0.0 and float(ds["theta"].max()) == pytest.approx(359.5)
    assert "point 1 is taken at 0 degree" in ds.attrs["reader_guesses"]["one.txt"]["angle"]


def test_reader_columns_record_the_resolved_meaning(tmp_path):
    f = _table(tmp_path / "res.txt", np.arange(180), _dev(180))
    ds = _read(f, arc="partial")
    assert ds.attrs["reader_columns"] == ["angle_deg", "deviation"]
    ds = _read(f, arc="full")
    assert ds.attrs["reader_columns"] == ["index", "deviation"]


def test_help_texts_keep_their_units(capsys):
    assert main(["metrology", "import", "--help"]) == 0
    out = " ".join(capsys.readouterr().out.replace("│", " ").split())
    assert "Layer spacing [mm]" in out and "mid-width [mm]" in out
    assert main(["metrology", "assess", "--help"]) == 0
    out = " ".join(capsys.readouterr().out.replace("│", " ").split())
    assert "Bore radius in mm" in out and "cut-off in UPR" in out
