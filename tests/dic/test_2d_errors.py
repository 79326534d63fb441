"""Bad input to the 2D engine: clear errors, or flagged points that are kept in the output."""

from __future__ import annotations

import numpy as np
import pytest

from jointwear import conventions
from jointwear.datasets import speckle as sp
from jointwear.dic import SubsetCorrelator, correlate
from jointwear.errors import BadInputError, ParameterError

FLAG = {
    name: i
    for i, name in enumerate(
        "ok not_converged low_correlation subset_outside_image no_texture invalid_pixels "
        "not_reached diverged".split()
    )
}


@pytest.fixture(scope="module")
def pair():
    return sp.speckle_pair((96, 96), sp.RigidField((0.4, -0.3)), seed=1)


def test_images_of_different_size_are_refused(pair):
    with pytest.raises(BadInputError, match=r"size 95x96 .* differs from the reference 96x96"):
        correlate(pair.reference, pair.deformed[:, :95])


def test_images_of_different_dtype_are_refused(pair):
    with pytest.raises(BadInputError, match="pixel type uint16 differs from the reference's uint8"):
        correlate(pair.reference, pair.deformed.astype(np.uint16))


@pytest.mark.parametrize("size", [20, 4, 31.0])
def test_even_or_invalid_subset_size_is_refused(pair, size):
    with pytest.raises(ParameterError, match="expected an odd integer >= 7"):
        correlate(pair.reference, pair.deformed, subset_size=size)


def test_colour_and_non_2d_images_are_refused(pair):
    rgb = np.repeat(pair.reference[..., None], 3, axis=2)
    with pytest.raises(BadInputError, match="single-channel"):
        correlate(rgb, rgb)
    with pytest.raises(BadInputError, match="expected a 2D image"):
        correlate(pair.reference.ravel(), pair.deformed.ravel())


def test_bad_options_are_refused(pair):
    with pytest.raises(ParameterError, match="shape='cubic'"):
        correlate(pair.reference, pair.deformed, shape="cubic")
    with pytest.raises(ParameterError, match="roi=.* must satisfy"):
        correlate(pair.reference, pair.deformed, roi=(10, 10, 200, 50))
    with pytest.raises(BadInputError, match=r"initial_guess: expected shape \(2, 2\)"):
        correlate(
            pair.reference,
            pair.deformed,
            points=[[40, 40], [50, 50]],
            initial_guess=np.zeros((3, 2)),
        )
    with pytest.raises(ParameterError, match="unknown correlation option"):
        SubsetCorrelator(pair.reference, subsetsize=21)


def test_subset_leaving_the_image_is_flagged_not_dropped(pair):
    pts = np.array([[48.0, 48.0], [5.0, 48.0], [48.0, 93.0], [-3.0, 10.0]])
    ds = correlate(pair.reference, pair.deformed, points=pts, subset_size=21)
    assert ds.sizes["point"] == 4
    assert ds.flag.values.tolist() == [0, 3, 3, 3]
    assert np.isfinite(ds.u.values[0]) and np.isnan(ds.u.values[1:]).all()


def test_blank_region_is_flagged(pair):
    ref = pair.reference.copy()
    dfm = pair.deformed.copy()
    ref[:, :45] = 100
    dfm[:, :45] = 100
    ds = correlate(ref, dfm, subset_size=21, step=8)
    X = np.broadcast_to(ds.x.values, ds.u.shape)
    blank = X + 10 < 45
    assert blank.any()
    assert (ds.flag.values[blank] == FLAG["no_texture"]).all()
    assert np.isnan(ds.u.values[blank]).all()
    textured = X - 10 > 47
    assert (ds.flag.values[textured] == 0).all()


def test_nan_pixels_are_flagged(pair):
    ref = pair.reference.astype(float)
    dfm = pair.deformed.astype(float)
    dfm[60:64, 60:64] = np.nan
    ref[20:22, 70:72] = np.nan
    ds = correlate(ref, dfm, subset_size=21, step=8)
    X, Y = np.meshgrid(ds.x.values, ds.y.values)
    near_def = (np.abs(X - 61.5) < 12) & (np.abs(Y - 61.5) < 12)
    near_ref = (np.abs(X - 70.5) < 12) & (np.abs(Y - 20.5) < 12)
    flags = ds.flag.values
    assert (flags[near_ref] == FLAG["invalid_pixels"]).all()
    assert (flags[near_def & ~near_ref] == FLAG["invalid_pixels"]).all()
    far = ~(np.abs(X - 61.5) < 17) & ~(np.abs(Y - 61.5) < 17) & ~near_ref
    assert (flags[far] == 0).all()
    assert np.isnan(ds.u.values[flags != 0]).all()


def test_output_follows_the_contract(pair):
    ds = correlate(pair.reference, pair.deformed, subset_size=21, step=10)
    conventions.validate(ds)
    assert ds.u.dims == ("y", "x") and ds.u.attrs["units"] == "pixel"
    meanings = ds.flag.attrs["flag_meanings"].split()
    assert len(meanings) == len(ds.flag.attrs["flag_values"]) and meanings[0] == "ok"
    assert float(ds.zncc.min()) > 0.99
