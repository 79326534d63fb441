"""B-spline prefilter and interpolation kernels of the 2D engine."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

from jointwear.dic.icgn import _interp


@pytest.mark.parametrize(("interpolation", "order"), [("cubic", 3), ("quintic", 5)])
def test_prefilter_matches_scipy_mirror_coefficients(interpolation, order):
    img = np.random.default_rng(0).random((37, 52)) * 255
    spl = _interp.prefilter(img, interpolation)
    want = np.pad(ndimage.spline_filter(img, order=order, mode="mirror"), _interp.PAD, "reflect")
    np.testing.assert_allclose(spl.coef, want, atol=1e-9)


@pytest.mark.parametrize(("interpolation", "order"), [("cubic", 3), ("quintic", 5)])
def test_interpolant_passes_through_pixels_and_reproduces_cubics(interpolation, order):
    y, x = np.mgrid[0:60, 0:64].astype(float)
    # a cubic polynomial is reproduced exactly by cubic and quintic B-splines (away from the
    # mirrored border, whose influence decays geometrically)
    poly = 0.001 * x**3 - 0.02 * x * y + 0.5 * y**2 + 3 * x + 7
    spl = _interp.prefilter(poly, interpolation)
    w = [np.empty(6) for _ in range(4)]
    rng = np.random.default_rng(1)
    for _ in range(20):
        px, py = rng.uniform(24, 36, 2)
        got = _interp.interp_value(spl.coef, order, px, py, w[0], w[1])
        want = 0.001 * px**3 - 0.02 * px * py + 0.5 * py**2 + 3 * px + 7
        assert abs(got - want) < 1e-5
        f, fx, fy = _interp.interp_value_grad(spl.coef, order, px, py, *w)
        assert abs(f - want) < 1e-5
        assert abs(fx - (0.003 * px**2 - 0.02 * py + 3)) < 1e-5
        assert abs(fy - (-0.02 * px + py)) < 1e-5
    img = np.random.default_rng(2).random((30, 30))
    spl = _interp.prefilter(img, interpolation)
    for py, px in [(0, 0), (29, 29), (5, 17)]:
        assert abs(_interp.interp_value(spl.coef, order, px, py, w[0], w[1]) - img[py, px]) < 1e-10


@pytest.mark.parametrize(("interpolation", "order"), [("cubic", 3), ("quintic", 5)])
def test_node_gradients_are_central_differences_or_the_interpolant_derivatives(
    interpolation, order
):
    img = np.random.default_rng(3).random((25, 31)) * 100
    central = _interp.prefilter(img, interpolation)
    gy, gx = np.gradient(img)
    np.testing.assert_allclose(central.gx[:, 1:-1], gx[:, 1:-1], atol=1e-12)
    np.testing.assert_allclose(central.gy[1:-1], gy[1:-1], atol=1e-12)
    assert (central.gx[:, [0, -1]] == 0).all()  # mirror boundary
    spl = _interp.prefilter(img, interpolation, gradient="spline")
    w = [np.empty(6) for _ in range(4)]
    for py, px in [(0, 0), (12, 17), (24, 30), (3, 29)]:
        _, fx, fy = _interp.interp_value_grad(spl.coef, order, float(px), float(py), *w)
        assert abs(spl.gx[py, px] - fx) < 1e-9
        assert abs(spl.gy[py, px] - fy) < 1e-9
