"""Accuracy of the 2D subset-DIC engine against synthetic speckle with exact ground truth."""

from __future__ import annotations

import math

import numpy as np
import pytest

from jointwear.datasets import speckle as sp
from jointwear.dic import SubsetCorrelator, correlate


def _errors(ds, pair):
    X, Y = np.meshgrid(ds.x.values, ds.y.values)
    tu, tv = pair.truth(X, Y)
    return ds.u.values - tu, ds.v.values - tv


@pytest.mark.parametrize(("interpolation", "speckle_size"), [("quintic", 5.0), ("cubic", 7.0)])
def test_subpixel_shift_systematic_error_below_1e3(interpolation, speckle_size):
    # noise-free 8-bit speckle; the S-shaped interpolation bias must stay below 0.001 px
    params = sp.SpeckleParams(speckle_size=speckle_size)
    worst = 0.0
    for s in np.arange(0.0, 1.0001, 0.1):
        pair = sp.speckle_pair((112, 112), sp.RigidField((s, 1.0 - s)), params=params, seed=7)
        ds = correlate(
            pair.reference, pair.deformed, subset_size=21, step=6, interpolation=interpolation
        )
        eu, ev = _errors(ds, pair)
        assert (ds.flag.values == 0).mean() > 0.9
        worst = max(worst, abs(np.nanmean(eu)), abs(np.nanmean(ev)))
    assert worst <= 0.001


def test_cubic_bias_is_larger_on_sharp_speckle_than_quintic():
    # the reason quintic is the default: a 0.3 px shift of 5-px speckles
    pair = sp.speckle_pair((112, 112), sp.RigidField((0.3, 0.0)), seed=7)
    bias = {}
    for interp in ("cubic", "quintic"):
        ds = correlate(pair.reference, pair.deformed, subset_size=21, step=6, interpolation=interp)
        bias[interp] = abs(np.nanmean(_errors(ds, pair)[0]))
    assert bias["quintic"] < 0.5 * bias["cubic"]


def test_brightness_and_contrast_change_cost_nothing():
    field = sp.RigidField((0.35, -0.6))
    plain = sp.speckle_pair((112, 112), field, seed=3)
    lit = sp.speckle_pair((112, 112), field, seed=3, gain=0.6, offset=40.0)
    assert abs(float(lit.deformed.mean()) - float(plain.deformed.mean())) > 5
    out = []
    for pair in (plain, lit):
        ds = correlate(pair.reference, pair.deformed, subset_size=21, step=8)
        eu, ev = _errors(ds, pair)
        assert (ds.flag.values == 0).all()
        out.append(np.sqrt(np.mean(eu**2 + ev**2)))
    # rms error with offset/gain differs only by the requantisation of the 8-bit image
    assert out[1] < 0.003
    assert abs(out[1] - out[0]) < 0.002


def test_noise_error_matches_the_theoretical_floor():
    sigma = 2.0  # grey levels
    field = sp.RigidField((0.3, 0.6))
    noisy = sp.speckle_pair((256, 256), field, params=sp.SpeckleParams(noise_std=sigma), seed=11)
    clean = sp.speckle_pair((256, 256), field, seed=11)  # same pattern, no noise
    half = 10
    ds = correlate(noisy.reference, noisy.deformed, subset_size=2 * half + 1, step=22)
    assert (ds.flag.values == 0).all()
    eu, ev = _errors(ds, noisy)
    # floor: sqrt(2) sigma / sqrt(sum of squared gradients over the subset), per subset; the
    # 8-bit rounding adds 1/12 grey level^2 of variance
    gy, gx = np.gradient(clean.reference.astype(float))
    s_eff = math.sqrt(sigma**2 + 1.0 / 12.0)
    fu, fv = [], []
    for y in ds.y.values.astype(int):
        for x in ds.x.values.astype(int):
            win = np.s_[y - half : y + half + 1, x - half : x + half + 1]
            fu.append(math.sqrt(2) * s_eff / math.sqrt(np.sum(gx[win] ** 2)))
            fv.append(math.sqrt(2) * s_eff / math.sqrt(np.sum(gy[win] ** 2)))
    floor_u = math.sqrt(np.mean(np.square(fu)))
    floor_v = math.sqrt(np.mean(np.square(fv)))
    std_u = float(np.std(eu))
    std_v = float(np.std(ev))
    assert 0.7 * floor_u < std_u < 1.3 * floor_u
    assert 0.7 * floor_v < std_v < 1.3 * floor_v
    # the per-point standard uncertainty estimated from the match residual agrees
    pred_u = math.sqrt(np.mean(ds.u_u.values**2))
    pred_v = math.sqrt(np.mean(ds.v_u.values**2))
    assert 0.75 * std_u < pred_u < 1.3 * std_u
    assert 0.75 * std_v < pred_v < 1.3 * std_v
    assert ds.u.attrs["ancillary_variables"] == "zncc flag u_u"


def test_affine_strain_and_rotation_recovered():
    field = sp.AffineField.from_strain(
        exx=0.01, eyy=-0.005, exy=0.002, rotation_deg=2.0, translation=(1.3, -0.7), center=(64, 64)
    )
    pair = sp.speckle_pair((128, 128), field, seed=3)
    ds = correlate(pair.reference, pair.deformed, subset_size=25, step=8)
    assert (ds.flag.values == 0).mean() > 0.95
    eu, ev = _errors(ds, pair)
    assert np.sqrt(np.nanmean(eu**2 + ev**2)) < 0.005
    G = np.asarray(field.gradient_matrix)
    for name, truth in (
        ("du_dx", G[0, 0]),
        ("du_dy", G[0, 1]),
        ("dv_dx", G[1, 0]),
        ("dv_dy", G[1, 1]),
    ):
        assert abs(np.nanmedian(ds[name].values) - truth) < 2e-4, name


def test_fifteen_degree_rotation_recovered_by_propagation():
    centre = (79.5, 79.5)
    pair = sp.speckle_pair((160, 160), sp.rotation(15.0, centre), seed=2)
    ds = correlate(pair.reference, pair.deformed, subset_size=25, step=8, search_radius=30)
    # every point whose deformed subset stays inside the image must be found
    X, Y = np.meshgrid(ds.x.values, ds.y.values)
    tu, tv = pair.truth(X, Y)
    reach = 12 * math.sqrt(2) + 4 + 1  # rotated subset corners + border margin
    inside = (X + tu > reach) & (X + tu < 159 - reach) & (Y + tv > reach) & (Y + tv < 159 - reach)
    ok = ds.flag.values == 0
    assert ok[inside].all()
    eu, ev = _errors(ds, pair)
    assert np.nanmax(np.abs(eu[ok])) < 0.02 and np.nanmax(np.abs(ev[ok])) < 0.02
    th = math.radians(15.0)
    assert abs(np.nanmedian(ds.du_dy.values) + math.sin(th)) < 1e-3
    assert abs(np.nanmedian(ds.dv_dx.values) - math.sin(th)) < 1e-3
    # points that fail are flagged, never dropped
    assert ds.u.size == X.size
    assert set(np.unique(ds.flag.values[~ok])) <= {1, 2, 3}


def test_quadratic_shape_function_fits_a_curved_field_better():
    pair = sp.speckle_pair((128, 128), sp.SinusoidalField((2.0, 1.0), 120.0), seed=4)
    rms = {}
    for shape in ("affine", "quadratic"):
        ds = correlate(pair.reference, pair.deformed, subset_size=31, step=8, shape=shape)
        eu, ev = _errors(ds, pair)
        rms[shape] = np.sqrt(np.nanmean(eu**2 + ev**2))
    assert rms["quadratic"] < 0.3 * rms["affine"]
    assert rms["quadratic"] < 0.02


def test_points_initial_guess_and_reused_reference():
    field = sp.RigidField((4.4, -2.2))
    pair = sp.speckle_pair((96, 96), field, seed=5)
    pts = np.array([[30.0, 30.0], [48.5, 47.25], [60.0, 40.0]])
    corr = SubsetCorrelator(pair.reference, points=pts, subset_size=21)
    ds = corr.correlate(pair.deformed, initial_guess=np.array([4.0, -2.0]))
    assert ds.u.dims == ("point",) and list(ds.x.values) == list(pts[:, 0])
    np.testing.assert_allclose(ds.u.values, 4.4, atol=0.003)
    np.testing.assert_allclose(ds.v.values, -2.2, atol=0.003)
    # the same prepared reference against another image, with affine guesses (N, 6)
    pair2 = sp.speckle_pair((96, 96), sp.RigidField((-1.3, 0.8)), seed=5)
    guess = np.tile([-1.0, 0.0, 0.0, 1.0, 0.0, 0.0], (3, 1))
    ds2 = corr.correlate(pair2.deformed, initial_guess=guess)
    np.testing.assert_allclose(ds2.u.values, -1.3, atol=0.003)
    np.testing.assert_allclose(ds2.v.values, 0.8, atol=0.003)
    assert (ds2.iterations.values >= 1).all() and (ds2.converged.values == 1).all()


def test_large_translation_found_from_given_seed_points_only():
    # 30 px away: outside a 10-px search window around the reference position, found when
    # the seed search is centred well (seed point) and the window is wide enough
    field = sp.RigidField((30.4, -12.6))
    pair = sp.speckle_pair((128, 128), field, seed=6)
    narrow = correlate(pair.reference, pair.deformed, subset_size=21, step=10, search_radius=10)
    assert (narrow.flag.values == 0).mean() < 0.2
    wide = correlate(
        pair.reference,
        pair.deformed,
        subset_size=21,
        step=10,
        search_radius=40,
        seed_points=np.array([[50.0, 60.0]]),
    )
    ok = wide.flag.values == 0
    X, Y = np.meshgrid(wide.x.values, wide.y.values)
    margin = 10 + 4  # half subset + border
    inside = (X + 30.4 >= margin) & (X + 30.4 <= 127 - margin)
    inside &= (Y - 12.6 >= margin) & (Y - 12.6 <= 127 - margin)
    assert inside.sum() > 20 and ok[inside].all()
    assert (wide.flag.values[~inside] != 0).all()  # carried out of the image: flagged
    eu, ev = _errors(wide, pair)
    assert np.max(np.abs(eu[ok])) < 0.01 and np.max(np.abs(ev[ok])) < 0.01


def test_guess_rows_with_nan_are_filled_from_neighbours():
    pair = sp.speckle_pair((96, 96), sp.RigidField((1.7, 0.9)), seed=8)
    corr = SubsetCorrelator(pair.reference, subset_size=21, step=10)
    guess = np.tile([1.5, 1.0], (corr.n_points, 1))
    guess[::3] = np.nan
    ds = corr.correlate(pair.deformed, initial_guess=guess)
    assert (ds.flag.values == 0).all()
    np.testing.assert_allclose(ds.u.values, 1.7, atol=0.005)
