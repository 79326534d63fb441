"""Outlier flags against known truths: a match that disagrees with its grid neighbours by far
more than its image's typical uncertainty is ``neighbour_outlier``, a match without neighbours
whose own u is far above the typical one is ``uncertainty_outlier``, so filtering on ``flag``
no longer keeps points that are off by many times the field's typical error, while a real
(smooth) deformation is not taken for outliers."""

from __future__ import annotations

import numpy as np
import pytest

from jointwear.datasets import speckle as sp
from jointwear.datasets.speckle import SpeckleParams
from jointwear.dic import CorrelationParams, correlate
from jointwear.dic.icgn._flags import (
    FLAG_NEIGHBOUR_OUTLIER,
    FLAG_U_OUTLIER,
    U_OUTLIER_FLOOR_PX,
    flag_uncertainty_outliers,
    neighbour_reach,
)
from jointwear.errors import ParameterError

SHIFT = (0.35, -0.2)
OFF = 0.05  # [pixel] a point further than this from the truth is "off"


def _faded(shape, fade_start, fade_length, seed=4):
    """A known shift of a speckle whose right part fades to a faint texture (a specimen's
    dark surroundings), 1.5 grey levels of noise: the faint subsets match, but imprecisely."""
    prm = SpeckleParams(noise_std=0.0, bit_depth=16)
    a, b = sp.speckle_sequence(shape, [None, sp.RigidField(SHIFT)], params=prm, seed=seed)
    contrast = np.clip(1 - (np.arange(shape[1]) - fade_start) / fade_length, 0.04, 1)[None, :]
    rng = np.random.default_rng(1)
    scale = 200 / a.max()
    return tuple(np.round(contrast * f * scale + 20 + rng.normal(0, 1.5, shape)) for f in (a, b))


@pytest.fixture(scope="module")
def faded():
    return _faded((200, 480), 400, 60)


def _error(ds):
    return np.hypot(ds.u.values - SHIFT[0], ds.v.values - SHIFT[1])


def test_off_points_are_flagged_and_good_ones_kept(faded):
    A, B = faded
    kw = dict(subset_size=21, step=10)
    before = correlate(A, B, **kw, u_outlier_factor=0, neighbour_outlier_factor=0)
    after = correlate(A, B, **kw)  # the default factors
    assert after.attrs["dic_neighbour_outlier_factor"] == 4.0
    assert after.attrs["dic_u_outlier_factor"] == CorrelationParams.u_outlier_factor
    assert after.attrs["dic_outlier_floor_pixel"] == U_OUTLIER_FLOOR_PX
    ok0, ok1, e = before.flag.values == 0, after.flag.values == 0, _error(before)
    # the matches are the same: only the flags differ
    np.testing.assert_array_equal(after.u.values[ok1], before.u.values[ok1])
    off_before = (ok0 & (e > OFF)).sum() / ok0.sum()
    off_after = (ok1 & (e > OFF)).sum() / ok1.sum()
    good = ok0 & (e <= OFF)
    assert off_before > 0.02  # without the tests, 3.4 % of the ok points are > 0.05 px off
    assert off_after <= 0.002  # the target
    assert (good & ~ok1).sum() / good.sum() <= 0.02  # and at most 2 % of the good ones lost
    flagged = ok0 & ~ok1
    assert set(np.unique(after.flag.values[flagged])) <= {FLAG_NEIGHBOUR_OUTLIER, FLAG_U_OUTLIER}
    assert np.isnan(after.u.values[flagged]).all()
    meanings = after.flag.attrs["flag_meanings"].split()
    values = list(after.flag.attrs["flag_values"])
    assert meanings[values.index(FLAG_NEIGHBOUR_OUTLIER)] == "neighbour_outlier"
    assert meanings[values.index(FLAG_U_OUTLIER)] == "uncertainty_outlier"
    # only the faint part loses points
    x = np.broadcast_to(after.x.values, flagged.shape)
    assert not flagged[x < 380].any()


def test_a_smooth_strain_field_is_not_flagged():
    """Real deformation (homogeneous strain and rotation; a sinusoid with 1.4 % strain whose
    curvature moves a point 0.03 pixel from its neighbours' median): no outliers."""
    prm = SpeckleParams(noise_std=1.0)
    strain = sp.AffineField.from_strain(
        exx=0.04, eyy=-0.02, rotation_deg=3, center=(120, 120), translation=(0.3, -0.2)
    )
    wave = sp.SinusoidalField((1.0, 0.5), 300.0)
    for field, shape in ((strain, (240, 240)), (wave, (300, 400))):
        pair = sp.speckle_pair(shape, field, params=prm, seed=4)
        ds = correlate(pair.reference, pair.deformed, subset_size=21, step=6)
        X, Y = np.meshgrid(ds.x.values, ds.y.values)
        tu, tv = pair.truth(X, Y)
        ok = ds.flag.values == 0
        assert np.nanmax(np.hypot(ds.u.values - tu, ds.v.values - tv)[ok]) < OFF
        outliers = np.isin(ds.flag.values, (FLAG_NEIGHBOUR_OUTLIER, FLAG_U_OUTLIER))
        assert outliers.mean() <= 0.005, (field, outliers.sum())


def _grid_field(n=20, step=10.0):
    """A quadratic displacement field sampled on an n x n grid: P (N, 12), centres, index."""
    r, c = np.indices((n, n)).reshape(2, -1)
    x, y = c * step, r * step
    a, b = 2e-4, -1.5e-4  # strong curvature: the plain median is 0.02-0.03 pixel off
    P = np.zeros((n * n, 12))
    P[:, 0] = 0.3 + 0.01 * x + a * x**2  # u
    P[:, 1] = 0.01 + 2 * a * x  # du/dx
    P[:, 6] = -0.2 + b * (x - 100) * (y - 100) + 0.005 * y  # v
    P[:, 7] = b * (y - 100)  # dv/dx
    P[:, 8] = b * (x - 100) + 0.005  # dv/dy
    return P, np.column_stack([x, y]).astype(float), np.column_stack([r, c])


def test_the_neighbour_rule_on_a_known_field():
    P, centres, index = _grid_field()
    n = len(P)
    flag = np.zeros(n, np.int8)
    sigma = np.full((n, 2), 0.004)
    kw = dict(P=P, centres=centres, index=index, neighbour_factor=4.0)
    # the deformation alone (edges and corners included) is no outlier
    assert not flag_uncertainty_outliers(flag, sigma, 3.0, **kw).any()
    # a point moved by 0.03 pixel (> 4 x 0.004 and the 0.02 floor) is; one moved by 0.015 is not
    bad = P.copy()
    bad[[45, 210], 0] += 0.03
    bad[130, 6] -= 0.015
    out = flag_uncertainty_outliers(flag, sigma, 3.0, **{**kw, "P": bad})
    assert np.flatnonzero(out).tolist() == [45, 210]
    assert (out[[45, 210]] == FLAG_NEIGHBOUR_OUTLIER).all()
    # u far above the median but in line with the neighbours: kept; without neighbours
    # (index -1, or the test off) the same point is an uncertainty outlier
    sigma_hi = sigma.copy()
    sigma_hi[77] = 0.05
    assert flag_uncertainty_outliers(flag, sigma_hi, 3.0, **kw)[77] == 0
    lone = index.copy()
    lone[77] = -1
    assert flag_uncertainty_outliers(flag, sigma_hi, 3.0, **{**kw, "index": lone})[77] == 11
    assert flag_uncertainty_outliers(flag, sigma_hi, 3.0)[77] == FLAG_U_OUTLIER
    # flagged neighbours are not used; a point with fewer than 3 ok neighbours is judged on u
    f2 = flag.copy()
    f2[[0 + 1, 20, 21]] = 2  # the corner point 0 loses its three neighbours
    sigma_hi[0] = 0.05
    assert flag_uncertainty_outliers(f2, sigma_hi, 3.0, **kw)[0] == FLAG_U_OUTLIER
    # 0 turns each test off; the input is not changed
    assert not flag_uncertainty_outliers(
        flag, sigma, 3.0, **{**kw, "P": bad, "neighbour_factor": 0}
    ).any()
    assert not flag.any()


def test_the_u_rule_per_image_and_its_limits():
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
    with pytest.raises(ParameterError, match="neighbour_outlier_factor"):
        CorrelationParams(neighbour_outlier_factor=0.5)


def test_neighbours_are_half_a_subset_apart():
    # compared subsets share at most about half their pixels (and errors)
    assert neighbour_reach(25, 12) == 1 and neighbour_reach(21, 6) == 2
    assert neighbour_reach(31, 10) == 2 and neighbour_reach(11, 2) == 3


def test_the_full_field_flags_them_too(faded):
    from jointwear.dic import measure_field

    A, B = faded
    ds = measure_field([A, B], subset_size=21, step=10, strain_window=0)
    meanings = ds.flag.attrs["flag_meanings"].split()
    assert meanings[FLAG_U_OUTLIER] == "uncertainty_outlier"
    assert meanings[FLAG_NEIGHBOUR_OUTLIER] == "neighbour_outlier"
    assert meanings[12] == "failed_in_source"  # an imported field's value, kept apart
    assert ds.attrs["dic_neighbour_outlier_factor"] == 4.0
    ok = ds.flag.values[1] == 0
    err = np.hypot(*(ds.displacement.values[1, ok] - SHIFT).T)
    assert (err > OFF).mean() <= 0.002
    flagged = np.isin(ds.flag.values[1], (FLAG_U_OUTLIER, FLAG_NEIGHBOUR_OUTLIER))
    assert flagged.any() and not flagged[ds.x.values < 380].any()


def test_an_image_mostly_of_outliers_names_the_factors():
    """Most of an image flagged by the outlier tests is no handful of outliers: the report
    names the two factors with their values and what to change."""
    import xarray as xr

    from jointwear.dic._flag_report import flag_report
    from jointwear.dic.icgn import OUTPUT_FLAG_MEANINGS, OUTPUT_FLAG_VALUES

    flag = np.full((1, 20), FLAG_NEIGHBOUR_OUTLIER, np.int8)
    flag[0, :4] = 0
    attrs = {"flag_values": OUTPUT_FLAG_VALUES, "flag_meanings": OUTPUT_FLAG_MEANINGS}
    ds = xr.Dataset(
        {"flag": (("time", "point"), flag, attrs)},
        attrs={"dic_neighbour_outlier_factor": 4.0, "dic_u_outlier_factor": 2.0},
    )
    (line,) = flag_report(ds).lines
    assert "16 of 20 points flagged, mostly neighbour_outlier" in line
    assert "--neighbour-outlier-factor 4.0" in line and "--u-outlier-factor 2.0" in line


def test_the_command_refuses_a_factor_below_1_and_runs_the_fix(tmp_path, capsys):
    """A factor between 0 and 1 would flag most good points: exit 3 naming the parameter;
    the values the message offers (>= 1, or 0) run, and the file states them."""
    from jointwear.cli import main
    from jointwear.io import load_header

    data = tmp_path / "s"
    assert main(["datasets", "speckle", str(data), "--size", "96x96"]) == 0
    images = [str(data / "reference.png"), str(data / "deformed.png")]
    out = tmp_path / "f.nc"
    base = ["dic", "correlate", *images, "--out", str(out), "--subset", "21"]
    assert main([*base, "--neighbour-outlier-factor", "0.5"]) == 3
    err = capsys.readouterr().err
    assert "--neighbour-outlier-factor 0.5" in err and "or 0 for no test" in err
    for value in ("1", "0"):
        assert main([*base, "--neighbour-outlier-factor", value, "--overwrite"]) == 0
        assert load_header(out).attrs["dic_neighbour_outlier_factor"] == float(value)


def test_second_derivatives_carry_a_sharply_curved_field():
    """u = 2 sin(2 pi x / 120) on a 6-pixel grid compared every 12 pixels: the trapezoid
    along the gradients misses by up to 0.04 pixel (beyond the 0.02 floor); with the
    quadratic shape's second derivatives (Euler-Maclaurin) by 3e-4: no outlier."""
    n, step, k = 24, 6.0, 2 * np.pi / 120
    r, c = np.indices((n, n)).reshape(2, -1)
    x = c * step
    P = np.zeros((n * n, 12))
    P[:, 0], P[:, 1], P[:, 3] = 2 * np.sin(k * x), 2 * k * np.cos(k * x), -2 * k**2 * np.sin(k * x)
    kw = dict(
        centres=np.column_stack([x, r * step]), index=np.column_stack([r, c]),
        neighbour_factor=4.0, reach=neighbour_reach(21, 6),
    )  # fmt: skip
    flag, sigma = np.zeros(n * n, np.int8), np.full((n * n, 2), 1e-4)
    assert not flag_uncertainty_outliers(flag, sigma, 2.0, P=P, **kw).any()
    affine = P.copy()
    affine[:, 3] = 0.0  # what an affine subset reports: no second derivatives
    assert (flag_uncertainty_outliers(flag, sigma, 2.0, P=affine, **kw) == 13).mean() > 0.1
