"""Matches flagged by their own uncertainty: a point whose u is far above its image's median
is ``uncertainty_outlier``, so filtering on ``flag`` no longer keeps points that are off by
many times the field's typical error."""

from __future__ import annotations

import numpy as np
import pytest

from jointwear.datasets import speckle as sp
from jointwear.datasets.speckle import SpeckleParams
from jointwear.dic import CorrelationParams, correlate
from jointwear.dic.icgn._flags import (
    FLAG_U_OUTLIER,
    U_OUTLIER_FLOOR_PX,
    flag_uncertainty_outliers,
)
from jointwear.errors import ParameterError

SHIFT = (0.35, -0.2)


@pytest.fixture(scope="module")
def faded():
    """A known shift of a speckle whose right quarter fades to a faint texture (a specimen's
    dark surroundings), 1.5 grey levels of noise: the faint subsets match, but imprecisely."""
    shape = (160, 400)
    prm = SpeckleParams(noise_std=0.0, bit_depth=16)
    a, b = sp.speckle_sequence(shape, [None, sp.RigidField(SHIFT)], params=prm, seed=4)
    contrast = np.clip(1 - (np.arange(shape[1]) - 280) / 100, 0.04, 1)[None, :]
    rng = np.random.default_rng(1)
    scale = 200 / a.max()
    A, B = (np.round(contrast * f * scale + 20 + rng.normal(0, 1.5, shape)) for f in (a, b))
    return A, B


def _share_off(ds, limit=0.05):
    ok = ds.flag.values == 0
    err = np.hypot(ds.u.values - SHIFT[0], ds.v.values - SHIFT[1])
    return (ok & (err > limit)).sum() / ok.sum()


def test_points_off_by_many_times_the_typical_error_are_flagged(faded):
    A, B = faded
    before = correlate(A, B, subset_size=21, step=6, u_outlier_factor=0)
    after = correlate(A, B, subset_size=21, step=6)  # the default factor
    assert after.attrs["dic_u_outlier_factor"] == CorrelationParams.u_outlier_factor
    assert _share_off(before) > 0.01  # without the test: several % of ok points > 0.05 px off
    assert _share_off(after) <= 0.002
    flagged = after.flag.values == FLAG_U_OUTLIER
    assert "uncertainty_outlier" in after.flag.attrs["flag_meanings"].split()
    assert FLAG_U_OUTLIER in after.flag.attrs["flag_values"]
    assert np.isnan(after.u.values[flagged]).all()
    # the rule, recomputed: larger component above 3 times the median over the ok points
    ok0 = before.flag.values == 0
    u = np.fmax(before.u_u.values, before.v_u.values)
    floor = U_OUTLIER_FLOOR_PX
    np.testing.assert_array_equal(flagged, ok0 & (u > max(3 * np.median(u[ok0]), floor)))
    # the well-textured part keeps its points: only the faint texture is flagged (its faintest
    # part; where u is still below U_OUTLIER_FLOOR_PX the matches are kept, and are right)
    x = np.broadcast_to(after.x.values, flagged.shape)
    assert flagged[x < 260].mean() <= 0.02 and flagged[x > 330].mean() > 0.3


def test_the_rule_per_image_and_its_limits():
    flag = np.zeros((2, 12), np.int8)
    sigma = np.full((2, 12, 2), 0.01)
    sigma[0, 3] = [0.01, 0.05]  # 5x the median in v
    sigma[1, 4] = [0.029, 0.01]  # below 3x
    tiny = np.full((12, 2), 1e-5)
    tiny[2] = 1e-3  # 100x the median, but a noise-free image's 0.001 pixel: no outlier
    assert not flag_uncertainty_outliers(flag[0], tiny, 3.0).any()
    flag[1, 0] = 2  # a flagged point stays as it was
    out = flag_uncertainty_outliers(flag, sigma, 3.0)
    assert np.flatnonzero(out[0]).tolist() == [3] and out[0, 3] == FLAG_U_OUTLIER
    assert out[1].tolist() == flag[1].tolist()
    assert (flag_uncertainty_outliers(flag, sigma, 0.0) == flag).all()  # 0: no test
    assert (flag_uncertainty_outliers(flag[:, :5], sigma[:, :5], 3.0) == flag[:, :5]).all()
    with pytest.raises(ParameterError, match="u_outlier_factor"):
        CorrelationParams(u_outlier_factor=0.5)


def test_the_full_field_flags_them_too(faded):
    from jointwear.dic import measure_field

    A, B = faded
    ds = measure_field([A, B], subset_size=21, step=12, strain_window=0)
    meanings = ds.flag.attrs["flag_meanings"].split()
    assert meanings[FLAG_U_OUTLIER] == "uncertainty_outlier"
    flagged = ds.flag.values[1] == FLAG_U_OUTLIER
    # the faintest texture (u above U_OUTLIER_FLOOR_PX) is flagged, none of the well-textured part
    assert flagged[ds.x.values > 330].mean() > 0.2 and not flagged[ds.x.values < 260].any()
    ok = ds.flag.values[1] == 0
    err = np.hypot(*(ds.displacement.values[1, ok] - SHIFT).T)
    assert (err > 0.05).mean() <= 0.002
    assert ds.attrs["dic_u_outlier_factor"] == 3.0
