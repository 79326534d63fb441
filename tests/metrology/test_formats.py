"""Formats beyond plain UTF-8 text: Excel workbooks, X3P point clouds, UTF-16 / UTF-8-BOM."""

from __future__ import annotations

import numpy as np
import pytest

from jointwear.cli import main
from jointwear.errors import BadInputError
from jointwear.metrology.readers import parse_file, read_scan, read_talyrond

CONV = ("+y", "counterclockwise")


def _trace(n=3600, R=8.0):
    th = np.arange(n) * 360.0 / n
    r = R * 1e3 + 1.5 * np.cos(np.radians(3 * th)) + 0.25 * np.sin(np.radians(7 * th))  # um
    return th, r


def _workbook(path, sheets):
    openpyxl = pytest.importorskip("openpyxl")
    wb = openpyxl.Workbook()
    wb.remove(wb.active)
    for name, rows in sheets.items():
        ws = wb.create_sheet(name)
        for row in rows:
            ws.append(list(row))
    wb.save(path)
    return path


def test_talyrond_style_workbook_reads_every_digit(tmp_path):
    th, r = _trace()
    rows = [("Instrument", "Talyrond 365"), ("Units", "um"), ("Angle (deg)", "Radius (um)")]
    rows += list(zip(th.tolist(), r.tolist(), strict=True))
    f = _workbook(tmp_path / "trace.xlsx", {"Trace": rows})
    ds = read_talyrond(f, convention=CONV)
    got = np.sort(ds["radius"].values[0])
    np.testing.assert_allclose(got, np.sort(r) * 1e-6, rtol=0, atol=1e-15)
    assert ds.attrs["instrument_metadata"]["Instrument"] == "Talyrond 365"
    # two sheets with numbers: which one is the trace is not guessed
    f2 = _workbook(tmp_path / "two.xlsx", {"Trace": rows, "Filtered": rows})
    with pytest.raises(
        BadInputError, match=r"several sheets hold numbers \('Trace', 'Filtered'\).*--sheet"
    ):
        read_scan(f2, convention=CONV)
    ds2 = read_scan(f2, convention=CONV, sheet="Filtered")
    np.testing.assert_array_equal(ds2["radius"].values, ds["radius"].values)
    with pytest.raises(BadInputError, match=r"no sheet 'Raw'; the sheets are 'Trace', 'Filtered'"):
        read_scan(f2, convention=CONV, sheet="Raw")
    out = tmp_path / "o.nc"
    args = [
        "metrology",
        "import",
        str(f2),
        "--angle-zero",
        "+y",
        "--angle-direction",
        "counterclockwise",
        "--out",
        str(out),
    ]
    assert main(args) == 3
    assert main(args + ["--sheet", "Trace"]) == 0 and out.exists()


def test_workbook_with_a_blank_value_cell_reads_a_missing_point(tmp_path):
    """A blank cell (a formula never calculated, a deleted cell) is a missing value (issue 38:
    NaN, counted); a blank angle cannot be placed and names the row."""
    th, r = _trace(360)
    rows = [("Units", "um"), ("Angle (deg)", "Deviation (um)")]
    rows += [(a, v - 8000.0) for a, v in zip(th.tolist(), r.tolist(), strict=True)]
    rows[50] = (rows[50][0], None)
    f = _workbook(tmp_path / "gap.xlsx", {"Sheet1": rows})
    ds = read_scan(f, convention=CONV)
    assert ds.attrs["missing_points"] == 1
    assert int(np.isnan(ds["radial_deviation"].values[0]).sum()) == 1
    rows[50] = (None, rows[51][1])
    g = _workbook(tmp_path / "gap2.xlsx", {"Sheet1": rows})
    with pytest.raises(BadInputError, match=r"gap2.xlsx' line 51: the angle_deg .* is missing"):
        read_scan(g, convention=CONV)


def test_damaged_workbook_and_old_xls_are_refused(tmp_path):
    f = _workbook(tmp_path / "ok.xlsx", {"S": [("Units", "um"), (0.0, 1.0)]})
    cut = tmp_path / "cut.xlsx"
    cut.write_bytes(f.read_bytes()[:300])
    with pytest.raises(BadInputError, match=r"cut.xlsx"):
        read_scan(cut, convention=CONV)
    xls = tmp_path / "old.xls"
    xls.write_bytes(b"\xd0\xcf\x11\xe0\xa1\xb1\x1a\xe1" + bytes(600))
    with pytest.raises(BadInputError, match=r"old binary Excel.*save it as .xlsx"):
        read_scan(xls, convention=CONV)


def test_x3p_point_cloud_of_three_layers(tmp_path):
    x3pio = pytest.importorskip("x3pio")
    n, R, e = 720, 8e-3, (3e-6, -2e-6)
    t = np.arange(n) * 2 * np.pi / n
    rho = R + 1e-6 * np.cos(2 * t)
    pts = []
    for z in (-1e-3, 0.0, 1e-3):
        pts.append(np.column_stack([e[0] + rho * np.cos(t), e[1] + rho * np.sin(t), np.full(n, z)]))
    f = tmp_path / "bore.x3p"
    x3pio.write_points(f, np.concatenate(pts))
    ds = read_scan(f, convention=("+x", "counterclockwise"))
    assert ds.sizes["z"] == 3 and ds.sizes["theta"] == n
    np.testing.assert_allclose(ds["z"].values, [-1e-3, 0.0, 1e-3], atol=1e-15)
    # radius about the origin of every point = hypot(x, y), exactly as written
    x, y = pts[0][:, 0], pts[0][:, 1]
    np.testing.assert_allclose(np.sort(ds["radius"].values[0]), np.sort(np.hypot(x, y)), rtol=1e-15)
    # the same cloud through assess: exact circle per layer centred on the set-up offset
    out = tmp_path / "c.nc"
    assert main(["metrology", "assess", str(f), "--out", str(out)]) == 0
    from jointwear import io

    res = io.load(out)
    np.testing.assert_allclose(res["x0"].values, e[0], atol=1e-13)
    np.testing.assert_allclose(res["radius"].values, R, atol=1e-13)
    np.testing.assert_allclose(res["RONt_LS"].values, 2e-6, rtol=1e-6)


def test_x3p_profile_is_refused(tmp_path):
    x3pio = pytest.importorskip("x3pio")
    f = tmp_path / "p.x3p"
    x3pio.Profile.from_array(np.sin(np.linspace(0, 6, 100)) * 1e-6, x_scale=1e-6).save(f)
    with pytest.raises(BadInputError, match=r"p.x3p': an X3P profile.*point cloud"):
        read_scan(f, convention=CONV)


@pytest.mark.parametrize("encoding", ["utf-16", "utf-16-le", "utf-16-be", "utf-8-sig"])
def test_utf16_and_bom_text_read_like_utf8(tmp_path, encoding):
    th, r = _trace(360)
    text = "Einheit: µm\nWinkel [°]\tAbweichung [µm]\n" + "".join(
        f"{a:.1f}\t{v - 8000:.5f}\n" for a, v in zip(th, r, strict=True)
    )
    ref = tmp_path / "ref.txt"
    ref.write_text(text, encoding="utf-8")
    f = tmp_path / f"{encoding}.txt"
    f.write_bytes(text.encode(encoding))
    a, b = parse_file(ref), parse_file(f)
    np.testing.assert_array_equal(a.data, b.data)
    assert b.columns == ("angle_deg", "deviation") and b.units == "µm"
    ds = read_scan(f, convention=CONV)
    assert float(ds["radial_deviation"].max()) == pytest.approx(
        np.max(np.round(r - 8000, 5)) * 1e-6, rel=1e-12
    )
