"""Layers crowded towards the bearing edges (``joint.axial_grading``, issue 16 item 2).

Closed forms: the layer positions of the blend of equal spacing and Chebyshev-Gauss-Lobatto
points, trapezoid shares that integrate polynomials of degree 1 exactly (and converge at second
order), the patch areas adding up to the bore; a tilted journal pressed on one edge keeps its
closed-form force on a graded grid; a graded map survives resampling and the Dataset round trip.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from jointwear.errors import ParameterError
from jointwear.params import replace_nested
from jointwear.sim import PARAMETER_SETS
from jointwear.sim.dynamics import _layers, point_area, wear_depth_on_grid
from jointwear.sim.wearmap import BearingGrid, layer_positions, wear_map_dataset, worn_volume

BASE = PARAMETER_SETS["zhang2023"]
WB = 15e-3


def test_zero_grading_is_the_study_spacing():
    z, share = layer_positions(20, WB, 0.0)
    np.testing.assert_allclose(z, WB / 2 - np.arange(20) * WB / 19, atol=1e-15)
    want = np.full(20, 1 / 19)
    want[[0, -1]] = 0.5 / 19
    np.testing.assert_allclose(share, want, rtol=1e-12)


@pytest.mark.parametrize("g", [0.3, 0.75, 0.95])
@pytest.mark.parametrize("n", [2, 7, 20, 80])
def test_graded_layers_are_symmetric_ordered_and_crowd_at_the_edges(n, g):
    z, share = layer_positions(n, WB, g)
    assert z[0] == WB / 2 and z[-1] == -WB / 2
    assert np.all(np.diff(z) < 0)
    np.testing.assert_allclose(z, -z[::-1], atol=1e-15)
    assert share.sum() == pytest.approx(1.0, rel=1e-14)
    if n >= 20:
        dz = -np.diff(z)
        uniform = WB / (n - 1)
        # the edge spacing is (1 - g) times the equal one to first order, the middle wider
        ds = 2.0 / (n - 1)
        ratio = dz[0] / uniform
        assert 1 - g < ratio <= 1 - g + g * math.pi**2 / 8 * ds * 1.0001
        assert dz[n // 2 - 1] / uniform == pytest.approx(1 + (math.pi / 2 - 1) * g, rel=0.05)


@pytest.mark.parametrize("g", [0.0, 0.75])
def test_shares_integrate_linear_exactly_and_smooth_profiles_at_second_order(g):
    errs = []
    for n in (20, 40, 80):
        z, share = layer_positions(n, WB, g)
        assert np.sum(share * WB * (3.0 + 2.0 * z)) == pytest.approx(3.0 * WB, rel=1e-13)
        exact = 2 * (WB / 2) ** 5 / 5  # integral of z^4 over the width
        errs.append(abs(np.sum(share * WB * z**4) - exact) / exact)
    assert errs[1] < errs[0] / 3.5 and errs[2] < errs[1] / 3.5  # error ~ 1/n^2


def test_patch_areas_and_worn_volume_on_a_graded_grid():
    grid = BearingGrid(n_layers=30, n_points=64, radius=8e-3, width=WB, axial_grading=0.75)
    assert grid.point_area.sum() == pytest.approx(2 * math.pi * 8e-3 * WB, rel=1e-13)
    # a wear band linear in z: the trapezoid volume is exact on any spacing
    h = np.repeat((1e-6 * (1 + grid.z / WB))[:, None], 64, axis=1)
    assert worn_volume(h, grid) == pytest.approx(2 * math.pi * 8e-3 * WB * 1e-6, rel=1e-12)
    # the simulator's shares and patch areas are the same as the grid's
    p = replace_nested(
        BASE, **{"joint.n_layers": 30, "joint.n_points": 64, "joint.axial_grading": 0.75}
    )
    np.testing.assert_allclose(_layers(p)[0], grid.z, atol=0)
    np.testing.assert_allclose(point_area(p), grid.point_area, rtol=1e-12)
    assert BearingGrid.from_params(p) == grid


def test_graded_map_round_trips_through_the_dataset_and_the_resampler():
    p = replace_nested(
        BASE, **{"joint.n_layers": 24, "joint.n_points": 90, "joint.axial_grading": 0.75}
    )
    grid = BearingGrid.from_params(p)
    th = np.radians(grid.theta_deg)
    h = 1e-6 * (2 + np.cos(th)[None, :]) * (1 + (grid.z / WB)[:, None] ** 2)
    ds = wear_map_dataset(h[None], np.array([1e5]), grid)
    zc = ds["z"].values
    assert ds.attrs["axial_grading"] == 0.75
    np.testing.assert_allclose(zc, grid.z[::-1], atol=0)  # ascending, the graded positions
    np.testing.assert_allclose(wear_depth_on_grid(ds["wear_depth"], p), h, rtol=1e-12, atol=1e-18)
    # onto an equally spaced grid: linear interpolation between the graded layers
    q = replace_nested(p, **{"joint.axial_grading": 0.0})
    back = wear_depth_on_grid(ds["wear_depth"], q)
    zq = _layers(q)[0]
    want = 1e-6 * (2 + np.cos(th)[None, :]) * (1 + (zq / WB)[:, None] ** 2)
    np.testing.assert_allclose(back, want, rtol=2e-3)


@pytest.mark.parametrize("bad", [-0.1, 1.0, 1.5, float("nan")])
def test_grading_outside_zero_one_is_refused_naming_it(bad):
    with pytest.raises(ParameterError, match="axial_grading"):
        replace_nested(BASE, **{"joint.axial_grading": bad})
    with pytest.raises(ParameterError, match="axial_grading"):
        BearingGrid(axial_grading=bad)
