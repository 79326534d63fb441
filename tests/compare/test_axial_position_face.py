"""The axial position of the maximum wear when wear peaks at a bearing face (#37): decided when
the measured map reaches that face, not comparable (saying what would decide it) otherwise."""

from __future__ import annotations

import numpy as np
import pytest
from _jw_synth import wear_history

import jointwear.compare.verdicts as vd
from jointwear import conventions
from jointwear.compare import compare

WIDTH = 15e-3
THETA = np.arange(0.0, 360.0, 5.0)


def _edge_wear(z, z_peak=None, scale=1.0):
    """Wear peaked at 240 degree [m], growing towards the face z = -7.5 mm (``z_peak`` None)
    or peaked at ``z_peak``."""
    z = np.asarray(z)[:, None]
    axial = (
        np.exp(-(z + WIDTH / 2) / 3e-3) if z_peak is None else np.exp(-(((z - z_peak) / 2e-3) ** 2))
    )
    return scale * 5e-6 * np.exp(-(((THETA - 240.0) / 30.0) ** 2))[None, :] * axial


def _sim():
    z = np.linspace(-WIDTH / 2, WIDTH / 2, 9)
    ds = wear_history(_edge_wear(z)[None], [1e6], z, THETA)
    ds.attrs.update({"title": "simulated", "data_origin": "simulated", "bearing_radius_m": 8e-3})
    return ds


def _meas(z, **kw):
    import xarray as xr

    ds = xr.Dataset(coords={"z": conventions.z_coord(z), "theta": conventions.theta_coord(THETA)})
    ds["wear_depth"] = (
        ("z", "theta"),
        _edge_wear(z, **kw),
        conventions.variable_attrs("wear_depth"),
    )
    ds.attrs.update({"title": "measured", "data_origin": "synthetic", "cycles": 1e6})
    return ds


def _axial(result):
    rows = result.decisions[result.decisions.quantity.str.startswith("axial position")]
    assert len(rows) == 1
    return rows.iloc[0]


def test_a_full_width_map_decides_a_maximum_on_the_face():
    full = _meas(np.linspace(-WIDTH / 2, WIDTH / 2, 16), scale=1.1)
    row = _axial(compare([_sim()], [full]))
    assert row.state == vd.PASS, row.reason
    assert "+0.00 mm (sim -7.50, meas -7.50)" in row.value


def test_a_full_width_map_whose_maximum_is_elsewhere_fails():
    # the measured wear peaks 4 mm inside the face: the criterion (3 mm) is decided, and fails
    full = _meas(np.linspace(-WIDTH / 2, WIDTH / 2, 16), z_peak=-3.5e-3)
    z = np.linspace(-WIDTH / 2, WIDTH / 2, 16)
    row = _axial(compare([_sim()], [full]))
    assert row.state == vd.FAIL
    z_meas = z[np.argmin(np.abs(z + 3.5e-3))]
    assert f"meas {z_meas * 1e3:+.2f}" in row.value


@pytest.mark.parametrize("half", [6e-3, 7e-3])
def test_a_band_short_of_the_face_says_what_would_decide_it(half):
    short = _meas(np.linspace(-half, half, 13))
    row = _axial(compare([_sim()], [short]))
    assert row.state == vd.NOT_COMPARABLE
    assert f"lie on its edge layer z = {-half * 1e3:+.2f} mm" in row.reason
    assert "a measured map reaching z = -7.50 mm" in row.reason
