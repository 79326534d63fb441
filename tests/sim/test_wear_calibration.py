"""kw calibration: linear estimate, its check by re-simulation, and maps in another convention."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from jointwear import conventions
from jointwear.errors import BadInputError
from jointwear.sim import (
    BearingGrid,
    ConstantContact,
    WearSettings,
    WinklerContact,
    calibrate_kw,
    simulate_wear,
)

GRID = BearingGrid(10, 72)


def smooth_pressure(theta_deg, z):
    """An analytic pressure field [Pa] (two lobes, axially asymmetric)."""
    th = np.deg2rad(theta_deg)
    return 1e6 * (1.2 + np.cos(2 * (th - np.deg2rad(80)))) * (1.0 + 40.0 * z)


def constant_model(grid=GRID):
    p = smooth_pressure(grid.theta_deg[None, :], grid.z[:, None])
    return ConstantContact(grid, pressure=p, sliding=0.02)


def test_linear_wear_gives_the_exact_kw_in_one_step():
    model = constant_model()
    sim = simulate_wear(contact=model, cycles=4e5, settings=WearSettings(kw=1e-14))
    measured = 3.7 * float(sim["max_wear_depth"][-1])
    cal = calibrate_kw(sim, measured)
    assert cal.kw == pytest.approx(3.7e-14, rel=1e-9)
    assert cal.linearity_error is None and not cal.converged

    def resim(kw):
        return simulate_wear(contact=model, cycles=4e5, settings=WearSettings(kw=kw))

    cal = calibrate_kw(sim, measured, resimulate=resim)
    assert cal.converged and len(cal.iterations) == 2
    assert abs(cal.linearity_error) < 1e-9
    vol = calibrate_kw(sim, 2.0 * float(sim["worn_volume"][-1]), quantity="volume")
    assert vol.kw == pytest.approx(2e-14, rel=1e-9)


def test_profile_feedback_breaks_linearity_and_resimulation_repairs_it():
    model = WinklerContact(GRID, load=20.0, load_angle_deg=90.0, foundation_modulus=1e11)
    settings = WearSettings(kw=1e-13, tol=0.1)
    n = 50_000

    def resim(kw):
        return simulate_wear(
            contact=model, cycles=n, snapshots=[], settings=WearSettings(kw=kw, tol=0.1)
        )

    kw_true = 4e-13
    measured = float(resim(kw_true)["max_wear_depth"][-1])
    sim = simulate_wear(contact=model, cycles=n, snapshots=[], settings=settings)
    cal = calibrate_kw(sim, measured, resimulate=resim, rtol=0.01)
    # the conformal wear spreads: depth grows more slowly than kw, the linear guess is too low
    assert cal.kw_linear < 0.95 * kw_true
    assert cal.linearity_error < -0.05
    assert cal.converged
    assert cal.kw == pytest.approx(kw_true, rel=0.03)


def test_calibration_from_a_measured_map_in_another_convention():
    model = constant_model()
    n, kw_true = 4e5, 2.5e-14
    sim = simulate_wear(contact=model, cycles=n, settings=WearSettings(kw=1e-14))
    # a "measured" map: 13 layers 1 mm apart, 90 points, theta = 0 along +x, counter-clockwise
    z = np.linspace(-6e-3, 6e-3, 13)
    th_meas = np.arange(90) * 4.0
    th_canon = (180.0 - th_meas) % 360.0  # the same physical directions, canonical angles
    depth = n * kw_true * 0.02 * smooth_pressure(th_canon[None, :], z[:, None])
    meas = xr.DataArray(
        depth,
        dims=("z", "theta"),
        coords={
            "z": conventions.z_coord(z),
            "theta": conventions.theta_coord(th_meas, conventions.AngleConvention("+x", "ccw")),
        },
        name="wear_depth",
    )
    cal = calibrate_kw(sim, meas.to_dataset(), cycles=n)
    assert cal.quantity == "map"
    assert cal.kw == pytest.approx(kw_true, rel=0.01)
    # the same map read with the wrong convention would not fit as well
    wrong = meas.copy()
    wrong["theta"].attrs.update(angle_zero="-x", angle_direction="clockwise")
    assert abs(calibrate_kw(sim, wrong, cycles=n).kw / kw_true - 1) > 0.05


def test_calibration_refuses_bad_input():
    sim = simulate_wear(contact=constant_model(), cycles=1000, settings=WearSettings(kw=1e-14))
    with pytest.raises(BadInputError, match="must be positive"):
        calibrate_kw(sim, -1e-6)
    with pytest.raises(BadInputError, match="measurement is at 2000 cycles"):
        calibrate_kw(sim, 1e-6, cycles=2000)
    with pytest.raises(BadInputError, match="needs a measured wear map"):
        calibrate_kw(sim, 1e-6, quantity="map")
    meas = sim["wear_depth"].isel(cycles=-1).drop_vars("cycles")
    meas = meas.assign_coords(z=meas["z"] * 3)
    with pytest.raises(BadInputError, match="beyond the simulated bearing"):
        calibrate_kw(sim, meas)
    unstated = sim["wear_depth"].isel(cycles=-1).drop_vars("cycles")
    unstated["theta"].attrs = {"units": "degree"}
    with pytest.raises(conventions.ConventionError, match="does not state its angle convention"):
        calibrate_kw(sim, unstated)
