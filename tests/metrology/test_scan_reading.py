"""A reader's options as one frozen ScanReading: the dataclass and its fields given as keywords
read a file identically, a keyword replaces the reading's, a preset keeps what the reading sets
rather than its own default, and an unknown or ill-chosen option is refused."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from jointwear.datasets.instruments import generate, write
from jointwear.errors import BadInputError
from jointwear.metrology import ScanReading, read_scan, read_talyrond

CONV = ("+y", "counterclockwise")


@pytest.fixture(scope="module")
def scan():
    return generate(n_layers=3, n_points=360, seed=5, convention=CONV)


def test_a_reading_and_its_fields_read_the_same(tmp_path, scan):
    target = tmp_path / "scan.txt"
    write(scan, target, layout="wide", delimiter=";", decimal=",", units="m")
    opts = dict(layout="wide", delimiter=";", decimal=",", expected_points=360)
    by_keywords = read_scan(target, convention=CONV, **opts)
    by_reading = read_scan(target, convention=CONV, reading=ScanReading(**opts))
    xr.testing.assert_identical(by_keywords, by_reading)
    np.testing.assert_allclose(
        by_reading["radial_deviation"].values + scan.nominal_radius,
        scan.truth["radius"].values,
        atol=2e-10,
    )
    # a keyword replaces the reading's choice ("long" would misread this wide file)
    wrong = ScanReading(**{**opts, "layout": "long"})
    replaced = read_scan(target, convention=CONV, reading=wrong, layout="wide")
    xr.testing.assert_identical(by_keywords, replaced)


def test_a_preset_keeps_what_the_reading_sets(tmp_path, scan):
    f = tmp_path / "trace.txt"
    write(scan, f, layout="single", header=False, column_names=False, angle="none")
    preset = read_talyrond(f, convention=CONV)  # the preset's defaults: µm, its instrument name
    assert preset.attrs["source"] == "measurement: Taylor Hobson Talyrond"
    by_keyword = read_talyrond(f, convention=CONV, instrument="Talyrond 365")
    by_reading = read_talyrond(f, convention=CONV, reading=ScanReading(instrument="Talyrond 365"))
    xr.testing.assert_identical(by_keyword, by_reading)
    assert by_reading.attrs["source"] == "measurement: Talyrond 365"
    np.testing.assert_array_equal(
        by_reading["radial_deviation"].values, preset["radial_deviation"].values
    )


def test_unknown_or_ill_chosen_options_are_refused(tmp_path, scan):
    target = tmp_path / "scan.txt"
    write(scan, target, layout="wide")
    with pytest.raises(TypeError, match="layuot"):
        read_scan(target, convention=CONV, layuot="wide")
    with pytest.raises(BadInputError, match="value must be 'auto', 'radius' or 'deviation'"):
        ScanReading(value="both")
    with pytest.raises(BadInputError, match="layout 'diagonal' is not known"):
        read_scan(target, convention=CONV, layout="diagonal")


def test_given_names_the_fields_set():
    reading = ScanReading(units="um", z=np.array([0.0, 1e-3]), allow_partial=False)
    assert set(reading.given()) == {"units", "z"}
    assert ScanReading().given() == {}
