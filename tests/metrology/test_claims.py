"""Exact files for issue 22: header claims against the numbers, z only from names that say z,
refusals whose own fixes work, and the formats labs produce. Each file is written here with
a known truth; a refusal's suggestion (``exc.suggestions``) is applied as given."""

from __future__ import annotations

import json

import numpy as np
import pytest

from jointwear.errors import BadInputError
from jointwear.metrology.readers import read_scan
from jointwear.metrology.readers.advice import Refusal

CONV = ("-x", "clockwise")  # canonical: theta comes back as written
N = 360
TH = np.arange(N) * 360.0 / N
DEV_UM = 2.0 * np.cos(np.radians(3 * TH)) + 0.5 * np.sin(np.radians(7 * TH))


def _write(path, rows, head=""):
    path.write_text(head + "".join("\t".join(r) + "\n" for r in rows))
    return path


def _rows(angles, values, fa="{:.6f}", fv="{:.6f}"):
    return [[fa.format(a), fv.format(v)] for a, v in zip(angles, values, strict=True)]


def _apply(path, exc, k=0, base=None, fill=None):
    """Read ``path`` with suggestion ``k`` of refusal ``exc`` (placeholders from ``fill``)."""
    opts = dict(base or {})
    for key, v in exc.suggestions[k].items():
        if isinstance(v, str) and v.startswith("<"):
            v = fill[key]
        if v is None:
            opts.pop(key, None)
        else:
            opts[key] = v
    return read_scan(path, convention=CONV, **opts)


# --- 1. header claims --------------------------------------------------------------------


def test_header_unit_contradicted_by_radius_magnitudes(tmp_path):
    r_mm = 8.0 + 1e-3 * DEV_UM
    f = _write(
        tmp_path / "um.txt", _rows(TH, r_mm, fv="{:.7f}"), "Units: um\nAngle (deg)\tRadius\n"
    )
    with pytest.raises(Refusal, match=r"'um'.*about 8 µm.*not a plausible bore.*units='mm'") as e:
        read_scan(f, convention=CONV)
    assert "um.txt" in str(e.value) and "ignore_header=units" in str(e.value)
    ds = _apply(f, e.value)
    np.testing.assert_allclose(ds["radius"].values[0], np.round(r_mm, 7) * 1e-3, rtol=1e-12)
    assert "ignored_header" in ds.attrs["reader_guesses"]["um.txt"]


def test_deviation_unit_contradicted_by_magnitude(tmp_path):
    f = _write(tmp_path / "mm.txt", _rows(TH, DEV_UM), "Units: mm\nAngle (deg)\tDeviation\n")
    with pytest.raises(Refusal, match=r"deviations of .* mm.*gauge's range.*units='um'") as e:
        read_scan(f, convention=CONV)
    ds = _apply(f, e.value)
    np.testing.assert_allclose(ds["radial_deviation"].values[0], DEV_UM * 1e-6, atol=1e-12)


def test_nominal_radius_contradicted_by_the_measured_radius(tmp_path):
    r = 80.0 + 1e-3 * DEV_UM
    head = "Units: mm\nNominal radius: 8 mm\nAngle (deg)\tRadius\n"
    f = _write(tmp_path / "nom.txt", _rows(TH, r), head)
    with pytest.raises(Refusal, match=r"Nominal radius.*8 mm.*about 80 mm \(10 x\)") as e:
        read_scan(f, convention=CONV)
    assert e.value.suggestions == ({"ignore_header": ("nominal_radius",)},)
    ds = _apply(f, e.value)
    assert float(ds["radius"].mean()) == pytest.approx(80e-3, rel=1e-4)
    assert "nominal_radius" not in ds.attrs  # the dropped claim is not carried on
    # a nominal that agrees is checked and recorded
    g = _write(tmp_path / "ok.txt", _rows(TH, r), "Units: mm\nNominal diameter: 160 mm\n")
    ds = read_scan(g, convention=CONV)
    assert "agrees" in ds.attrs["reader_guesses"]["ok.txt"]["nominal_radius_check"]


def test_points_per_revolution_over_ten_rows_is_refused_for_that_reason(tmp_path):
    a = np.arange(10) * 0.02
    f = _write(
        tmp_path / "ten.txt", _rows(a, 8.0 + 1e-3 * DEV_UM[:10]), "Units: mm\nPoints: 18000\n"
    )
    with pytest.raises(Refusal, match=r"18000 points per revolution.*10 rows.*truncated") as e:
        read_scan(f, convention=CONV)
    assert "look like radii" not in str(e.value)
    assert {"arc": "partial", "angle_unit": "deg"} in e.value.suggestions
    ds = _apply(f, e.value, e.value.suggestions.index({"arc": "partial", "angle_unit": "deg"}))
    np.testing.assert_allclose(ds["theta"].values, a, atol=1e-9)  # a 0.18 degree arc, as stated
    # without an angle column, 10 values are no revolution of 18000 points
    g = _write(
        tmp_path / "vals.txt", [[f"{v:.6f}"] for v in DEV_UM[:10]], "Units: um\nPoints: 18000\n"
    )
    with pytest.raises(Refusal, match=r"18000 points per revolution.*10 rows and no angle"):
        read_scan(g, convention=CONV, arc="full")


def test_points_per_revolution_against_the_angular_step(tmp_path):
    f = _write(tmp_path / "step.txt", _rows(TH, DEV_UM), "Units: um\nPoints per revolution: 3600\n")
    with pytest.raises(Refusal, match=r"3600 points per revolution.*360 rows") as e:
        read_scan(f, convention=CONV)
    ds = _apply(f, e.value, -1)  # ignore_header points: the header was wrong
    assert ds.sizes["theta"] == N
    good = _write(tmp_path / "good.txt", _rows(TH, DEV_UM), "Units: um\nPoints: 360\n")
    assert read_scan(good, convention=CONV).sizes["theta"] == N


def test_stated_filter_contradicted_by_the_spectrum(tmp_path):
    n = 3600
    th = np.arange(n) * 360.0 / n
    rng = np.random.default_rng(0)
    raw = 2.0 * np.cos(np.radians(3 * th)) + 0.05 * rng.standard_normal(n)
    head = "Units: um\nFilter: Gaussian 50 UPR\nAngle (deg)\tDeviation\n"
    f = _write(tmp_path / "raw.txt", _rows(th, raw), head)
    with pytest.raises(Refusal, match=r"Filter.*50 UPR.*not filtered as stated") as e:
        read_scan(f, convention=CONV)
    _apply(f, e.value)
    from jointwear.metrology.filters import filter_profile

    filt = filter_profile(raw * 1e-6, 50) * 1e6
    g = _write(tmp_path / "filt.txt", _rows(th, filt, fv="{:.9f}"), head)
    ds = read_scan(g, convention=CONV)
    assert "consistent" in ds.attrs["reader_guesses"]["filt.txt"]["filter"]


def test_layer_count_and_spacing_claims(tmp_path):
    rows = [
        [f"{k:.1f}", f"{t:.6f}", f"{v:.6f}"]
        for k in range(3)
        for t, v in zip(TH, DEV_UM, strict=True)
    ]
    head = "Units: um\nZ unit: mm\nLayers: 4\nz\tAngle (deg)\tDeviation\n"
    f = _write(tmp_path / "cnt.txt", rows, head)
    with pytest.raises(Refusal, match=r"Layers = '4'.*3 layer\(s\)"):
        read_scan(f, convention=CONV)
    head = "Units: um\nZ unit: mm\nLayer spacing: 2 mm\nz\tAngle (deg)\tDeviation\n"
    g = _write(tmp_path / "sp.txt", rows, head)
    with pytest.raises(Refusal, match=r"Layer spacing = '2 mm'.*1 mm apart") as e:
        read_scan(g, convention=CONV)
    ds = _apply(g, e.value)
    np.testing.assert_allclose(ds["z"].values, [-1e-3, 0, 1e-3], atol=1e-15)


# --- 1a. an inch/mm slip (25.4 x) is named, and its fix reads right ------------------------

R_IN = (8.0 + 1e-3 * DEV_UM) / 25.4  # an 8-mm bore radius exported in inch (0.315 in)


def _refused_then_read(path, match, k, truth_mm, **opts):
    """The file is refused with ``match``; suggestion ``k`` applied as given reads
    ``truth_mm`` (the radii, mm, as written in the file's true unit)."""
    with pytest.raises(Refusal, match=match) as e:
        read_scan(path, convention=CONV, **opts)
    ds = _apply(path, e.value, k, base=opts)
    np.testing.assert_allclose(ds["radius"].values[0], truth_mm * 1e-3, rtol=1e-12)
    return e.value


def test_radii_in_inch_under_a_mm_header_name_25_4(tmp_path):
    f = _write(tmp_path / "in.txt", _rows(TH, R_IN, fv="{:.9f}"), "Units: mm\nAngle\tRadius\n")
    exc = _refused_then_read(
        f,
        r"about 315 µm.*units='inch' \(if the values are in inch: a radius of 8 mm, 25.4 x",
        1,
        np.round(R_IN, 9) * 25.4,
    )
    assert exc.suggestions[1] == {"ignore_header": ("units",), "units": "inch"}
    # with a nominal diameter in mm, inch is the only reading left
    g = _write(
        tmp_path / "nom.txt",
        _rows(TH, R_IN, fv="{:.9f}"),
        "Units: mm\nNominal diameter: 16 mm\nAngle\tRadius\n",
    )
    exc = _refused_then_read(g, r"units='inch'.*25.4 x the mm reading", 0, np.round(R_IN, 9) * 25.4)
    assert len(exc.suggestions) == 1


def test_units_option_mm_over_inch_radii_names_25_4(tmp_path):
    f = _write(tmp_path / "bare.txt", _rows(TH, R_IN, fv="{:.9f}"), "Angle\tRadius\n")
    exc = _refused_then_read(
        f,
        r"read in 'mm' \(units= given\).*units='inch'.*25.4 x",
        1,
        np.round(R_IN, 9) * 25.4,
        units="mm",
    )
    assert exc.suggestions[1] == {"units": "inch"}


def test_large_bore_in_inch_under_a_mm_nominal_names_1_over_25_4(tmp_path):
    # 40 mm radius written as 1.5748 in under "Units: mm": 1.57 mm is a plausible bore, so only
    # the nominal diameter can tell; the refusal names the exact ratio
    r_in = (40.0 + 1e-3 * DEV_UM) / 25.4
    head = "Units: mm\nNominal diameter: 80 mm\nAngle\tRadius\n"
    f = _write(tmp_path / "big.txt", _rows(TH, r_in, fv="{:.9f}"), head)
    exc = _refused_then_read(
        f, r"about 1.575 mm \(1/25.4 x: values in inch read as mm\?\)", 0, np.round(r_in, 9) * 25.4
    )
    assert exc.suggestions[0] == {"ignore_header": ("units",), "units": "inch"}


def test_mm_radii_under_an_inch_header_name_25_4(tmp_path):
    r = 8.0 + 1e-3 * DEV_UM
    head = "Units: inch\nNominal radius: 8 mm\nAngle\tRadius\n"
    f = _write(tmp_path / "mm.txt", _rows(TH, r, fv="{:.7f}"), head)
    _refused_then_read(
        f, r"about 203.2 mm \(25.4 x: values in mm read as inch\?\)", 0, np.round(r, 7)
    )


def test_nominal_in_inch_without_unit_names_25_4(tmp_path):
    r = 8.0 + 1e-3 * DEV_UM
    head = "Units: mm\nNominal diameter: 0.63\nAngle\tRadius\n"
    f = _write(tmp_path / "nin.txt", _rows(TH, r, fv="{:.7f}"), head)
    exc = _refused_then_read(f, r"\(25.4 x: an inch/mm slip between the nominal", 0, np.round(r, 7))
    assert exc.suggestions == ({"ignore_header": ("nominal_radius",)},)


# --- 1b. a header layer spacing that is the only source of z ------------------------------


def _numbered(path, head, n=3):
    rows = [
        [str(k + 1), f"{t:.6f}", f"{v + k:.6f}"]
        for k in range(n)
        for t, v in zip(TH, DEV_UM, strict=True)
    ]
    return _write(path, rows, "Units: um\n" + head + "Layer\tAngle (deg)\tDeviation\n")


def test_sole_header_spacing_is_read_and_said_to_be_unconfirmed(tmp_path):
    ds = read_scan(_numbered(tmp_path / "sole.txt", "Layer spacing: 1 mm\n"), convention=CONV)
    np.testing.assert_allclose(ds["z"].values, [-1e-3, 0, 1e-3], atol=1e-15)
    note = ds.attrs["z_unconfirmed"]
    assert "Layer spacing = '1 mm' alone" in note and "layer_spacing=<m>" in note
    # a stated z range that agrees confirms it: no note
    ds = read_scan(
        _numbered(tmp_path / "conf.txt", "Layer spacing: 1 mm\nZ range: 0 - 2 mm\n"),
        convention=CONV,
    )
    assert "z_unconfirmed" not in ds.attrs
    # the option gives z: nothing to confirm
    ds = read_scan(_numbered(tmp_path / "opt.txt", ""), convention=CONV, layer_spacing=1e-3)
    assert "z_unconfirmed" not in ds.attrs


def test_import_summary_says_the_spacing_is_unconfirmed(tmp_path, capsys, run_import):
    from jointwear import io

    f = _numbered(tmp_path / "sole.txt", "Layer spacing: 1 mm\n")
    out = tmp_path / "o.nc"
    assert run_import(f, out, zero="-x", direction="clockwise") == 0
    assert "note: z from the header's Layer spacing = '1 mm' alone" in capsys.readouterr().out
    assert "alone" in io.load(out).attrs["z_unconfirmed"]


def test_sole_header_spacing_contradicted_by_the_z_range(tmp_path):
    # the truth: layers 2 mm apart (z range 0-4 mm); the header's spacing (1 mm) is wrong
    f = _numbered(tmp_path / "rng.txt", "Layer spacing: 1 mm\nZ range: 0 - 4 mm\n")
    with pytest.raises(Refusal, match=r"Z range = '0 - 4 mm' but the layers span 2 mm") as e:
        read_scan(f, convention=CONV)
    ds = _apply(f, e.value, 1, fill={"layer_spacing": 2e-3})
    np.testing.assert_allclose(ds["z"].values, [-2e-3, 0, 2e-3], atol=1e-15)
    assert "z_unconfirmed" not in ds.attrs
    # the range alone against a z column
    rows = [
        [f"{k:.1f}", f"{t:.6f}", f"{v:.6f}"]
        for k in range(3)
        for t, v in zip(TH, DEV_UM, strict=True)
    ]
    g = _write(
        tmp_path / "zc.txt", rows, "Units: um\nTotal height: 4 mm\nz [mm]\tAngle (deg)\tDeviation\n"
    )
    with pytest.raises(
        Refusal, match=r"Total height = '4 mm' but the layers span 2 mm.*z column"
    ) as e:
        read_scan(g, convention=CONV)
    assert _apply(g, e.value).sizes["z"] == 3


def test_bare_spacing_key_as_sole_source_is_refused(tmp_path):
    # "Spacing: 0.5 mm" may be the sampling step along the trace; z from it would be a guess
    f = _numbered(tmp_path / "bare.txt", "Spacing: 0.5 mm\n")
    with pytest.raises(
        Refusal, match=r"'Spacing' does not say it is the distance between layers"
    ) as e:
        read_scan(f, convention=CONV)
    ds = _apply(f, e.value, 1, fill={"layer_spacing": 1.5e-3})  # it was another spacing
    np.testing.assert_allclose(ds["z"].values, [-1.5e-3, 0, 1.5e-3], atol=1e-15)
    ds = _apply(f, e.value, 0, fill={"layer_spacing": 0.5e-3})  # it was the layers'
    np.testing.assert_allclose(ds["z"].values, [-0.5e-3, 0, 0.5e-3], atol=1e-15)


def test_z_in_file_names_against_z_in_headers(tmp_path):
    d = tmp_path / "scan"
    d.mkdir()
    for k in range(3):
        _write(d / f"trace_z{k * 2}mm.txt", _rows(TH, DEV_UM), f"Units: um\nHeight: {k} mm\n")
    with pytest.raises(Refusal, match=r"header says z = 0.002 m but the file name says z = 0.004"):
        read_scan(d, convention=CONV)
    ds = read_scan(d, convention=CONV, z_source="names")
    np.testing.assert_allclose(ds["z"].values, [-2e-3, 0, 2e-3], atol=1e-15)
    ds = read_scan(d, convention=CONV, z_source="header")
    np.testing.assert_allclose(ds["z"].values, [-1e-3, 0, 1e-3], atol=1e-15)


# --- 2. z from column names only when they say z ---------------------------------------


def _wide(path, names, head="Units: um\n"):
    rows = [
        [f"{t:.6f}"] + [f"{v + k:.6f}" for k in range(len(names) - 1)]
        for t, v in zip(TH, DEV_UM, strict=True)
    ]
    return _write(path, rows, head + "\t".join(names) + "\n")


def test_layer_numbers_in_column_names_are_not_heights(tmp_path):
    f = _wide(tmp_path / "lay.txt", ["Angle (deg)", "Layer 1", "Layer 2", "Layer 3"])
    with pytest.raises(Refusal, match=r"numbered.*nothing of their height.*layer_spacing") as e:
        read_scan(f, convention=CONV, value="deviation")
    with pytest.raises(Refusal, match=r"numbered"):  # a z unit makes no height of a number
        read_scan(f, convention=CONV, value="deviation", z_units="mm")
    ds = _apply(f, e.value, base={"value": "deviation"}, fill={"layer_spacing": 0.5e-3})
    np.testing.assert_allclose(ds["z"].values, [-0.5e-3, 0, 0.5e-3], atol=1e-15)
    with pytest.raises(Refusal, match=r"z_units='mm'.*cannot apply"):
        read_scan(f, convention=CONV, value="deviation", layer_spacing=1e-3, z_units="mm")
    hz = _wide(tmp_path / "hz.txt", ["Angle (deg)", "z=0.0mm", "z=1.5mm", "z=3.0mm"])
    ds = read_scan(hz, convention=CONV, value="deviation")
    np.testing.assert_allclose(ds["z"].values, [-1.5e-3, 0, 1.5e-3], atol=1e-15)


def test_probe_columns_are_never_layers(tmp_path):
    f = _wide(tmp_path / "probes.txt", ["Angle (deg)", "Radius1", "Radius2"])
    with pytest.raises(Refusal, match=r"2 value columns \('Radius1', 'Radius2'\)") as e:
        read_scan(f, convention=CONV, value="deviation")
    with pytest.raises(BadInputError):  # a z unit cannot turn probe numbers into heights
        read_scan(f, convention=CONV, value="deviation", z_units="mm")
    ds = _apply(f, e.value, 1, base={"value": "deviation"})
    assert ds.sizes["z"] == 1
    np.testing.assert_allclose(ds["radial_deviation"].values[0], DEV_UM * 1e-6, atol=1e-12)


def test_two_angle_value_pairs_are_two_probes(tmp_path):
    rows = [
        [f"{t:.4f}", f"{v:.6f}", f"{t:.4f}", f"{-v:.6f}"] for t, v in zip(TH, DEV_UM, strict=True)
    ]
    for names in ("Angle\tDev A\tAngle\tDev B\n", ""):
        f = _write(tmp_path / "pairs.txt", rows, "Units: um\nAngle unit: deg\n" + names)
        with pytest.raises(Refusal, match=r"2 angle columns.*probes") as e:
            read_scan(f, convention=CONV, value="deviation")
        ds = _apply(f, e.value, 1, base={"value": "deviation"})
        np.testing.assert_allclose(ds["radial_deviation"].values[0], -DEV_UM * 1e-6, atol=1e-12)


def test_layer_column_combines_with_the_spacing(tmp_path):
    rows = [
        [str(k), f"{t:.6f}", f"{v:.6f}"] for k in (1, 2, 3) for t, v in zip(TH, DEV_UM, strict=True)
    ]
    f = _write(tmp_path / "lc.txt", rows, "Units: um\nLayer\tAngle (deg)\tDeviation\n")
    with pytest.raises(Refusal, match=r"numbered.*layer_spacing") as e:
        read_scan(f, convention=CONV)
    ds = _apply(f, e.value, fill={"layer_spacing": 2e-3})
    np.testing.assert_allclose(ds["z"].values, [-2e-3, 0, 2e-3], atol=1e-15)
    with pytest.raises(Refusal, match=r"z_units='mm'.*cannot apply"):
        read_scan(f, convention=CONV, layer_spacing=2e-3, z_units="mm")
    # unnamed: a run column of layer numbers is refused with both readings
    g = _write(tmp_path / "un.txt", rows, "Units: um\n")
    with pytest.raises(Refusal, match=r"holds heights.*holds layer numbers 1, 2") as e:
        read_scan(g, convention=CONV, angle_unit="deg")
    ds = _apply(g, e.value, 1, base={"angle_unit": "deg"}, fill={"layer_spacing": 1e-3})
    np.testing.assert_allclose(ds["z"].values, [-1e-3, 0, 1e-3], atol=1e-15)


def test_spacing_that_cannot_apply_is_an_error(tmp_path):
    rows = [
        [f"{k * 1.0:.1f}", f"{t:.6f}", f"{v:.6f}"]
        for k in range(3)
        for t, v in zip(TH, DEV_UM, strict=True)
    ]
    f = _write(tmp_path / "zc.txt", rows, "Units: um\nz [mm]\tAngle (deg)\tDeviation\n")
    with pytest.raises(Refusal, match=r"layer_spacing=0.002 m.*cannot apply.*z column"):
        read_scan(f, convention=CONV, layer_spacing=2e-3)
    ds = read_scan(f, convention=CONV, layer_spacing=1e-3)  # agrees with the column: fine
    assert ds.sizes["z"] == 3


# --- 3. formats ------------------------------------------------------------------------


def test_unsupported_formats_are_named(tmp_path):
    j = tmp_path / "t.json"
    j.write_text(json.dumps({"angle": TH.tolist(), "r": DEV_UM.tolist()}))
    with pytest.raises(Refusal, match=r"is JSON, which the readers do not support") as e:
        read_scan(j, convention=CONV, units="um")
    assert "delimiter" not in str(e.value) and not e.value.suggestions
    rows = [
        [f"{int(t)}°{int(60 * (t % 1))}'0\"", f"{v:.4f}"] for t, v in zip(TH, DEV_UM, strict=True)
    ]
    d = _write(tmp_path / "dms.txt", rows, "Units: um\n")
    with pytest.raises(Refusal, match=r"degrees-minutes-seconds.*not support"):
        read_scan(d, convention=CONV)


def test_concatenated_layer_blocks(tmp_path):
    text = "Units: um\nInstrument: Talyrond\n"
    for k in range(3):
        text += f"\nLayer {k + 1}\nHeight: {k * 1.5:.1f} mm\nAngle (deg)\tDeviation\n"
        text += "".join(f"{t:.6f}\t{v + k:.6f}\n" for t, v in zip(TH, DEV_UM, strict=True))
    f = tmp_path / "blocks.txt"
    f.write_text(text)
    ds = read_scan(f, convention=CONV)
    assert ds.attrs["layout"] == "blocks"
    np.testing.assert_allclose(ds["z"].values, [-1.5e-3, 0, 1.5e-3], atol=1e-15)
    np.testing.assert_allclose(ds["radial_deviation"].values[2], (DEV_UM + 2) * 1e-6, atol=1e-12)
    # without heights: the layer numbers need the spacing, and then give z
    g = tmp_path / "nohead.txt"
    g.write_text("\n".join(ln for ln in text.splitlines() if not ln.startswith("Height")) + "\n")
    with pytest.raises(Refusal, match="numbered") as e:
        read_scan(g, convention=CONV)
    ds = _apply(g, e.value, fill={"layer_spacing": 1.5e-3})
    np.testing.assert_allclose(ds["z"].values, [-1.5e-3, 0, 1.5e-3], atol=1e-15)


def test_quoted_csv_thousands_and_crlf_with_ctrl_z(tmp_path):
    r_um = 8000.0 + DEV_UM
    q = tmp_path / "q.csv"
    q.write_text(
        '"Units","um"\n"Angle (deg)","Radius"\n'
        + "".join(f'"{t:.2f}","{v:,.4f}"\n' for t, v in zip(TH, r_um, strict=True))
    )
    ds = read_scan(q, convention=CONV)
    np.testing.assert_allclose(ds["radius"].values[0], np.round(r_um, 4) * 1e-6, rtol=1e-12)
    eu = tmp_path / "eu.txt"  # decimal comma and '.' thousands, semicolons
    eu.write_text(
        "Units: um\n"
        + "".join(
            f"{t:.2f};{v:,.4f}\n".replace(",", "X").replace(".", ",").replace("X", ".")
            for t, v in zip(TH, r_um, strict=True)
        ).replace(";", "\t")
    )
    ds = read_scan(eu, convention=CONV, angle_unit="deg")
    np.testing.assert_allclose(ds["radius"].values[0], np.round(r_um, 4) * 1e-6, rtol=1e-12)
    c = tmp_path / "dos.txt"
    c.write_bytes(
        (
            "Units: um\r\nAngle (deg)\tDeviation\r\n"
            + "".join(f"{t:.2f}\t{v:.6f}\r\n" for t, v in zip(TH, DEV_UM, strict=True))
        ).encode()
        + b"\x1a"
    )
    ds = read_scan(c, convention=CONV)
    np.testing.assert_allclose(ds["radial_deviation"].values[0], DEV_UM * 1e-6, atol=1e-12)
    assert "eof_mark" in ds.attrs["reader_guesses"]["dos.txt"]


def test_closed_profile_drops_the_repeated_point(tmp_path):
    a = np.append(TH, 360.0)
    v = np.append(DEV_UM, DEV_UM[0])
    f = _write(tmp_path / "closed.txt", _rows(a, v), "Units: um\nAngle (deg)\tDeviation\n")
    ds = read_scan(f, convention=CONV)
    assert ds.sizes["theta"] == N
    assert "closed profile" in ds.attrs["reader_guesses"]["closed.txt"]["closed_profile"]
    # integers 0..360: a closed profile in degrees or a full turn of 361 indices: refused
    g = _write(tmp_path / "int.txt", _rows(np.arange(361), v, fa="{:.0f}"), "Units: um\n")
    with pytest.raises(Refusal, match=r"closed profile of 360 points.*361 points") as e:
        read_scan(g, convention=CONV, value="deviation")
    ds = _apply(g, e.value, 0, base={"value": "deviation"})
    assert ds.sizes["theta"] == N


def test_coarsely_rounded_angles_of_a_dense_trace_use_the_row_index(tmp_path):
    n = 18000
    th = np.arange(n) * 360.0 / n
    v = 2.0 * np.cos(np.radians(3 * th))
    f = _write(
        tmp_path / "dense.txt", _rows(th, v, fa="{:.1f}"), "Units: um\nAngle (deg)\tDeviation\n"
    )
    ds = read_scan(f, convention=CONV)
    np.testing.assert_allclose(np.sort(ds["theta"].values), th, atol=1e-9)
    assert "row index" in ds.attrs["reader_guesses"]["dense.txt"]["angle"]


def test_gradians_when_stated(tmp_path):
    g = TH / 0.9
    f = _write(tmp_path / "gon.txt", _rows(g, DEV_UM), "Units: um\nAngle [gon]\tDeviation\n")
    ds = read_scan(f, convention=CONV)
    np.testing.assert_allclose(np.sort(ds["theta"].values), TH, atol=1e-6)
    # unstated: degrees would be 1.11 turns; the refusal offers gradians, which read right
    h = _write(tmp_path / "g2.txt", _rows(g, DEV_UM), "Units: um\n")
    with pytest.raises(Refusal, match=r"gradians.*angle_unit='grad'") as e:
        read_scan(h, convention=CONV, value="deviation")
    ds = _apply(h, e.value, base={"value": "deviation"})
    np.testing.assert_allclose(np.sort(ds["theta"].values), TH, atol=1e-6)


def test_cli_speaks_the_suggested_flags_and_they_work(tmp_path, capsys):
    """The command line names the refusal's fix as flags; running them reads the file right."""
    import re as _re
    import shlex

    from jointwear import io
    from jointwear.cli import main

    r_mm = 8.0 + 1e-3 * DEV_UM
    f = _write(
        tmp_path / "um.txt", _rows(TH, r_mm, fv="{:.7f}"), "Units: um\nAngle (deg)\tRadius\n"
    )
    conv = ["--angle-zero", "-x", "--angle-direction", "clockwise"]
    out = tmp_path / "s.nc"
    assert main(["metrology", "import", str(f), "--out", str(out), *conv]) == 3
    err = capsys.readouterr().err
    m = _re.search(r"pass (--ignore-header units --units mm)", err)
    assert m, err
    flags = shlex.split(m.group(1))
    assert main(["metrology", "import", str(f), "--out", str(out), *conv, *flags]) == 0
    ds = io.load(out)
    np.testing.assert_allclose(ds["radius"].values[0], np.round(r_mm, 7) * 1e-3, rtol=1e-12)


def _trace(rng, n, rich):
    """A deviation trace [um]: smooth (form to 12 UPR) or rich (harmonics to n/2, 1/k
    amplitudes, and 20 nm probe noise)."""
    ks = np.arange(2, 13) if not rich else np.arange(2, n // 2)
    amp = rng.uniform(0.05, 1.0, ks.size) / (1 if not rich else np.sqrt(ks))
    spec = np.zeros(n // 2 + 1, complex)
    spec[ks] = amp * np.exp(1j * rng.uniform(0, 2 * np.pi, ks.size)) * n / 2
    v = np.fft.irfft(spec, n)
    return v + (0.02 * rng.standard_normal(n) if rich else 0.0)


@pytest.mark.parametrize("seed", range(2))
def test_truly_filtered_traces_are_never_refused_and_unfiltered_rich_ones_are(tmp_path, seed):
    """Issue 38: two medians of |rfft| that were both the rounding floor refused a smooth,
    truly filtered trace ("0.84 x above 150 UPR"). 52 generated filtered traces (smooth and
    rich, cut-offs 15-500 UPR, 1-6 decimals written) all pass; every unfiltered rich one is
    refused."""
    from jointwear.metrology.filters import filter_profile

    rng = np.random.default_rng(seed)
    refused = 0
    for i in range(26):
        n = int(rng.choice([3600, 7200]))
        kc = float(rng.choice([15, 50, 150, 500] if n > 4000 else [15, 50, 150]))
        rich = bool(i % 2)
        raw = _trace(rng, n, rich)
        decimals = int(rng.integers(1, 7))
        th = np.arange(n) * 360.0 / n
        head = f"Units: um\nFilter: Gaussian {kc:g} UPR\nAngle (deg)\tDeviation\n"
        filt = filter_profile(raw * 1e-6, kc) * 1e6
        g = _write(tmp_path / f"f{i}.txt", _rows(th, filt, fv=f"{{:.{decimals}f}}"), head)
        ds = read_scan(g, convention=CONV)  # a truly filtered trace: never refused
        assert "consistent" in ds.attrs["reader_guesses"][g.name]["filter"]
        if rich and decimals >= 3:  # written finely enough to show the unfiltered band
            f = _write(tmp_path / f"r{i}.txt", _rows(th, raw, fv=f"{{:.{decimals}f}}"), head)
            with pytest.raises(Refusal, match="not filtered as stated"):
                read_scan(f, convention=CONV)
            refused += 1
    assert refused >= 3
