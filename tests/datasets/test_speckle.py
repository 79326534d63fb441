"""The analytic speckle generator: exact ground truth, parameters, determinism."""

from __future__ import annotations

import math

import numpy as np
import pytest

from jointwear.datasets import speckle as sp
from jointwear.errors import ParameterError

FLOAT = sp.SpeckleParams(bit_depth=0)


def test_integer_translation_is_an_exact_raster_shift():
    pair = sp.speckle_pair((64, 80), sp.RigidField((3.0, 2.0)), params=FLOAT, seed=3)
    # deformed(x + 3, y + 2) == reference(x, y): no interpolation anywhere
    np.testing.assert_allclose(pair.deformed[2:, 3:], pair.reference[:-2, :-3], atol=1e-12)


def test_quarter_turn_is_an_exact_rot90():
    n = 48
    c = (n - 1) / 2
    pair = sp.speckle_pair((n, n), sp.rotation(90.0, (c, c)), params=FLOAT, seed=4)
    # +90 degrees from +x towards +y (y down): D[i, j] = R[n - 1 - j, i] = rot90(R, -1)
    np.testing.assert_allclose(pair.deformed, np.rot90(pair.reference, -1), atol=1e-9)


def test_subpixel_positions_are_evaluated_from_the_blob_formula():
    # the renderer evaluates sum_k a_k exp(-|X - c_k|^2 / (2 s^2)) at any (sub-pixel) position:
    # compare with a brute-force numpy evaluation at shifted, rotated coordinates
    from jointwear.datasets.speckle import _render, _scatter_blobs

    params = sp.SpeckleParams(speckle_size=5.0, density=0.5)
    blobs = _scatter_blobs((-15.0, 60.0, -15.0, 60.0), params, np.random.default_rng(2))
    x, y = np.meshgrid(np.arange(40.0), np.arange(40.0))
    field = sp.AffineField.from_strain(exx=0.01, rotation_deg=3.0, translation=(0.37, -0.21))
    X, Y = field.inverse(x, y)
    F = np.zeros((40, 40, 4))
    G = np.eye(2) + np.asarray(field.gradient_matrix)
    F[..., 0], F[..., 1], F[..., 2], F[..., 3] = G[0, 0], G[0, 1], G[1, 0], G[1, 1]
    got = _render(blobs, X, Y, F, params)
    s2 = (params.speckle_size / 4) ** 2
    d2 = (X[..., None] - blobs.x) ** 2 + (Y[..., None] - blobs.y) ** 2
    # the blob keeps its reference shape (F maps it), scaled by |det F| / |det F| = 1
    want = np.sum(blobs.amp * np.exp(-0.5 * d2 / s2), axis=-1)
    np.testing.assert_allclose(got, want, atol=1e-9)


@pytest.mark.parametrize(
    "field",
    [
        sp.AffineField.from_strain(exx=0.02, eyy=-0.01, exy=0.005, rotation_deg=7, center=(30, 20)),
        sp.SinusoidalField((3.0, -2.0), 60.0, direction_deg=30.0, phase=0.4),
        sp.rotation(-40.0, (12.5, 7.0)),
    ],
)
def test_inverse_mapping_round_trip(field):
    rng = np.random.default_rng(0)
    X = rng.uniform(0, 100, 50)
    Y = rng.uniform(0, 100, 50)
    x, y = field.forward(X, Y)
    Xb, Yb = field.inverse(x, y)
    np.testing.assert_allclose(Xb, X, atol=1e-9)
    np.testing.assert_allclose(Yb, Y, atol=1e-9)
    # gradient against central differences
    h = 1e-5
    ux, uy, vx, vy = field.gradient(X, Y)
    u1, v1 = field.displacement(X + h, Y)
    u0, v0 = field.displacement(X - h, Y)
    np.testing.assert_allclose(ux, (u1 - u0) / (2 * h), atol=1e-7)
    np.testing.assert_allclose(vx, (v1 - v0) / (2 * h), atol=1e-7)
    u1, v1 = field.displacement(X, Y + h)
    u0, v0 = field.displacement(X, Y - h)
    np.testing.assert_allclose(uy, (u1 - u0) / (2 * h), atol=1e-7)
    np.testing.assert_allclose(vy, (v1 - v0) / (2 * h), atol=1e-7)


def test_blur_is_a_gaussian_convolution_of_the_blob_sum():
    from scipy import ndimage

    from jointwear.datasets.speckle import _render, _scatter_blobs

    params = sp.SpeckleParams(speckle_size=8.0, density=0.3)
    blurred = sp.SpeckleParams(speckle_size=8.0, density=0.3, blur_std=1.5)
    rng = np.random.default_rng(1)
    blobs = _scatter_blobs((-20.0, 100.0, -20.0, 100.0), params, rng)
    x, y = np.meshgrid(np.arange(80.0), np.arange(80.0))
    F = np.zeros((80, 80, 4))
    F[..., 0] = F[..., 3] = 1.0
    sharp = _render(blobs, x, y, F, params)
    soft = _render(blobs, x, y, F, blurred)
    ref = ndimage.gaussian_filter(sharp, 1.5, mode="nearest", truncate=6.0)
    inner = np.s_[15:-15, 15:-15]
    assert np.max(np.abs(soft[inner] - ref[inner])) < 2e-3 * np.max(sharp)
    assert soft.std() < sharp.std()


def test_bit_depth_noise_and_seed():
    base = sp.speckle_image((64, 64), params=sp.SpeckleParams(bit_depth=12), seed=9)
    assert base.dtype == np.uint16 and base.max() <= 4095 and base.max() > 2000
    img8 = sp.speckle_image((64, 64), seed=9)
    assert img8.dtype == np.uint8
    np.testing.assert_array_equal(img8, sp.speckle_image((64, 64), seed=9))
    assert not np.array_equal(img8, sp.speckle_image((64, 64), seed=10))
    clean = sp.speckle_image((128, 128), params=sp.SpeckleParams(bit_depth=0), seed=9)
    noisy = sp.speckle_image(
        (128, 128), params=sp.SpeckleParams(bit_depth=0, noise_std=0.05), seed=9
    )
    assert math.isclose(float(np.std(noisy - clean)), 0.05, rel_tol=0.05)
    # contrast: the grey-level span scales with it
    lo = sp.speckle_image((64, 64), params=sp.SpeckleParams(bit_depth=0, contrast=0.4), seed=9)
    hi = sp.speckle_image((64, 64), params=sp.SpeckleParams(bit_depth=0, contrast=0.8), seed=9)
    np.testing.assert_allclose(hi - 0.5, 2 * (lo - 0.5 + 0.2) - 0.4, atol=1e-12)


def test_truth_dataset_matches_the_field():
    field = sp.SinusoidalField((1.5, 0.5), 40.0)
    ds = sp.truth_dataset(field, (32, 48), step=4)
    assert ds.u.dims == ("y", "x") and ds.sizes == {"y": 8, "x": 12}
    u, v = field.displacement(*np.meshgrid(ds.x.values, ds.y.values))
    np.testing.assert_allclose(ds.u.values, u)
    np.testing.assert_allclose(ds.v.values, v)


def test_bad_parameters_are_refused():
    with pytest.raises(ParameterError, match="speckle_size=0.5 is out of range"):
        sp.SpeckleParams(speckle_size=0.5)
    with pytest.raises(ParameterError, match="must stay below 0.9"):
        sp.SinusoidalField((20.0, 0.0), 50.0)
    with pytest.raises(ParameterError, match=r"image shape \(4, 64\)"):
        sp.speckle_image((4, 64))
    with pytest.raises(ParameterError, match="singular"):
        sp.AffineField(((-1.0, 0.0), (0.0, 0.0)))
