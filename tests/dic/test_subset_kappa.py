"""The noise factor kappa: computing the spline's node derivatives once for a dense grid (over
the box the subsets cover, subset sums from summed-area tables) gives the numbers of computing
them subset by subset (to rounding), and
both agree with a direct NumPy evaluation of the definition."""

from __future__ import annotations

import numpy as np
import pytest

from jointwear.datasets import speckle as sp
from jointwear.dic.icgn._interp import PAD, node_filters, prefilter
from jointwear.dic.icgn._reference import subset_kappa


@pytest.fixture(scope="module")
def image():
    pair = sp.speckle_pair(
        shape=(90, 120),
        field=sp.RigidField((0.3, 0.2), 0.0, (60, 45)),
        params=sp.SpeckleParams(speckle_size=3.5, noise_std=1.0),
        seed=5,
    )
    return pair.reference


@pytest.mark.parametrize("interpolation", ["cubic", "quintic"])
@pytest.mark.parametrize(
    "centres",
    [
        # a dense grid over part of the image (the box path), reaching the image's edges
        np.array([[x, y] for y in np.arange(0.0, 60.0, 3.0) for x in np.arange(50.0, 119.0, 3.0)]),
        # a dense grid with a NaN centre and off-grid positions
        np.array(
            [[np.nan, 3.0]]
            + [[x + 0.4, y - 0.3] for y in range(20, 70, 2) for x in range(20, 70, 2)]
        ),
    ],
    ids=["edge-grid", "nan-offgrid"],
)
def test_dense_grid_equals_subset_by_subset(image, interpolation, centres):
    r = prefilter(image, interpolation, gradients=True, gradient="central")
    half = 8
    together = np.full(len(centres), np.nan)
    subset_kappa(r.coef, r.order, r.gx, r.gy, centres, half, together)
    one_by_one = np.full(len(centres), np.nan)
    for i, c in enumerate(centres):  # one interior centre: its nodes one by one
        out = np.empty(1)
        subset_kappa(r.coef, r.order, r.gx, r.gy, c[None, :], half, out)
        one_by_one[i] = out[0]
    assert len(centres) * (2 * half + 1) ** 2 > (70 * 60)  # the grid took the box path
    np.testing.assert_allclose(together, one_by_one, rtol=1e-12)  # summed-area sums
    ok = np.isfinite(centres).all(axis=1)
    assert (together[~ok] == 1.0).all()
    assert ((together[ok] > 0.5) & (together[ok] < 1.0)).all()  # g_c under-estimates g_s


def _kappa_numpy(r, centre, half):
    """``sum |g_c|^2 / sum g_c . g_s`` over the subset, g_s from the B-spline coefficients by
    the separable node filters, written out with NumPy."""
    val, der = node_filters(r.order)
    k = val.size // 2
    h, w = r.gx.shape
    ic, jc = (int(round(v)) for v in centre)
    ys = np.arange(max(jc - half, 0), min(jc + half + 1, h))
    xs = np.arange(max(ic - half, 0), min(ic + half + 1, w))
    a = b = 0.0
    for y in ys:
        for x in xs:
            block = r.coef[y + PAD - k : y + PAD + k + 1, x + PAD - k : x + PAD + k + 1]
            sx = val @ block @ der  # d/dx: derivative filter along the row
            sy = der @ block @ val
            a += r.gx[y, x] ** 2 + r.gy[y, x] ** 2
            b += r.gx[y, x] * sx + r.gy[y, x] * sy
    return a / b


@pytest.mark.parametrize("interpolation", ["cubic", "quintic"])
def test_kappa_is_its_definition(image, interpolation):
    r = prefilter(image, interpolation, gradients=True, gradient="central")
    centres = np.array([[30.0, 30.0], [0.0, 0.0], [119.0, 60.2], [75.6, 44.4]])
    out = np.empty(len(centres))
    subset_kappa(r.coef, r.order, r.gx, r.gy, centres, 8, out)
    expected = [_kappa_numpy(r, c, 8) for c in centres]
    np.testing.assert_allclose(out, expected, rtol=1e-12)
