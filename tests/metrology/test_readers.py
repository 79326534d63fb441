"""Readers: round trips through the generator for every layout, sniffing, and bad input."""

from __future__ import annotations

import re
import string

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from jointwear.conventions import AngleConvention
from jointwear.datasets.instruments import generate, write
from jointwear.errors import BadInputError, ConventionError
from jointwear.metrology.readers import parse_file, read_scan, read_talyrond

CONV = ("+y", "counterclockwise")


@pytest.fixture(scope="module")
def scan():
    return generate(n_layers=4, n_points=360, seed=3, convention=CONV)


def _values(ds, nominal):
    if "radius" in ds:
        return ds["radius"].values
    return ds["radial_deviation"].values + nominal


CASES = [
    dict(layout="folder"),
    dict(layout="folder-names", angle="rad", delimiter=";", decimal=","),
    dict(layout="folder-header", angle="index", delimiter=" "),
    dict(layout="folder", angle="none", header=False, read=dict(arc="full", units="um")),
    dict(layout="folder", angle="xy", units="mm"),
    dict(layout="folder", value="radius", units="inch", delimiter=","),
    dict(layout="long", units="mm"),
    dict(layout="long", delimiter=";", decimal=","),
    dict(layout="wide", delimiter=","),
    dict(layout="wide", delimiter="\t", decimal=",", units="m"),
]


@pytest.mark.parametrize("case", CASES, ids=lambda c: "-".join(f"{k}={v!r}" for k, v in c.items()))
def test_round_trip_every_layout(tmp_path, scan, case):
    case = dict(case)
    options = case.pop("read", {})
    target = tmp_path / ("scan" if case["layout"].startswith("folder") else "scan.txt")
    write(scan, target, **case)
    ds = read_scan(target, convention=CONV, **options)
    truth = scan.truth
    np.testing.assert_allclose(_values(ds, scan.nominal_radius), truth["radius"].values, atol=2e-10)
    np.testing.assert_allclose(ds["theta"].values, truth["theta"].values, atol=1e-9)
    np.testing.assert_allclose(ds["z"].values, truth["z"].values, atol=1e-12)
    assert ds.attrs["instrument_angle_zero"] == "+y"
    assert ds["theta"].attrs["angle_zero"] == "-x"  # canonical
    assert ds.attrs["n_points_per_layer"] == 360


def test_single_trace_and_talyrond_preset_units(tmp_path, scan):
    f = tmp_path / "trace.txt"
    write(scan, f, layout="single", header=False, column_names=False, angle="none")
    # no unit anywhere in the file: the generic reader refuses, the preset assumes µm
    with pytest.raises(BadInputError, match="unit is not stated.*pass units="):
        read_scan(f, convention=CONV)
    ds = read_talyrond(f, convention=CONV)
    np.testing.assert_allclose(
        ds["radial_deviation"].values[0] + scan.nominal_radius,
        scan.truth["radius"].values[0],
        atol=2e-10,
    )
    assert ds.attrs["source"] == "measurement: Taylor Hobson Talyrond"
    # the header's unit wins over the preset's default
    g = tmp_path / "mm.txt"
    write(scan, g, layout="single", units="mm")
    ds2 = read_talyrond(g, convention=CONV)
    np.testing.assert_allclose(
        ds2["radial_deviation"].values, ds["radial_deviation"].values[:1], atol=2e-10
    )


def test_convention_is_required(tmp_path, scan):
    write(scan, tmp_path / "s", layout="folder")
    with pytest.raises(ConventionError, match="never guesses"):
        read_scan(tmp_path / "s")


def test_overrides_win_where_the_file_is_silent(tmp_path, scan):
    f = tmp_path / "t.txt"
    write(scan, f, layout="single", angle="deg", header=False, column_names=False)
    ds = read_scan(
        f,
        convention=AngleConvention("+y", "counterclockwise"),
        columns=("angle_deg", "deviation"),
        units="mm",  # the file does not say: the option is the truth
        max_deviation=0.1,  # ... even where it makes deviations of 31 mm (limit overridden)
    )
    np.testing.assert_allclose(
        ds["radial_deviation"].values[0],
        1e3 * (scan.truth["radius"].values[0] - scan.nominal_radius),
        rtol=1e-6,
        atol=1e-12,
    )
    assert ds.attrs["reader_format"]["units"] == "mm"


def test_folder_with_spacing_and_mismatched_points(tmp_path, scan):
    d = tmp_path / "f"
    write(scan, d, layout="folder", header=False, angle="deg")
    (d / "manifest.csv").unlink()
    with pytest.raises(BadInputError, match="pass layer_spacing"):
        read_scan(d, convention=CONV, units="um")
    ds = read_scan(d, convention=CONV, units="um", layer_spacing=1e-3)
    np.testing.assert_allclose(ds["z"].values, scan.truth["z"].values, atol=1e-12)
    # layer 3 loses its last 10 points
    lines = (d / "layer03.txt").read_text().splitlines()
    (d / "layer03.txt").write_text("\n".join(lines[:-10]) + "\n")
    with pytest.raises(BadInputError, match=r"layer03.txt'.*layer 3 has 350 points.*re-export"):
        read_scan(d, convention=CONV, units="um", layer_spacing=1e-3)
    with pytest.raises(BadInputError, match=r"expected 360 points in layer 1, found 350"):
        read_scan(d, convention=CONV, units="um", layer_spacing=1e-3, expected_points=360)
    part = read_scan(d, convention=CONV, units="um", layer_spacing=1e-3, allow_partial=True)
    assert int(np.isnan(part["radial_deviation"].values).sum()) == 10


BAD = {
    "truncated": (
        "Units: um\nAngle\tDev\n0.0\t1.0\n1.0\t2.0\n2.0\t3.0\n3.0\n",
        r"line 6: expected 2 fields, found 1.*truncated",
    ),
    "nan": (
        "Units: um\n0.0\t1.0\n1.0\t2.0\n2.0\tnan\n3.0\t1.0\n",
        r"layer 1 has 1 of 4 points missing \(25.0%\), more than max_missing",
    ),
    "text": (
        "Units: um\n0.0\t1.0\n1.0\t2.0\n2.0\t2.5\n3.0\tabc\n",
        r"line 5: 'abc' is not a number.*fix the line",
    ),
    "duplicate": (
        "Units: um\n0.0\t1.0\n1.0\t2.0\n1.0\t2.0\n3.0\t1.0\n4.0\t1.0\n",
        r"line 4: angle 1 repeats.*duplicate",
    ),
    "backwards": (
        "Units: um\n0.0\t1.0\n1.0\t2.0\n2.0\t2.0\n1.5\t1.0\n4.0\t1.0\n5.0\t1.0\n",
        r"line 5: angle 1.5 goes back",
    ),
    "units": (
        "Units: furlong\n0.0\t1.0\n1.0\t2.0\n2.0\t3.0\n",
        r"line 1: unit 'furlong' is not known.*units=",
    ),
    "empty": ("", r"is empty \(line 1\).*re-export"),
    "blank": ("\n\n   \n", r"is empty"),
    "no_table": ("Instrument: Talyrond\nOperator: me\n", r"no table of numbers found"),
}


@pytest.mark.parametrize("name", list(BAD))
def test_bad_input_messages(tmp_path, name):
    text, pattern = BAD[name]
    f = tmp_path / f"{name}.txt"
    f.write_text(text)
    with pytest.raises(BadInputError, match=pattern) as exc:
        read_scan(
            f,
            convention=CONV,
            columns=("angle_deg", "deviation")
            if name not in ("empty", "blank", "no_table")
            else None,
        )
    assert f"{name}.txt" in str(exc.value)


def test_binary_garbage(tmp_path):
    f = tmp_path / "scan.bin"
    f.write_bytes(bytes(range(256)) * 10)
    with pytest.raises(
        BadInputError, match=r"scan.bin' looks like a binary file.*export the trace as text"
    ):
        read_scan(f, convention=CONV)


def test_header_metadata_and_names(tmp_path):
    f = tmp_path / "x.csv"
    f.write_text(
        "Instrument;Talyrond 565H\nDate;2024-01-02\nNominal radius;8,000 mm\n"
        "Winkel [deg];Abweichung [µm]\n"
        + "".join(
            f"{i * 10:.1f};{np.cos(np.radians(i * 20)):.4f}".replace(".", ",") + "\n"
            for i in range(36)
        )
    )
    pf = parse_file(f)
    assert pf.fmt.delimiter == ";" and pf.fmt.decimal == ","
    assert pf.columns == ("angle_deg", "deviation")
    assert pf.units == "µm"
    ds = read_scan(f, convention=CONV)
    assert ds.attrs["instrument"] == "Talyrond 565H"
    assert ds.attrs["nominal_radius"] == pytest.approx(8e-3)
    assert ds["radial_deviation"].max().item() == pytest.approx(1e-6, rel=1e-6)


# --- hypothesis: the sniffer recovers any well-formed table; garbage gives BadInputError ---

_delims = st.sampled_from(["\t", ";", ",", " "])


@settings(
    max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    delim=_delims,
    dec=st.sampled_from([".", ","]),
    ncol=st.integers(1, 4),
    nrow=st.integers(5, 40),
    nhead=st.integers(0, 3),
    names=st.booleans(),
    seed=st.integers(0, 2**31 - 1),
)
def test_sniffer_recovers_tables(tmp_path_factory, delim, dec, ncol, nrow, nhead, names, seed):
    if dec == "," and delim == ",":
        dec = "."
    rng = np.random.default_rng(seed)
    data = rng.uniform(-500, 500, (nrow, ncol)).round(4)
    sep = "  " if delim == " " else delim
    head = "".join(f"Key{i}: value {i}\n" for i in range(nhead))
    if names:
        head += sep.join(f"col{i}" for i in range(ncol)) + "\n"
    body = "".join(sep.join(f"{v:.4f}".replace(".", dec) for v in row) + "\n" for row in data)
    f = tmp_path_factory.mktemp("s") / "t.txt"
    f.write_text(head + body)
    pf = parse_file(f)
    assert pf.data.shape == data.shape
    np.testing.assert_allclose(pf.data, data, atol=1e-9)
    assert pf.fmt.header_lines == nhead + names
    for i in range(nhead):
        assert pf.metadata[f"Key{i}"] == f"value {i}"


@settings(
    max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(text=st.text(alphabet=string.printable + "µé\x00\x07", max_size=300))
def test_sniffer_never_crashes(tmp_path_factory, text):
    f = tmp_path_factory.mktemp("g") / "g.txt"
    f.write_text(text, encoding="utf-8")
    try:
        ds = read_scan(f, convention=CONV, units="um")
    except BadInputError as exc:
        assert "g.txt" in str(exc) or re.search(r"layer|layers|z|points", str(exc))
    else:
        assert ds.sizes["theta"] >= 3


@settings(
    max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    layout=st.sampled_from(["folder", "folder-names", "folder-header", "long", "wide", "single"]),
    angle=st.sampled_from(["deg", "rad", "index", "none", "xy"]),
    delim=_delims,
    dec=st.sampled_from([".", ","]),
    units=st.sampled_from(["um", "mm", "m", "inch"]),
    value=st.sampled_from(["deviation", "radius"]),
    header=st.booleans(),
    names=st.booleans(),
    n_layers=st.integers(1, 5),
    n_points=st.sampled_from([18, 90, 360]),
)
def test_every_written_combination_reads_back(
    tmp_path_factory, layout, angle, delim, dec, units, value, header, names, n_layers, n_points
):
    """Any file the generator can write is read back without options (except what the file
    cannot say without a header: units, angle unit, span, z unit; z of an unnamed wide file)."""
    if delim == dec or (layout == "wide" and angle == "xy"):
        return
    header = header or layout == "folder-header"
    sc = generate(n_layers=n_layers, n_points=n_points, seed=n_points + n_layers)
    d = tmp_path_factory.mktemp("w")
    path = d / ("s" if layout.startswith("folder") else "s.txt")
    write(
        sc,
        path,
        layout=layout,
        angle=angle,
        delimiter=delim,
        decimal=dec,
        units=units,
        value=value,
        header=header,
        column_names=names,
    )
    kw = {}
    if not header:
        kw["units"] = units
        if not names and angle in ("rad", "index"):
            kw["angle_unit"] = angle  # 0..17 is a point index or 17 degrees: the file can't say
        if angle == "none":
            kw["arc"] = "full"
        if layout == "long" and not names:
            kw["z_units"] = "mm"
    if layout == "wide" and not names:
        kw["layer_spacing"] = 1e-3
    ds = read_scan(path, convention=CONV, **kw)
    ref = scan_values = sc.truth["radius"].values
    if layout == "single":
        ref = scan_values[:1]
    got = _values(ds, sc.nominal_radius)
    np.testing.assert_allclose(got, ref, atol=1e-9)
