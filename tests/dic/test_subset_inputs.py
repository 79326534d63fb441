"""Smaller input rules of the 2D engine: default grid margin, guess broadcasting, seeds, frame
folders with odd files, and the correlate CLI's solver options."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from jointwear import io
from jointwear.cli import main
from jointwear.datasets import speckle as sp
from jointwear.dic import SubsetCorrelator, correlate, correlate_sequence, read_frames
from jointwear.dic.subset._correlator import _GRID_SLACK
from jointwear.errors import BadInputError


@pytest.mark.parametrize("shift", [-0.4, 0.4])
def test_default_grid_survives_small_motion_towards_every_edge(shift):
    # outer points used to sit exactly on the border margin: a sub-pixel motion towards the
    # edge flagged them subset_outside_image
    # 101 px: without the slack the 8-px grid spans the margins exactly (14..86)
    pair = sp.speckle_pair((101, 101), sp.RigidField((shift, shift)), seed=4)
    ds = correlate(pair.reference, pair.deformed, subset_size=21, step=8)
    assert (ds.flag.values == 0).all()
    assert ds.x.values.min() - 10 >= 4 + _GRID_SLACK
    assert ds.x.values.max() + 10 <= 100 - 4 - _GRID_SLACK
    np.testing.assert_allclose(ds.u.values, shift, atol=0.01)


def test_one_row_initial_guess_is_broadcast():
    pair = sp.speckle_pair((96, 96), sp.RigidField((3.3, -1.2)), seed=8)
    corr = SubsetCorrelator(pair.reference, subset_size=21, step=12)
    for guess in ([[3.0, -1.0]], [3.0, -1.0], [[3.0, 0, 0, -1.0, 0, 0]]):
        ds = corr.correlate(pair.deformed, initial_guess=np.array(guess))
        assert (ds.flag.values == 0).all()
        np.testing.assert_allclose(ds.u.values, 3.3, atol=0.005)
    with pytest.raises(BadInputError, match="initial_guess"):
        corr.correlate(pair.deformed, initial_guess=np.zeros((2, 2)))


def test_seeds_outside_the_image_are_refused_for_pairs_and_sequences():
    pair = sp.speckle_pair((80, 80), sp.RigidField((0.5, 0.0)), seed=1)
    with pytest.raises(BadInputError, match=r"seed point \(120, 40\).*outside the 80x80"):
        correlate(pair.reference, pair.deformed, seed_points=np.array([[120.0, 40.0]]))
    with pytest.raises(BadInputError, match=r"seed point \(-1, 3\)"):
        correlate_sequence([pair.reference, pair.deformed], seed_points=[-1.0, 3.0], subset_size=21)


def test_sequence_searches_from_the_given_seeds(monkeypatch):
    # frame 2 jumps 25 px: the guess from frame 1 fails and the frame is searched afresh,
    # starting at the seed (which must reach the search, here followed through the
    # incremental reference)
    fields = [None, sp.RigidField((1.0, 0.0)), sp.RigidField((26.0, 0.0))]
    frames = sp.speckle_sequence((96, 160), fields, seed=3)
    seen = []
    orig = SubsetCorrelator.match

    def spy(self, deformed, **kw):
        seen.append(kw.get("seed_points"))
        return orig(self, deformed, **kw)

    monkeypatch.setattr(SubsetCorrelator, "match", spy)
    ds = correlate_sequence(
        frames,
        seed_points=[[40.0, 48.0]],
        subset_size=21,
        step=12,
        search_radius=32,
        reference="incremental",
        update_every=1,
    )
    searched = [s for s in seen if s is not None]
    assert searched and abs(searched[-1][0, 0] - 41.0) < 0.05  # the seed moved with frame 1
    ok = ds.flag.values[-1] == 0
    assert ok.mean() > 0.5
    np.testing.assert_allclose(ds.u.values[-1][ok], 26.0, atol=0.02)


def test_folder_with_a_mask_image_is_refused_unless_a_pattern_is_given(tmp_path):
    frames = sp.speckle_sequence((64, 64), [None, sp.RigidField((0.5, 0.0))], seed=2)
    for k, f in enumerate(frames):
        cv2.imwrite(str(tmp_path / f"frame_{k:04d}.png"), f)
    cv2.imwrite(str(tmp_path / "roi.tif"), np.full((64, 64), 255, np.uint8))
    with pytest.raises(BadInputError, match=r"'roi.tif'.*frame_\*\.png"):
        read_frames(tmp_path)
    got, _ = read_frames(str(tmp_path / "frame_*.png"))
    assert len(got) == 2 and np.array_equal(got[1], frames[1])


def test_cli_points_tolerance_iterations_and_update_options(tmp_path):
    frames = sp.speckle_sequence(
        (96, 96), [None] + [sp.RigidField((0.7 * k, 0.2 * k)) for k in (1, 2, 3)], seed=9
    )
    for k, f in enumerate(frames):
        cv2.imwrite(str(tmp_path / f"img_{k}.png"), f)
    pts = tmp_path / "points.csv"
    pts.write_text("x,y\n30, 40\n50.5, 47\n# a comment\n60 60\n")
    out = tmp_path / "seq.nc"
    args = ["dic", "correlate", str(tmp_path / "img_*.png"), "--points", str(pts)]
    args += ["--subset", "21", "--tolerance", "1e-4", "--max-iterations", "30"]
    args += ["--sequence-mode", "incremental", "--update-every", "1", "--out", str(out)]
    assert main(args) == 0
    ds = io.load(out)
    assert list(ds.x.values) == [30.0, 50.5, 60.0]
    assert ds.attrs["dic_tolerance_pixel"] == 1e-4
    assert list(ds.reference_frame.values) == [0, 0, 1, 2]
    np.testing.assert_allclose(ds.u.values[-1], 2.1, atol=0.01)
    pts.write_text("30, 40, 5\n")
    assert main([*args[:-2], "--out", str(tmp_path / "x.nc")]) == 3
    assert main(["dic", "correlate", str(tmp_path / "img_*.png"), "--update-every", "2"]) == 2
