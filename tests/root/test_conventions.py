"""Angle conventions and the data-contract validator."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr
from hypothesis import given, settings
from hypothesis import strategies as st

from jointwear import conventions as C
from jointwear.errors import ConventionError


def _field(theta_deg, convention, values=None):
    theta = C.theta_coord(theta_deg, convention)
    if values is None:
        values = np.arange(len(theta_deg), dtype=float)
    return xr.DataArray(values, coords={"theta": theta}, dims="theta", name="wear_depth")


def test_known_conversion_plus_x_counterclockwise_to_canonical():
    # +x counter-clockwise: 0 -> +x, 90 -> +y, 180 -> -x, 270 -> -y.
    # canonical (-x, clockwise): -x -> 0, +y -> 90, +x -> 180, -y -> 270.
    da = _field([0.0, 90.0, 180.0, 270.0], C.AngleConvention("+x", "counterclockwise"))
    out = C.to_canonical(da)
    np.testing.assert_array_equal(out.theta.values, [0.0, 90.0, 180.0, 270.0])
    np.testing.assert_array_equal(out.values, [2.0, 1.0, 0.0, 3.0])
    assert out.theta.attrs["angle_zero"] == "-x"
    assert out.theta.attrs["angle_direction"] == "clockwise"


def test_numeric_origin_and_wraparound_sorted():
    # zero at 30 deg ccw from +x, clockwise: physical psi = 30 - theta
    conv = C.AngleConvention("30", "clockwise")
    theta = np.array([0.0, 10.0, 200.0, 350.0])
    da = _field(theta, conv)
    out = C.to_canonical(da)
    psi = 30.0 - theta
    expected = np.mod(180.0 - psi, 360.0)  # canonical theta = 180 - psi
    order = np.argsort(expected)
    np.testing.assert_allclose(out.theta.values, expected[order])
    np.testing.assert_array_equal(out.values, da.values[order])
    assert np.all(np.diff(out.theta.values) > 0)
    assert out.theta.values.min() >= 0 and out.theta.values.max() < 360


conventions = st.builds(
    C.AngleConvention,
    zero=st.one_of(
        st.sampled_from(["+x", "-x", "+y", "-y"]),
        st.floats(-720, 720, allow_nan=False).map(lambda v: f"{v:.6f}"),
    ),
    direction=st.sampled_from(["clockwise", "counterclockwise"]),
)


@settings(max_examples=60, deadline=None)
@given(conv=conventions, other=conventions, n=st.integers(1, 40), offset=st.floats(0, 359))
def test_round_trip_any_convention(conv, other, n, offset):
    theta = np.mod(offset + np.arange(n) * 360.0 / n, 360.0)
    theta = np.round(theta, 6)
    theta = np.unique(theta)
    da = _field(theta, conv, values=np.sin(np.deg2rad(theta)) + theta / 1000)
    there = C.convert_theta(da, other)
    back = C.convert_theta(there, conv)
    ref = da.sortby("theta")
    np.testing.assert_allclose(back.theta.values, ref.theta.values, atol=1e-9)
    np.testing.assert_array_equal(back.values, ref.values)
    assert back.theta.attrs["angle_zero"] == conv.zero


def test_conversion_preserves_physical_direction():
    # a value sitting at physical +y must end at canonical 90 from any convention
    for conv in [
        C.AngleConvention(z, d)
        for z in ("+x", "-y", "123.4")
        for d in ("clockwise", "counterclockwise")
    ]:
        theta_at_plus_y = conv.from_physical(np.array([90.0]))[0]
        da = _field([theta_at_plus_y], conv, values=np.array([7.0]))
        out = C.to_canonical(da)
        assert out.theta.values[0] == pytest.approx(90.0, abs=1e-9)


def test_refuses_unstated_convention():
    da = xr.DataArray(
        [1.0, 2.0], coords={"theta": ("theta", [0.0, 180.0], {"units": "degree"})}, dims="theta"
    )
    with pytest.raises(ConventionError, match="does not state its angle convention"):
        C.to_canonical(da)


def test_bad_convention_names():
    with pytest.raises(ConventionError, match="angle_zero 'north'"):
        C.AngleConvention("north", "clockwise")
    with pytest.raises(ConventionError, match="angle_direction 'sideways'"):
        C.AngleConvention("-x", "sideways")


def _dataset():
    return xr.Dataset(
        {"wear_depth": (("z", "theta"), np.zeros((3, 4)), C.variable_attrs("wear_depth"))},
        coords={"z": C.z_coord([-1e-3, 0.0, 1e-3]), "theta": C.theta_coord([0, 90, 180, 270])},
    )


def test_validate_accepts_contract_dataset():
    assert C.validate(_dataset()) is not None


def test_validate_lists_every_problem():
    ds = _dataset()
    del ds["wear_depth"].attrs["units"]
    ds["wear_depth"].attrs["long_name"] = "x"
    ds = ds.assign_coords(
        z=("z", [0.0, 2e-3, 1e-3], {"units": "mm", "z_zero": "mid", "z_direction": "+z"})
    )
    ds["extra"] = ("z", np.ones(3))
    with pytest.raises(ConventionError) as info:
        C.validate(ds)
    text = str(info.value)
    assert "'wear_depth' has no 'units'" in text
    assert "'extra' has no 'units'" in text
    assert "coordinate 'z' has units 'mm'" in text
    assert "'z' is not strictly monotonic" in text


def test_validate_wrong_units_and_theta_range():
    ds = _dataset()
    ds["wear_depth"].attrs["units"] = "um"
    ds = ds.assign_coords(theta=C.theta_coord([0, 90, 180, 360]))
    with pytest.raises(ConventionError, match=r"units 'um', the contract says 'm'") as info:
        C.validate(ds)
    assert "[0, 360)" in str(info.value)
