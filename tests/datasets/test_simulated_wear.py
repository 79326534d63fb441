"""Generated scans can carry a simulated wear map: the function reproduces the map it is given."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from jointwear.datasets.simulated_wear import wear_from_simulation
from jointwear.errors import BadInputError


def _map(h_of) -> xr.Dataset:
    theta = np.arange(0.0, 360.0, 2.0)
    z = np.linspace(-7.5e-3, 7.5e-3, 16)
    cycles = np.array([1e5, 4e5])
    T, Z = np.meshgrid(theta, z)
    h = np.stack([0.5 * h_of(T, Z), h_of(T, Z)])
    return xr.Dataset(
        {"wear_depth": (("cycles", "z", "theta"), h)},
        coords={"cycles": cycles, "z": z, "theta": theta},
    )


def _smooth(theta_deg, z):
    # linear in z (bilinear interpolation is exact in z) and a slow cosine in theta
    return 1e-6 * (2.0 + np.cos(np.radians(theta_deg - 240.0))) * (1.0 + 40.0 * z)


def test_reproduces_the_map_and_applies_scale_and_rotation():
    h = wear_from_simulation(_map(_smooth), scale=1.1, rotation_deg=6.0)
    theta = np.linspace(0.0, 359.0, 97)
    z = np.full_like(theta, 2.3e-3)
    expected = 1.1 * _smooth(theta - 6.0, z)
    # only the theta interpolation errs: 2-degree spacing of a 1-cycle cosine, < 2e-4 relative
    np.testing.assert_allclose(h(theta, z), expected, rtol=2e-4)
    # the peak moved by the rotation
    fine = np.linspace(0.0, 360.0, 3601)[:-1]
    assert fine[np.argmax(h(fine, np.zeros_like(fine)))] == pytest.approx(246.0, abs=0.2)


def test_earlier_snapshot_and_clamping_outside_the_width():
    ds = _map(_smooth)
    early = wear_from_simulation(ds, cycles=1e5)
    last = wear_from_simulation(ds)
    theta = np.array([240.0, 60.0])
    np.testing.assert_allclose(early(theta, 0.0), 0.5 * last(theta, 0.0))
    # beyond the simulated width the edge value holds, not an extrapolation
    np.testing.assert_allclose(last(theta, 9e-3), last(theta, 7.5e-3))


def test_missing_snapshot_or_variable_is_refused():
    with pytest.raises(BadInputError, match="no snapshot at 200000 cycles"):
        wear_from_simulation(_map(_smooth), cycles=2e5)
    with pytest.raises(BadInputError, match="wear_depth"):
        wear_from_simulation(xr.Dataset())
    with pytest.raises(BadInputError, match="--wear-scale"):
        wear_from_simulation(_map(_smooth), scale=-1.0)


def test_the_command_imposes_the_simulated_wear_scaled_turned_on_its_bore(tmp_path):
    from jointwear import io
    from jointwear.cli import main
    from jointwear.conventions import theta_coord, z_coord

    sim = _map(_smooth)
    sim = sim.assign_coords(theta=theta_coord(sim["theta"].values), z=z_coord(sim["z"].values))
    sim["cycles"].attrs.update(units="1", long_name="crank cycles")
    sim["wear_depth"].attrs.update(units="m", long_name="wear depth")
    sim.attrs.update(data_origin="simulated", bearing_radius_m=7.9e-3)
    io.save(sim, tmp_path / "sim.nc")
    args = ["datasets", "instruments", str(tmp_path / "scan.txt"), "--layout", "long"]
    args += ["--wear-from", str(tmp_path / "sim.nc"), "--wear-scale", "1.1"]
    args += ["--wear-rotation-deg", "6", "--truth", str(tmp_path / "truth.nc")]
    assert main(args) == 0
    truth = io.load(tmp_path / "truth.nc")
    expected = wear_from_simulation(sim, scale=1.1, rotation_deg=6.0)
    theta, z = np.meshgrid(truth["theta"].values, truth["z"].values)
    np.testing.assert_allclose(truth["wear_depth"].values, expected(theta, z), rtol=1e-12)
    assert truth.attrs["nominal_radius"] == 7.9e-3  # the simulated bore's, not the default
    assert (tmp_path / "scan.txt").is_file()
