"""The tracking fast paths: region prefilter, preloaded reference subsets, frame prefetch."""

from __future__ import annotations

import threading

import numpy as np
import pytest
from scipy import ndimage

from jointwear.dic._api2d import CorrelationParams, SubsetCorrelator
from jointwear.dic.footage._video import open_frames, prefetch
from jointwear.dic.icgn import _interp


def _speckle(shape, seed=0):
    rng = np.random.default_rng(seed)
    return ndimage.gaussian_filter(rng.normal(size=shape), 1.3) * 500 + 120


@pytest.mark.parametrize("interpolation", ["cubic", "quintic"])
def test_region_prefilter_equals_the_whole_image_prefilter_where_it_is_computed(interpolation):
    img = _speckle((180, 230))
    full = _interp.prefilter(img, interpolation, gradients=False)
    centres = np.array([[40.3, 30.0], [60.0, 52.7], [200.0, 170.0], [2.0, 120.0]])
    r = 9
    ws: dict = {}
    reg = _interp.prefilter_region(img.astype(np.float32), interpolation, centres, r, workspace=ws)
    P = _interp.PAD
    inside = np.zeros(full.coef.shape, bool)
    for x, y in np.rint(centres).astype(int):
        inside[max(y - r, 0) + P : y + r + P + 1, max(x - r, 0) + P : x + r + P + 1] = True
    scale = np.abs(full.coef).max()
    assert np.abs(reg.coef[inside] - full.coef[inside]).max() < 1e-6 * scale
    # far from every centre nothing is computed: NaN, never a stale or wrong value
    assert np.isnan(reg.coef[P + 100, P + 120])
    # the workspace is reused, and a second call does not leave the first call's values
    reg2 = _interp.prefilter_region(img, interpolation, centres[:1], r, workspace=ws)
    assert reg2.coef is ws["coef"]
    assert np.isnan(reg2.coef[P + 170, P + 200])


def test_region_prefilter_replaces_invalid_pixels_and_reports_them():
    img = _speckle((80, 80))
    img[10:14, 10:14] = np.nan
    reg = _interp.prefilter_region(img, "cubic", np.array([[40.0, 40.0]]), 30)
    assert not reg.valid[12, 12] and reg.valid[40, 40]
    assert np.isfinite(reg.coef[_interp.PAD + 40, _interp.PAD + 40])


@pytest.mark.parametrize("interpolation", ["cubic", "quintic"])
def test_preloaded_references_give_the_same_matches(interpolation):
    ref = _speckle((160, 160), seed=3)
    shift = (0.35, -0.6)  # (row, col)
    cur = ndimage.shift(ref, shift, order=5, mode="mirror")
    # sub-pixel centres as the right camera's tracker has them
    pts = np.mgrid[30:131:20, 30:131:20].reshape(2, -1).T[:, ::-1] + np.array([0.37, 0.81])
    params = CorrelationParams(subset_size=21, interpolation=interpolation, threads=1)
    plain = SubsetCorrelator(ref, points=pts, params=params)
    loaded = SubsetCorrelator(ref, points=pts, params=params)
    loaded.preload_references()
    guess = np.tile([-0.2, 0.0, 0.0, 0.9, 0.0, 0.0], (len(pts), 1))
    a = plain.match(cur, initial_guess=guess)
    b = loaded.match(cur, initial_guess=guess)
    assert b.ok.all()
    np.testing.assert_allclose(b.params, a.params, atol=1e-9)
    np.testing.assert_allclose(b.zncc, a.zncc, atol=1e-12)
    np.testing.assert_array_equal(b.iterations, a.iterations)
    # and the known shift is found (x = -0.6, y = +0.35)
    assert np.abs(b.params[:, 0] + 0.6).max() < 0.01
    assert np.abs(b.params[:, 6] - 0.35).max() < 0.01


def test_preload_refuses_the_quadratic_shape():
    c = SubsetCorrelator(_speckle((80, 80)), points=[[40.0, 40.0]], shape="quadratic")
    with pytest.raises(Exception, match="affine"):
        c.preload_references()


def test_prefetch_yields_everything_in_order_and_raises_where_the_source_fails():
    assert list(prefetch(iter(range(50)), depth=2)) == list(range(50))

    def broken():
        yield 1
        yield 2
        raise ValueError("frame 2 could not be decoded")

    got = []
    with pytest.raises(ValueError, match="frame 2"):
        for x in prefetch(broken()):
            got.append(x)
    assert got == [1, 2]


def test_prefetch_stops_its_thread_when_the_consumer_stops_early():
    closed = threading.Event()

    def endless():
        try:
            k = 0
            while True:
                yield k
                k += 1
        finally:
            closed.set()

    it = prefetch(endless(), depth=2)
    assert [next(it) for _ in range(3)] == [0, 1, 2]
    it.close()
    assert closed.wait(5.0)


def test_native_grey_frames_equal_the_float_frames(tmp_path):
    import cv2

    rng = np.random.default_rng(0)
    frames = [rng.integers(0, 256, (48, 64), dtype=np.uint8) for _ in range(4)]
    path = tmp_path / "grey.avi"
    w = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"GREY"), 50, (64, 48), False)
    for f in frames:
        w.write(f)
    w.release()
    src = open_frames(path)
    native = [img for _, _, img in src.frames(native=True)]
    floats = [img for _, _, img in src.frames()]
    assert all(n.dtype == np.uint8 and n.shape == (48, 64) for n in native)
    for n, f, want in zip(native, floats, frames, strict=True):
        np.testing.assert_array_equal(n, want)  # lossless grey: the written frames exactly
        assert f.dtype == np.float32
        np.testing.assert_array_equal(f, want.astype(np.float32))


def test_features_of_deep_images_are_scaled_not_clipped():
    from jointwear.dic.footage._track import _as_uint8

    img16 = (_speckle((64, 64)) * 40).clip(0, 65535).astype(np.uint16)  # ~12-bit range
    u8 = _as_uint8(img16)
    assert u8.dtype == np.uint8
    assert np.corrcoef(u8.ravel(), img16.ravel())[0, 1] > 0.99  # clipping would flatten it
    grey = np.arange(256, dtype=np.uint8).reshape(16, 16)
    assert _as_uint8(grey) is grey


def test_stereo_prediction_is_exact_for_points_moving_linearly_in_depth():
    # the right camera's start: left matches carried to the right image at depths
    # extrapolated from the two previous frames; exact when the depth changes linearly
    from jointwear.datasets.rig import RigConfig, VirtualRig
    from jointwear.dic.footage._track import _stereo_prediction

    cal = VirtualRig(RigConfig(width=640, height=512)).calibration
    rng = np.random.default_rng(4)
    X0 = np.column_stack([rng.uniform(0.1, 0.3, 30), rng.uniform(0.15, 0.3, 30), np.zeros(30)])
    v = np.array([2e-3, -1e-3, 1.5e-3])  # m per frame, with an out-of-plane part
    frames = [X0 + k * v for k in range(3)]
    uv_left = cal.left.project(frames[2])
    pred = _stereo_prediction(cal, uv_left, frames[:2])
    np.testing.assert_allclose(pred, cal.right.project(frames[2]), atol=1e-6)
    # unknown points stay unknown
    uv_left[3] = np.nan
    assert np.isnan(_stereo_prediction(cal, uv_left, frames[:2])[3]).all()


def test_region_prefilter_on_a_window_of_an_integer_frame_equals_the_cropped_float_one():
    rng = np.random.default_rng(5)
    frame = rng.integers(0, 256, (120, 160), dtype=np.uint8)
    x0, y0, w, h = 30, 20, 90, 80
    centres = np.array([[40.0, 30.0], [60.5, 47.2]])
    a = _interp.prefilter_region(frame[y0 : y0 + h, x0 : x0 + w].astype(np.float32), "cubic",
                                 centres, 12)  # fmt: skip
    b = _interp.prefilter_region(frame, "cubic", centres, 12, window=(x0, y0, w, h))
    np.testing.assert_array_equal(np.isnan(a.coef), np.isnan(b.coef))
    np.testing.assert_allclose(b.coef[~np.isnan(b.coef)], a.coef[~np.isnan(a.coef)], atol=1e-9)
    assert b.valid.shape == (h, w) and b.valid.all()
    with pytest.raises(ValueError, match="inside"):
        _interp.prefilter_region(frame, "cubic", centres, 12, window=(100, 20, 90, 80))
