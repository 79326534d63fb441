"""The specimen's edges: a ROI that covers background, a hole and the image border gives NaN
strain with a ``strain_flag`` saying why where neighbours are missing, never an exception, and
the exact strain of an affine field wherever the window is whole."""

from __future__ import annotations

import numpy as np
import pytest

from jointwear.datasets import speckle as sp
from jointwear.dic import measure_field

GRAD = ((0.006, 0.002), (0.001, -0.003))


@pytest.fixture(scope="module")
def specimen():
    """A speckled specimen on a blank background (right third), with a blank hole, the ROI the
    whole image (its border included)."""
    field = sp.AffineField(translation=(0.7, -0.4), gradient_matrix=GRAD, center=(80, 70))
    params = sp.SpeckleParams(speckle_size=4.0, noise_std=1.0)
    frames = sp.speckle_sequence((150, 180), [None, field], params=params, seed=5)
    yy, xx = np.mgrid[0:150, 0:180]
    blank = (xx > 125) | ((xx - 60) ** 2 + (yy - 75) ** 2 < 18**2)
    out = []
    for f in frames:
        g = f.astype(float)
        g[blank] = 128.0  # background and hole: no texture, the same in both images
        out.append(g)
    ds = measure_field(
        out, roi=(0, 0, 179, 149), subset_size=21, step=6, strain_window=5,
        data_origin="synthetic",
    )  # fmt: skip
    return ds, blank


def test_strain_at_the_edges_is_nan_with_a_flag_and_exact_inside(specimen):
    ds, blank = specimen
    flag = ds.flag.values[1]
    assert (flag != 0).any() and (flag == 0).mean() > 0.3  # edges flagged, the rest measured
    E = ds.strain.values[1]
    sflag = ds.strain_flag.values[1]
    meanings = ds.strain_flag.attrs["flag_meanings"].split()
    assert meanings[0] == "ok"
    # NaN exactly where the flag is not ok, for every derived variable
    for name in ("strain", "strain_u", "strain_engineering"):
        values = ds[name].values[1]
        assert np.array_equal(np.isnan(values).any(axis=1), sflag != 0), name
    # a point that was not measured has no strain, and says so
    assert (sflag[flag != 0] == meanings.index("point_not_measured")).all()
    # measured points next to the hole or the background lack neighbours
    short = meanings.index("window_incomplete")
    assert ((flag == 0) & (sflag == short)).sum() > 5
    # wherever the window is whole, the Green-Lagrange strain of the affine field
    F = np.eye(2) + np.array(GRAD)
    G = 0.5 * (F.T @ F - np.eye(2))
    whole = sflag == 0
    assert whole.sum() > 20
    np.testing.assert_allclose(np.median(E[whole], axis=0), [G[0, 0], G[1, 1], G[0, 1]], atol=3e-4)


def test_surface_strain_with_an_unmeasured_centre_point_gives_nan_not_an_error():
    """The reference position of the centre point unknown (flagged in the reference image),
    its neighbours known: the fit has no origin; it used to raise LinAlgError."""
    from jointwear.dic.field._strain import surface_strain

    ys, xs = np.mgrid[0:7, 0:7]
    ref = np.column_stack([xs.ravel(), ys.ravel()]).astype(float) * 10.0
    cur = (ref * 1.003)[None]
    sigma = np.full((1, ref.shape[0]), 0.01)
    index = np.column_stack([ys.ravel(), xs.ravel()])
    centre = 3 * 7 + 3
    ref_gap = ref.copy()
    ref_gap[centre] = np.nan
    E, U, _ = surface_strain(ref_gap, cur, sigma, index, 5, ref.copy(), 21)
    assert np.isnan(E[0, centre]).all() and np.isnan(U[0, centre]).all()
    assert np.isfinite(E[0, centre + 1]).all()  # its neighbours keep theirs
    # stereo (3D positions): the same
    ref3 = np.column_stack([ref_gap, np.zeros(len(ref))])
    cur3 = np.column_stack([ref * 1.003, np.zeros(len(ref))])[None]
    E3, _, _ = surface_strain(ref3, cur3, sigma, index, 5, ref.copy(), 21)
    assert np.isnan(E3[0, centre]).all() and np.isfinite(E3[0, centre + 1]).all()


def test_cli_field_on_a_roi_beyond_the_specimen_exits_0(specimen, tmp_path):
    import cv2

    from jointwear.cli import main

    field = sp.AffineField(translation=(0.7, -0.4), gradient_matrix=GRAD, center=(80, 70))
    params = sp.SpeckleParams(speckle_size=4.0, noise_std=1.0)
    frames = sp.speckle_sequence((150, 180), [None, field], params=params, seed=5)
    names = []
    for k, f in enumerate(frames):
        g = f.copy()
        g[:, 126:] = 128
        names.append(str(tmp_path / f"s_{k}.png"))
        cv2.imwrite(names[-1], g)
    out = tmp_path / "f.nc"
    args = ["dic", "field", *names, "--roi", "0,0,179,149", "--subset", "21", "--step", "8"]
    assert main([*args, "--out", str(out)]) == 0
