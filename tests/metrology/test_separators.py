"""Issue 38 item 1: the field delimiter is decided before the decimal and thousands marks, and a
thousands mark is taken only where every value of its column is grouped by it. Comma CSVs with
three decimals (the commonest export there is) used to read 1000 x wrong with exit 0."""

from __future__ import annotations

import re

import numpy as np
import pytest

from jointwear.errors import BadInputError
from jointwear.metrology.readers import read_scan
from jointwear.metrology.readers.pretext import (
    fields,
    sniff_delimiter,
    sniff_thousands,
    thousands_mark,
)

CONV = ("-x", "clockwise")  # canonical: theta comes back as written


def _dev_um(n, k):
    t = np.radians(np.arange(n) * 360.0 / n)
    return 0.3 * np.cos(2 * t + 0.1 * k) + 0.2 * np.sin(5 * t) + 0.158


def _cell(v, decimals, dec):
    return f"{v:.{decimals}f}".replace(".", dec)


@pytest.mark.parametrize(
    ("delim", "dec"), [(",", "."), (";", "."), (";", ","), ("\t", "."), ("\t", ",")]
)
@pytest.mark.parametrize("decimals", [1, 2, 3, 4, 5, 6])
def test_wide_files_read_right_at_every_number_of_decimals(tmp_path, delim, dec, decimals):
    n = 3600  # angles 0.000 ... 359.900 written with `decimals` decimals (>= 1)
    th = np.arange(n) * 360.0 / n
    dev = [_dev_um(n, k) for k in range(3)]
    lines = ["Units: um", delim.join(["Angle (deg)"] + [f"Dev z={k} mm" for k in range(3)])]
    for i in range(n):
        cells = [_cell(th[i], max(decimals, 1), dec)] + [_cell(d[i], decimals, dec) for d in dev]
        lines.append(delim.join(cells))
    f = tmp_path / "wide.csv"
    f.write_text("\n".join(lines) + "\n")
    ds = read_scan(f, convention=CONV)
    want = np.round(np.array(dev), decimals) * 1e-6
    np.testing.assert_allclose(ds["radial_deviation"].values, want, rtol=0, atol=1e-12)
    np.testing.assert_allclose(ds["theta"].values, th, atol=1e-9)
    np.testing.assert_allclose(np.diff(ds["z"].values), 1e-3, rtol=1e-9)
    assert "thousands" not in ds.attrs["reader_guesses"]["wide.csv"]


@pytest.mark.parametrize(("delim", "dec"), [(",", "."), (";", ","), ("\t", ".")])
@pytest.mark.parametrize("decimals", [2, 3, 4])
def test_long_files_with_angles_above_100_and_z_to_12_mm(tmp_path, delim, dec, decimals):
    n = 720
    th = np.arange(n) * 360.0 / n
    zs = np.linspace(0.0, 12.0, 5)  # 0.000 ... 12.000 mm
    dev = [_dev_um(n, k) for k in range(zs.size)]
    lines = ["Units: um", "Z unit: mm", delim.join(["z", "angle", "dev"])]
    for k, z in enumerate(zs):
        lines += [
            delim.join([_cell(z, 3, dec), _cell(th[i], decimals, dec), _cell(dev[k][i], 3, dec)])
            for i in range(n)
        ]
    f = tmp_path / "long.csv"
    f.write_text("\n".join(lines) + "\n")
    ds = read_scan(f, convention=CONV, angle_unit="deg")
    np.testing.assert_allclose(
        ds["radial_deviation"].values, np.round(dev, 3) * 1e-6, rtol=0, atol=1e-12
    )
    np.testing.assert_allclose(ds["theta"].values, th, atol=1e-9)
    np.testing.assert_allclose(ds["z"].values, (zs - 6.0) * 1e-3, atol=1e-12)


def test_the_issue_file_reads_ront_0_625_um_not_625(tmp_path, run_import):
    """`Angle (deg),Dev z=0 mm,Dev z=1 mm` / `0.0,0.458,0.508` under `Units: um`."""
    import xarray as xr

    from jointwear.metrology import assess

    n = 720
    th = np.arange(n) * 0.5
    t = np.radians(th)
    a = 0.3125 * np.cos(2 * t) + 0.1455  # p-p 0.625 um; the first row is 0.458
    b = 0.3125 * np.cos(3 * t) + 0.1955  # first row 0.508
    f = tmp_path / "issue.csv"
    f.write_text(
        "Units: um\nAngle (deg),Dev z=0 mm,Dev z=1 mm\n"
        + "".join(f"{x:.1f},{u:.3f},{v:.3f}\n" for x, u, v in zip(th, a, b, strict=True))
    )
    assert f.read_text().splitlines()[2] == "0.0,0.458,0.508"
    out = tmp_path / "issue.nc"
    assert run_import(f, out) == 0
    ds = xr.load_dataset(out)
    form = assess(ds)
    np.testing.assert_allclose(form["RONt_LS"].values, [0.625e-6, 0.625e-6], atol=0.002e-6)


def test_a_thousands_mark_needs_every_value_of_its_column_grouped(tmp_path):
    n = 360
    th = np.arange(n) * 1.0
    r = 8000.0 + 1.5 * np.cos(3 * np.radians(th))
    tab = "Units: um\n" + "".join(f"{a:.3f}\t{v:,.4f}\n" for a, v in zip(th, r, strict=True))
    f = tmp_path / "tab.txt"
    f.write_text(tab)
    ds = read_scan(f, convention=CONV, angle_unit="deg")
    np.testing.assert_allclose(ds["radius"].values[0], np.round(r, 4) * 1e-6, rtol=1e-12)
    assert "thousands mark 'comma'" in ds.attrs["reader_guesses"]["tab.txt"]["thousands"]
    # semicolons, decimal comma, space thousands (the mark --help lists: 'space')
    g = tmp_path / "space.txt"
    g.write_text(
        "Units: um\n"
        + "".join(
            f"{a:.3f};{v:,.4f}\n".replace(",", " ").replace(".", ",")
            for a, v in zip(th, r, strict=True)
        )
    )
    ds = read_scan(g, convention=CONV, angle_unit="deg")
    np.testing.assert_allclose(ds["radius"].values[0], np.round(r, 4) * 1e-6, rtol=1e-12)
    ds = read_scan(g, convention=CONV, angle_unit="deg", thousands="space")
    np.testing.assert_allclose(ds["radius"].values[0], np.round(r, 4) * 1e-6, rtol=1e-12)


def test_sniffer_parts_decide_the_delimiter_first():
    assert sniff_delimiter(["0.0,0.458,0.508", "0.5,0.457,0.507"]) == ","
    assert sniff_thousands(["0.0,0.458,0.508", "0.5,0.457,0.507"], ",") is None
    assert sniff_delimiter(["0,000;8.001,234", "1,000;8.000,999"]) == ";"
    assert sniff_thousands(["0,000;8.001,234", "1,000;8.000,999"], ";") == "."
    # a column in which a value of 4+ digits is not grouped: no thousands mark
    assert sniff_thousands(["1\t8,001.5", "2\t8002.5"], "\t") is None
    # the delimiter is never the thousands mark, even if one number looks grouped
    assert sniff_thousands(["0.0,8,001.234", "0.5,8,001.235"], ",") is None
    assert sniff_delimiter(["0.000 100.00 -0.282", "0.000 100.50 -0.281"]) == " "
    assert sniff_delimiter(["1.5", "2.5"]) is None
    assert fields("1,2,", ",") == ["1", "2"]
    assert [thousands_mark(w) for w in ("space", "comma", "point", "apostrophe", "'")] == [
        " ",
        ",",
        ".",
        "'",
        "'",
    ]
    with pytest.raises(BadInputError, match="comma, point, apostrophe or space"):
        thousands_mark("underscore")


def test_a_given_thousands_mark_that_is_the_delimiter_is_refused(tmp_path):
    f = tmp_path / "c.csv"
    f.write_text("Units: um\n" + "".join(f"{a:.1f},{0.1 * a:.3f}\n" for a in range(360)))
    with pytest.raises(BadInputError, match="is the field delimiter"):
        read_scan(f, convention=CONV, thousands="comma")


def test_comma_thousands_in_a_comma_csv_is_not_read_as_two_layers(tmp_path):
    """`0.0,8,001.234`: the comma is the delimiter, so it cannot be a thousands mark; the file
    is not read (a third column of 001.234 is not a layer of radii)."""
    r = 8000.0 + 1.5 * np.cos(3 * np.radians(np.arange(360.0)))
    f = tmp_path / "amb.csv"
    f.write_text(
        "Units: um\nAngle (deg),Radius\n"
        + "".join(f"{a:.1f},{v:,.3f}\n" for a, v in zip(range(360), r, strict=True))
    )
    with pytest.raises(BadInputError, match=r"both separates the fields and groups thousands"):
        read_scan(f, convention=CONV)


# --- issue 38 item 2: a unit claim against the form the numbers make on the stated radius ----


def _small_form(tmp_path, unit_line, nominal_line, form=0.625):
    """A deviation trace of peak-to-valley ``form`` as written (in the file's unit)."""
    n = 720
    th = np.arange(n) * 0.5
    dev = 0.5 * form * np.cos(2 * np.radians(th))
    f = tmp_path / "small.txt"
    f.write_text(
        f"{unit_line}\n{nominal_line}\nAngle (deg)\tDeviation\n"
        + "".join(f"{a:.1f}\t{v:.4f}\n" for a, v in zip(th, dev, strict=True))
    )
    return f, dev


def test_a_sub_um_form_under_a_mm_header_is_refused_naming_both_readings(tmp_path, run_import):
    f, dev = _small_form(tmp_path, "Units: mm", "Nominal diameter: 25 mm")
    with pytest.raises(BadInputError) as exc:
        read_scan(f, convention=CONV)
    msg = str(exc.value)
    assert re.search(r"form \(peak-to-valley\) of 0\.6\d* mm.*read in um it is 0\.6\d* µm", msg)
    assert "form_fraction" in msg
    assert "12.5 mm" in msg
    assert exc.value.suggestions == ({"ignore_header": ("units",), "units": "um"},)
    ds = read_scan(f, convention=CONV, **exc.value.suggestions[0])
    np.testing.assert_allclose(ds["radial_deviation"].values[0], np.round(dev, 4) * 1e-6)
    # the command line names the flags, and they run as printed
    out = tmp_path / "o.nc"
    assert run_import(f, out) == 3
    assert run_import(f, out, "--ignore-header", "units", "--units", "um") == 0


def test_a_form_within_one_percent_of_the_radius_passes(tmp_path):
    # 0.1 mm form on a 12.5 mm radius (0.8 %): a plausible worn bore in mm
    f, dev = _small_form(tmp_path, "Units: mm", "Nominal radius: 12.5 mm", form=0.1)
    ds = read_scan(f, convention=CONV)
    np.testing.assert_allclose(ds["radial_deviation"].values[0], np.round(dev, 4) * 1e-3)
    # the same in um with the nominal stated is of course fine
    g, dev = _small_form(tmp_path, "Units: um", "Nominal radius: 12.5 mm")
    ds = read_scan(g, convention=CONV)
    np.testing.assert_allclose(ds["radial_deviation"].values[0], np.round(dev, 4) * 1e-6)
    # 0.2 mm (1.6 %) is refused, and form_fraction widens the rule
    h, dev = _small_form(tmp_path, "Units: mm", "Nominal radius: 12.5 mm", form=0.2)
    with pytest.raises(BadInputError, match="form_fraction"):
        read_scan(h, convention=CONV)
    ds = read_scan(h, convention=CONV, form_fraction=0.02)
    np.testing.assert_allclose(ds["radial_deviation"].values[0], np.round(dev, 4) * 1e-3)


# --- issue 38 item 4: missing values are NaN points, counted; too many refused ---------------


@pytest.mark.parametrize("mark", ["---", "NaN", "nan", "", "-", "*", "n/a", "#N/A", "invalid"])
@pytest.mark.parametrize("delim", [",", ";", "\t"])
def test_missing_cells_are_nan_points_counted(tmp_path, mark, delim, run_import):
    import xarray as xr

    from jointwear.metrology import assess

    n = 360
    th = np.arange(n) * 1.0
    dev = 0.3 * np.cos(2 * np.radians(th))
    gone = [10, 100, 250]
    rows = [
        delim.join([f"{a:.1f}", mark if i in gone else f"{v:.4f}"])
        for i, (a, v) in enumerate(zip(th, dev, strict=True))
    ]
    f = tmp_path / "miss.csv"
    f.write_text(f"Units: um\nAngle (deg){delim}Deviation\n" + "\n".join(rows) + "\n")
    ds = read_scan(f, convention=CONV)
    v = ds["radial_deviation"].values[0]
    assert np.flatnonzero(np.isnan(v)).tolist() == gone
    want = np.round(dev, 4) * 1e-6
    want[gone] = np.nan
    np.testing.assert_allclose(v, want, rtol=0, atol=1e-12)
    assert ds.attrs["missing_points"] == 3
    assert "3 missing" in ds.attrs["reader_guesses"]["miss.csv"]["missing"]
    # the fit skips them: the LS roundness is that of the 357 points left (limaçon, lstsq)
    ok = np.isfinite(want)
    t = np.radians(ds["theta"].values[ok])
    a = np.column_stack([np.ones(t.size), np.cos(t), np.sin(t)])
    res = want[ok] - a @ np.linalg.lstsq(a, want[ok], rcond=None)[0]
    np.testing.assert_allclose(assess(ds)["RONt_LS"].values[0], np.ptp(res), rtol=1e-9)
    out = tmp_path / "miss.nc"
    assert run_import(f, out) == 0
    assert xr.load_dataset(out).attrs["missing_points"] == 3


def test_a_layer_with_too_many_missing_points_is_refused_naming_the_flag(tmp_path, run_import):
    n = 100
    rows = [f"{i * 3.6:.1f}\t{'---' if i % 10 == 0 else f'{np.cos(i / 9):.4f}'}" for i in range(n)]
    f = tmp_path / "holes.txt"
    f.write_text("Units: um\nAngle (deg)\tDeviation\n" + "\n".join(rows) + "\n")
    with pytest.raises(BadInputError, match=r"10 of 100 points missing.*max_missing") as exc:
        read_scan(f, convention=CONV)
    assert exc.value.suggestions == ({"max_missing": "<value>"},)
    assert read_scan(f, convention=CONV, max_missing=0.1).attrs["missing_points"] == 10
    out = tmp_path / "h.nc"
    assert run_import(f, out) == 3
    assert run_import(f, out, "--max-missing", "0.1") == 0


def test_a_missing_angle_or_a_cut_row_is_refused_not_a_missing_point(tmp_path):
    rows = [f"{i:.1f}\t{np.cos(i / 9):.4f}" for i in range(360)]
    rows[50] = "---\t0.5"
    f = tmp_path / "angle.txt"
    f.write_text("Units: um\nAngle (deg)\tDeviation\n" + "\n".join(rows) + "\n")
    with pytest.raises(BadInputError, match=r"line 53: the angle_deg \(column 1\) is missing"):
        read_scan(f, convention=CONV)
    rows = [f"{i:.1f};{np.cos(i / 9):.4f};{np.sin(i / 9):.4f}" for i in range(360)]
    rows[50] = "50.0;0.5"  # a field short: not an empty cell
    g = tmp_path / "cut.txt"
    g.write_text("Units: um\nAngle (deg);Dev z=0 mm;Dev z=1 mm\n" + "\n".join(rows) + "\n")
    with pytest.raises(BadInputError, match=r"line 53: expected 3 fields, found 2"):
        read_scan(g, convention=CONV)


# --- issue 38 item 5: heights from an index file, uneven z on the command line --------------


def _layer_folder(d, zs_mm):
    d.mkdir()
    n = 360
    th = np.arange(n) * 1.0
    for k in range(len(zs_mm)):
        dev = 0.3 * np.cos(2 * np.radians(th)) + 0.1 * k
        (d / f"trace{k + 1}.txt").write_text(
            "Units: um\nAngle (deg)\tDeviation\n"
            + "".join(f"{a:.1f}\t{v:.4f}\n" for a, v in zip(th, dev, strict=True))
        )
    return d


@pytest.mark.parametrize(
    ("name", "head", "sep", "extra"),
    [
        ("heights.txt", "", " ", ("--z-units", "mm")),  # file, height; no unit: --z-units
        ("index.csv", "file,height_mm\n", ",", ()),
        ("manifest.txt", "file;z [mm]\n", ";", ()),
    ],
)
def test_heights_from_an_index_file_in_the_folder(tmp_path, run_import, name, head, sep, extra):
    import xarray as xr

    zs = [0.0, 1.5, 4.0]  # uneven
    d = _layer_folder(tmp_path / "scan", zs)
    (d / name).write_text(head + "".join(f"trace{k + 1}.txt{sep}{z:g}\n" for k, z in enumerate(zs)))
    out = tmp_path / "o.nc"
    assert run_import(d, out, *extra) == 0
    ds = xr.load_dataset(out)
    np.testing.assert_allclose(ds["z"].values, (np.array(zs) - 2.0) * 1e-3, atol=1e-12)
    assert ds.sizes["z"] == 3  # the heights file is not read as a layer


def test_heights_file_given_and_z_mm_on_the_command_line(tmp_path, run_import):
    import xarray as xr

    zs = [0.0, 1.5, 4.0]
    d = _layer_folder(tmp_path / "scan", zs)
    hf = tmp_path / "my_z.tsv"
    hf.write_text("name\theight_mm\n" + "".join(f"trace{k + 1}\t{z:g}\n" for k, z in enumerate(zs)))
    out = tmp_path / "o.nc"
    assert run_import(d, out, "--heights", str(hf)) == 0
    np.testing.assert_allclose(xr.load_dataset(out)["z"].values, [-2e-3, -0.5e-3, 2e-3])
    out2 = tmp_path / "o2.nc"
    assert run_import(d, out2, "--z-mm", "0,1.5,4") == 0
    np.testing.assert_allclose(xr.load_dataset(out2)["z"].values, [-2e-3, -0.5e-3, 2e-3])
    assert run_import(d, tmp_path / "o3.nc", "--z-mm", "0,1.5") == 3  # one per layer
    assert run_import(d, tmp_path / "o4.nc", "--z-mm", "0;x") == 2


@pytest.mark.parametrize("with_z", [True, False])
def test_excel_merged_layer_headers_read_as_layers_with_their_z(tmp_path, with_z):
    openpyxl = pytest.importorskip("openpyxl")
    zs = [0.0, 1.5, 4.0]
    wb = openpyxl.Workbook()
    ws = wb.active
    ws.append(["Units", "um"])
    heads = [f"Layer {k + 1}" + (f"  z = {z:.1f} mm" if with_z else "") for k, z in enumerate(zs)]
    ws.append([c for h in heads for c in (h, None)])
    for k in range(3):
        ws.merge_cells(start_row=2, start_column=2 * k + 1, end_row=2, end_column=2 * k + 2)
    ws.append(["Angle (deg)", "Deviation (um)"] * 3)
    th = np.arange(360) * 1.0
    dev = np.array([0.3 * np.cos(2 * np.radians(th)) + 0.1 * k for k in range(3)])
    for i in range(360):
        ws.append([c for k in range(3) for c in (th[i], float(dev[k, i]))])
    f = tmp_path / "merged.xlsx"
    wb.save(f)
    if with_z:
        ds = read_scan(f, convention=CONV)
        np.testing.assert_allclose(ds["z"].values, [-2e-3, -0.5e-3, 2e-3], atol=1e-12)
    else:  # layer numbers: z needs the spacing, and the refusal says so
        with pytest.raises(BadInputError, match="layer_spacing"):
            read_scan(f, convention=CONV)
        ds = read_scan(f, convention=CONV, layer_spacing=1e-3)
        np.testing.assert_allclose(ds["z"].values, [-1e-3, 0, 1e-3], atol=1e-12)
    np.testing.assert_allclose(ds["radial_deviation"].values, dev * 1e-6, atol=1e-15)


# --- issue 38 item 6: micro-inch, --units over an unknown header unit, --thousands named ------


@pytest.mark.parametrize("name", ["uin", "µin", "μin", "microinch"])
def test_micro_inch_is_a_unit(tmp_path, name):
    th = np.arange(360) * 1.0
    dev = 20.0 * np.cos(2 * np.radians(th))  # 20 uin = 0.508 um
    f = tmp_path / "uin.txt"
    f.write_text(
        f"Units: {name}\nAngle (deg)\tDeviation\n"
        + "".join(f"{a:.1f}\t{v:.3f}\n" for a, v in zip(th, dev, strict=True))
    )
    ds = read_scan(f, convention=CONV)
    np.testing.assert_allclose(
        ds["radial_deviation"].values[0], np.round(dev, 3) * 25.4e-9, rtol=1e-12
    )


def test_units_option_replaces_a_header_unit_nobody_knows(tmp_path, run_import):
    th = np.arange(360) * 1.0
    f = tmp_path / "odd.txt"
    f.write_text(
        "Units: Mikron*\nAngle (deg)\tDeviation\n"
        + "".join(f"{a:.1f}\t{np.cos(np.radians(2 * a)):.4f}\n" for a in th)
    )
    with pytest.raises(BadInputError, match=r"line 1: unit 'Mikron\*' is not known") as exc:
        read_scan(f, convention=CONV)
    assert exc.value.suggestions == ({"units": "<unit>"},)
    ds = read_scan(f, convention=CONV, units="um")
    assert "Mikron" in ds.attrs["reader_guesses"]["odd.txt"]["unknown_unit"]
    np.testing.assert_allclose(ds["radial_deviation"].values[0].max(), 1e-6)
    out = tmp_path / "o.nc"
    assert run_import(f, out) == 3
    assert run_import(f, out, "--units", "um") == 0
    # a known header unit is still never overridden silently
    g = tmp_path / "mm.txt"
    g.write_text(f.read_text().replace("Mikron*", "um"))
    with pytest.raises(BadInputError, match="contradicts the file"):
        read_scan(g, convention=CONV, units="mm")


def test_refusals_name_thousands_where_it_helps(tmp_path, run_import):
    """Grouped integers (`8'001'000` nm) show no decimal mark, so the mark is not sniffed; the
    refusal names --thousands, and the flag as printed reads the file."""
    th = np.arange(360) * 1.0
    r = 8000 + np.cos(np.radians(3 * th))
    f = tmp_path / "ap.txt"
    f.write_text(
        "Units: nm\n"
        + "".join(
            f"{a:.1f}\t{int(v * 1000):,}\n".replace(",", "'") for a, v in zip(th, r, strict=True)
        )
    )
    with pytest.raises(BadInputError, match="thousands='apostrophe'") as exc:
        read_scan(f, convention=CONV)
    assert exc.value.suggestions == ({"thousands": "apostrophe"},)
    ds = read_scan(f, convention=CONV, **exc.value.suggestions[0])
    np.testing.assert_allclose(ds["radius"].values[0], np.floor(r * 1000) * 1e-9, rtol=1e-12)
    assert run_import(f, tmp_path / "o.nc", "--thousands", "apostrophe") == 0
    # space-grouped integers in a semicolon file: --thousands space, the spelling --help lists
    g = tmp_path / "sp.txt"
    g.write_text(g_text := f.read_text().replace("'", " ").replace("\t", ";"))
    assert "8 000 999" in g_text or "8 001 000" in g_text
    with pytest.raises(BadInputError, match="thousands='space'"):
        read_scan(g, convention=CONV)
    assert run_import(g, tmp_path / "o2.nc", "--thousands", "space") == 0


def test_a_missing_first_value_of_a_value_only_file_is_not_taken_for_a_header(tmp_path):
    """`NaN` on the first line of a column of values used to become a header line: one point
    fewer, every angle of a full turn shifted, exit 0."""
    v = np.cos(np.radians(2 * np.arange(100) * 3.6))
    f = tmp_path / "v.txt"
    f.write_text("Units: um\nNaN\n" + "".join(f"{x:.4f}\n" for x in v[1:]))
    ds = read_scan(f, convention=CONV, arc="full", max_missing=0.05)
    assert ds.sizes["theta"] == 100 and ds.attrs["missing_points"] == 1
    want = np.round(v, 4) * 1e-6
    want[0] = np.nan
    np.testing.assert_allclose(ds["radial_deviation"].values[0], want, atol=1e-12)


def test_the_form_rule_leaves_out_the_set_up_eccentricity(tmp_path):
    """Deviations about the spindle hold the set-up's eccentricity (a first harmonic), which
    is no form: 0.3 mm of it on a 12.5 mm bore (2.4 % p-p) passes, with a 20 um form."""
    th = np.arange(720) * 0.5
    t = np.radians(th)
    dev = 0.15 * np.cos(t - 0.3) + 0.01 * np.cos(3 * t)  # mm
    f = tmp_path / "ecc.txt"
    f.write_text(
        "Units: mm\nNominal radius: 12.5 mm\nAngle (deg)\tDeviation\n"
        + "".join(f"{a:.1f}\t{v:.6f}\n" for a, v in zip(th, dev, strict=True))
    )
    ds = read_scan(f, convention=CONV)
    np.testing.assert_allclose(ds["radial_deviation"].values[0], np.round(dev, 6) * 1e-3)
