"""Form assessment: minimum zone, least squares, inscribed/circumscribed references."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr
from hypothesis import given, settings
from hypothesis import strategies as st

from jointwear.errors import BadInputError
from jointwear.metrology.assess import assess
from jointwear.metrology.form import (
    circle_zone,
    circle_zones,
    cylinder_zone,
    cylindricity,
    limacon_error,
    normalise_reference,
    roundness,
)

R = 8e-3


def _zone_profile(n=720, t=3e-6, centre=(4e-6, -7e-6), seed=0):
    """Limaçon profile whose minimum zone is exactly t (4 alternating extreme points)."""
    rng = np.random.default_rng(seed)
    th = np.sort(rng.uniform(0, 360, n))
    th[:4] = [0.0, 90.0, 180.0, 270.0]
    rho = R + rng.uniform(0.05 * t, 0.95 * t, n)
    rho[:4] = [R + t, R, R + t, R]
    rad = np.radians(th)
    r = rho + centre[0] * np.cos(rad) + centre[1] * np.sin(rad)
    return th, r


def test_minimum_zone_exact_on_constructed_profile():
    th, r = _zone_profile()
    res = circle_zone(th, r, reference="MZ")
    assert res.total == pytest.approx(3e-6, abs=1e-9)
    assert res.centre[0] == pytest.approx(4e-6, abs=1e-9)
    assert res.centre[1] == pytest.approx(-7e-6, abs=1e-9)
    assert res.peak == pytest.approx(1.5e-6, abs=1e-9)
    assert res.valley == pytest.approx(1.5e-6, abs=1e-9)
    # the least-squares zone of the same points is wider
    assert circle_zone(th, r, reference="LS").total > res.total + 1e-9


def test_pure_harmonic_all_references():
    th = np.arange(3600) * 0.1
    rad = np.radians(th)
    a = 2e-6
    r = R + 5e-6 * np.cos(rad) - 3e-6 * np.sin(rad) + a * np.cos(3 * rad)
    for ref in ("LS", "MZ", "MI", "MC"):
        res = circle_zone(th, r, reference=ref)
        assert res.total == pytest.approx(2 * a, rel=1e-9), ref
        assert res.centre[0] == pytest.approx(5e-6, abs=1e-12), ref
        assert res.centre[1] == pytest.approx(-3e-6, abs=1e-12), ref
    ls = circle_zone(th, r, reference="LS")
    assert ls.radius == pytest.approx(R, rel=1e-12)
    assert ls.rms == pytest.approx(a / np.sqrt(2), rel=1e-9)
    mi = circle_zone(th, r, reference="MI")
    assert mi.valley == 0.0 and mi.radius == pytest.approx(R - a, rel=1e-12)
    mc = circle_zone(th, r, reference="MC")
    assert mc.peak == 0.0 and mc.radius == pytest.approx(R + a, rel=1e-12)


def test_cylindricity_recovers_tilt_and_zone():
    nz, nt = 5, 2000
    z = (np.arange(nz) - 2) * 1e-3
    th = np.arange(nt) * 360.0 / nt
    rad = np.radians(th)
    zz, tt = np.meshgrid(z, rad, indexing="ij")
    a = 1.5e-6
    r = R + (3e-6 + 2e-3 * zz) * np.cos(tt) + (-1e-6 + 5e-3 * zz) * np.sin(tt) + a * np.cos(4 * tt)
    da = xr.DataArray(r, dims=("z", "theta"), coords={"z": z, "theta": th})
    for ref in ("MZ", "LS", "MI", "MC"):
        assert cylindricity(da, reference=ref) == pytest.approx(2 * a, rel=1e-7), ref
    res = cylinder_zone(np.broadcast_to(z[:, None], r.shape), np.degrees(tt), r, reference="MZ")
    assert res.tilt[0] == pytest.approx(2e-3, abs=1e-8)
    assert res.tilt[1] == pytest.approx(5e-3, abs=1e-8)
    assert res.centre[0] == pytest.approx(3e-6, abs=1e-10)


def test_cylindricity_of_taper_is_its_radius_change():
    z = np.linspace(-6e-3, 6e-3, 13)
    th = np.arange(720) * 0.5
    r = R + 4e-6 * (z[:, None] / 6e-3) + 0 * th[None, :]
    da = xr.DataArray(r, dims=("z", "theta"), coords={"z": z, "theta": th})
    # a taper cannot be removed by tilting the axis: the zone is the radius change, 8 µm
    assert cylindricity(da) == pytest.approx(8e-6, abs=1e-9)
    assert cylindricity(xr.Dataset({"radius": da}), reference="LS") == pytest.approx(8e-6, rel=1e-9)


@settings(max_examples=25, deadline=None)
@given(
    seed=st.integers(0, 2**31 - 1),
    n=st.integers(12, 200),
    amp=st.floats(1e-8, 1e-4),
)
def test_minimum_zone_is_narrowest(seed, n, amp):
    rng = np.random.default_rng(seed)
    # one point per sector of 360/n degree: the points surround the axis
    th = (np.arange(n) + rng.uniform(0.05, 0.95, n)) * 360.0 / n
    r = R + amp * rng.standard_normal(n)
    mz = circle_zone(th, r, reference="MZ").total
    for ref in ("LS", "MI", "MC"):
        assert mz <= circle_zone(th, r, reference=ref).total * (1 + 1e-9) + 1e-13


def test_roundness_per_layer():
    z = np.array([0.0, 1e-3])
    th = np.arange(360.0)
    r = R + np.array([[1e-6], [2e-6]]) * np.cos(np.radians(2 * th))[None, :]
    da = xr.DataArray(r, dims=("z", "theta"), coords={"z": z, "theta": th})
    out = roundness(da, reference="LSCI")
    np.testing.assert_allclose(out.values, [2e-6, 4e-6], rtol=1e-9)
    assert roundness(da.isel(z=0)) == pytest.approx(2e-6, rel=1e-9)


def test_nan_points_are_ignored():
    th, r = _zone_profile(n=400)
    r2 = r.copy()
    r2[10:20] = np.nan
    assert circle_zone(th, r2).total == pytest.approx(3e-6, abs=1e-9)


def test_bad_inputs():
    with pytest.raises(BadInputError, match="reference 'XX' is not known"):
        normalise_reference("XX")
    with pytest.raises(BadInputError, match="only 2 finite points"):
        circle_zone([0, 90, 180], [1.0, 1.0, np.nan])
    z = np.zeros(10)
    with pytest.raises(BadInputError, match="at least two layers"):
        cylinder_zone(z, np.arange(10) * 36.0, np.ones(10))
    with pytest.raises(BadInputError, match="could not be computed"):
        circle_zone(np.linspace(0, 30, 20), R + np.linspace(0, 1e-6, 20), reference="MI")
    with pytest.raises(BadInputError, match="neither 'radius' nor 'radial_deviation'"):
        cylindricity(xr.Dataset({"x": ("z", [1.0])}))
    with pytest.raises(BadInputError, match=r"assess: .*neither 'radius' nor 'radial_deviation'"):
        assess(xr.Dataset({"x": ("z", [1.0])}))


def test_limacon_error():
    assert limacon_error(40e-6, 8e-3) == pytest.approx(40e-6**2 / (4 * 8e-3))
    # closed form check: exact radius about an offset axis minus the limaçon
    e, rr = 200e-6, 8e-3
    phi = np.radians(np.arange(360.0))
    exact = e * np.cos(phi) + np.sqrt(rr**2 - (e * np.sin(phi)) ** 2)
    lim = rr + e * np.cos(phi)
    amp = 0.5 * np.ptp(exact - lim)
    assert amp == pytest.approx(limacon_error(e, rr), rel=1e-3)


def test_block_lp_matches_single_layer_solves():
    rng = np.random.default_rng(7)
    th = np.arange(720) * 0.5
    rad = np.radians(th)
    r = (
        R
        + rng.uniform(-5e-6, 5e-6, (4, 1)) * np.cos(rad)
        + 1e-6 * np.cos(3 * rad + rng.uniform(0, 6, (4, 1)))
        + 0.2e-6 * rng.standard_normal((4, 720))
    )
    r[1, 5:9] = np.nan
    for ref in ("MZ", "MI", "MC", "LS"):
        block = circle_zones(th, r, reference=ref)
        for i in range(4):
            single = circle_zone(th, r[i], reference=ref)
            assert block[i].total == pytest.approx(single.total, abs=1e-12), ref
            assert block[i].radius == pytest.approx(single.radius, abs=1e-12), ref
