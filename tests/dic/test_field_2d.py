"""``measure_field`` in 2D (one camera): strain against a known affine field, honest
uncertainty on zero-motion data, ROI flags, still images, CSV export and the figure."""

from __future__ import annotations

import csv

import numpy as np
import pytest

from jointwear.datasets import speckle as sp
from jointwear.dic import measure_field, plot_field, write_field_csv
from jointwear.errors import BadInputError


@pytest.fixture(scope="module")
def affine():
    # 0.5 % stretch along x, -0.2 % along y, a little shear, on 3-px noisy speckle
    field = sp.AffineField(
        translation=(1.3, -0.6),
        gradient_matrix=((0.005, 0.002), (0.001, -0.002)),
        center=(80, 70),
    )
    params = sp.SpeckleParams(speckle_size=4.0, noise_std=1.0)
    frames = sp.speckle_sequence((140, 160), [None, None, field], params=params, seed=11)
    return field, frames


def test_green_lagrange_strain_of_an_affine_field(affine):
    field, frames = affine
    ds = measure_field(frames, subset_size=21, step=8, strain_window=5, data_origin="synthetic")
    ok = ds.flag.values[2] == 0
    assert ok.mean() > 0.95
    X, Y = ds.x.values, ds.y.values
    u, v = field.displacement(X, Y)
    np.testing.assert_allclose(ds.displacement.values[2][ok, 0], u[ok], atol=0.02)
    F = np.eye(2) + np.array([[0.005, 0.002], [0.001, -0.002]])
    E = 0.5 * (F.T @ F - np.eye(2))
    got = np.nanmedian(ds.strain.values[2], axis=0)
    np.testing.assert_allclose(got, [E[0, 0], E[1, 1], E[0, 1]], atol=1e-4)
    # the engineering normal strain is the stretch minus one
    assert (
        abs(np.nanmedian(ds.strain_engineering.values[2, :, 0]) - (np.hypot(F[0, 0], F[1, 0]) - 1))
        < 1e-4
    )
    assert ds.strain.attrs["strain_window"].startswith("local linear fit")
    # still images: no time coordinate, the image index instead
    assert "time" not in ds.coords and list(ds.image.values) == [0, 1, 2]
    assert ds.attrs["data_origin"] == "synthetic"


def test_reported_uncertainty_matches_the_zero_motion_scatter(affine):
    # frames 0 and 1 are the same pattern with independent noise
    _, frames = affine
    ds = measure_field(frames[:2], subset_size=21, step=8, strain_window=5)
    ok = ds.flag.values[1] == 0
    d = ds.displacement.values[1][ok]
    du = ds.displacement_u.values[1][ok]
    for i in range(2):
        ratio = np.sqrt(np.mean(du[:, i] ** 2)) / d[:, i].std()
        assert 0.7 < ratio < 1.3, ratio
    E = ds.strain.values[1]
    Eu = ds.strain_u.values[1]
    for i in range(3):
        good = np.isfinite(E[:, i])
        robust = (np.percentile(E[good, i], 75) - np.percentile(E[good, i], 25)) / 1.349
        ratio = np.median(Eu[good, i]) / robust
        assert 0.6 < ratio < 1.5, (i, ratio)


def test_polygon_roi_flags_subsets_crossing_its_edge(affine, tmp_path):
    _, frames = affine
    poly = tmp_path / "roi.toml"
    poly.write_text("[roi]\npolygon = [[20, 20], [140, 20], [20, 120]]\n")
    ds = measure_field(frames[:2], roi=str(poly), subset_size=21, step=10, strain_window=0)
    edge = ds.flag.values[1] == 9
    assert edge.any() and (ds.flag.values[1][~edge] == 0).all()
    x, y = ds.x.values, ds.y.values
    # a subset is wholly inside the triangle when its far corner is: (x+10, y+10)
    reach = (x + 10 - 20) / 120 + (y + 10 - 20) / 100
    assert (reach[~edge] <= 1 + 0.015).all() and (reach[edge] > 1 - 0.015).all()
    assert ((x - 20) / 120 + (y - 20) / 100 <= 1.01).all()  # centres inside
    assert np.isnan(ds.displacement.values[1][edge]).all()
    assert "strain" not in ds
    with pytest.raises(BadInputError, match="at least 3 vertices"):
        poly.write_text("[roi]\npolygon = [[1, 2], [3, 4]]\n")
        measure_field(frames[:2], roi=str(poly))


def test_csv_export_and_figure(affine, tmp_path):
    _, frames = affine
    ds = measure_field(frames, subset_size=21, step=12, strain_window=3)
    files = write_field_csv(ds, tmp_path / "field.csv")
    assert [f.name for f in files] == ["field_0000.csv", "field_0001.csv", "field_0002.csv"]
    rows = list(csv.DictReader(files[2].read_text().splitlines()))
    assert len(rows) == ds.sizes["point"]
    # a border point measures displacement but has too few window neighbours for strain
    strained = np.isfinite(ds.strain.values[2, :, 0])
    k = next(i for i, r in enumerate(rows) if r["flag"] == "ok" and strained[i])
    assert float(rows[k]["u [pixel]"]) == pytest.approx(ds.displacement.values[2, k, 0], rel=1e-8)
    assert float(rows[k]["exx"]) == pytest.approx(ds.strain.values[2, k, 0], rel=1e-8)
    fig = plot_field(ds)
    assert len(fig.axes) >= 4


def test_cli_2d_field_with_a_frame_rate_and_a_mask(affine, tmp_path):
    import cv2

    from jointwear import io
    from jointwear.cli import main

    _, frames = affine
    names = []
    for k, f in enumerate(frames):
        names.append(str(tmp_path / f"img_{k}.png"))
        cv2.imwrite(names[-1], f)
    mask = np.zeros(frames[0].shape, np.uint8)
    mask[20:120, 30:130] = 255
    cv2.imwrite(str(tmp_path / "mask.png"), mask)
    out = tmp_path / "f.nc"
    args = ["dic", "field", *names, "--roi", str(tmp_path / "mask.png"), "--subset", "21"]
    assert main([*args, "--step", "10", "--fps", "50", "--out", str(out)]) == 2  # stills
    # the refusal's fix: the frames as a quoted pattern take a frame rate
    args[2 : 2 + len(names)] = [str(tmp_path / "img_*.png")]
    assert main([*args, "--step", "10", "--fps", "50", "--out", str(out)]) == 0
    ds = io.load(out)
    np.testing.assert_allclose(ds.time.values, [0, 0.02, 0.04])
    assert ds.time.attrs["units"] == "s" and ds.displacement.attrs["units"] == "pixel"
    x, y = ds.x.values, ds.y.values
    assert (x - 10 >= 30).all() and (x + 10 <= 129).all() and (y - 10 >= 20).all()
    assert (ds.flag.values[2] == 0).mean() > 0.95
    # a mask of another size is refused, naming both sizes
    cv2.imwrite(str(tmp_path / "small.png"), mask[:50])
    bad = ["dic", "field", *names, "--roi", str(tmp_path / "small.png"), "--out", str(out)]
    assert main(bad) == 3


def test_strain_needs_the_stated_share_of_the_window():
    """A point whose window holds fewer valid neighbours than min_count gets no strain
    (min_count counts points; it once counted three per point)."""
    from jointwear.dic.field._strain import surface_strain

    ys, xs = np.mgrid[0:7, 0:7]
    ref = np.column_stack([xs.ravel(), ys.ravel()]).astype(float) * 10.0
    cur = (ref * 1.003)[None]
    sigma = np.full((1, ref.shape[0]), 0.01)
    index = np.column_stack([ys.ravel(), xs.ravel()])
    pixels = ref.copy()
    E, _, _ = surface_strain(ref, cur, sigma, index, 5, pixels, 21)
    centre = 3 * 7 + 3
    assert E[0, centre, 0] == pytest.approx(0.5 * (1.003**2 - 1), rel=1e-9)
    # 25 points in the 5x5 window, min_count = 15: keep 10 valid -> no strain
    keep = np.zeros(ref.shape[0], bool)
    win = [(r, c) for r in range(1, 6) for c in range(1, 6)]
    for r, c in win[:10]:
        keep[r * 7 + c] = True
    thin = np.where(keep[None, :, None], cur, np.nan)
    E, _, _ = surface_strain(ref, thin, sigma, index, 5, pixels, 21)
    assert np.isnan(E[0, centre, 0])
