"""Footage sources as cameras and DIC software write them: numbering, patterns, TIFF stacks."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from jointwear.dic.footage._video import check_stereo_pair, list_image_sequence, open_frames
from jointwear.dic.subset._sequence import read_frames
from jointwear.errors import BadInputError


def _frame(k: int, shape=(24, 32), dtype=np.uint8) -> np.ndarray:
    """A frame whose pixels all carry its index k (so order mistakes show)."""
    return np.full(shape, 10 * k + 3, dtype=dtype)


def _write(folder, names, dtype=np.uint8):
    folder.mkdir(parents=True, exist_ok=True)
    for name, k in names:
        assert cv2.imwrite(str(folder / name), _frame(k, dtype=dtype))


def test_unpadded_numbers_are_read_in_frame_order(tmp_path):
    # frame_9 must come before frame_10 (a plain name sort puts 10 first); frame 12 is missing
    names = [(f"frame_{k}.png", k) for k in (8, 9, 10, 11, 13)]
    _write(tmp_path / "seq", names)
    files, numbers = list_image_sequence(tmp_path / "seq")
    assert [f.name for f in files] == [n for n, _ in names]
    assert numbers.tolist() == [8, 9, 10, 11, 13]
    src = open_frames(tmp_path / "seq", fps=50.0)
    values = [int(img[0, 0]) for _, _, img in src.frames()]
    assert values == [10 * k + 3 for k in (8, 9, 10, 11, 13)]
    # the gap is a dropped frame: 40 ms between frames 11 and 13
    assert np.allclose(np.diff(src.nominal_times()), [0.02, 0.02, 0.02, 0.04])
    # the 2D engine's reader uses the same order
    frames, _ = read_frames(tmp_path / "seq")
    assert [int(f[0, 0]) for f in frames] == values


def test_vic3d_style_shared_folder_needs_a_pattern(tmp_path):
    # VIC-3D writes both cameras into one folder: name_<frame>_<camera>.tif
    folder = tmp_path / "images"
    _write(folder, [(f"Spec-{k:04d}_{c}.tif", k + 10 * c) for k in range(6) for c in (0, 1)])
    with pytest.raises(BadInputError, match=r"only 6 distinct frame numbers.*'folder/\*_0.tif'"):
        open_frames(folder, fps=50.0)
    left = open_frames(str(folder / "*_0.tif"), fps=50.0, what="left footage")
    right = open_frames(str(folder / "*_1.tif"), fps=50.0, what="right footage")
    check_stereo_pair(left, right)  # same numbering 0..5 on both
    assert left.frame_numbers.tolist() == list(range(6))
    assert [int(img[0, 0]) for _, _, img in left.frames()] == [10 * k + 3 for k in range(6)]
    assert [int(img[0, 0]) for _, _, img in right.frames()] == [10 * (k + 10) + 3 for k in range(6)]
    # the counter is the number that changes, not the last one in the name
    files, numbers = list_image_sequence(str(folder / "*_1.tif"))
    assert numbers.tolist() == list(range(6))
    with pytest.raises(BadInputError, match=r"pattern '.*\*_7.tif' holds no images"):
        open_frames(str(folder / "*_7.tif"), fps=50.0)


def test_pattern_matching_non_images_is_refused(tmp_path):
    _write(tmp_path, [("a_1.png", 1), ("a_2.png", 2)])
    (tmp_path / "a_3.txt").write_text("notes")
    with pytest.raises(BadInputError, match="not images"):
        list_image_sequence(str(tmp_path / "a_*"))


def test_multipage_tiff_stack_round_trip(tmp_path):
    pages = [_frame(k, dtype=np.uint16) * 50 for k in range(70)]  # more than one read batch
    path = tmp_path / "stack.tif"
    assert cv2.imwritemulti(str(path), pages)
    with pytest.raises(BadInputError, match=r"multi-page TIFF \(70 pages\): give the frame rate"):
        open_frames(path)
    src = open_frames(path, fps=1000.0)
    assert src.kind == "stack" and src.n_frames == 70 and src.size == (32, 24)
    got = list(src.frames(60, 70, native=True))
    assert [i for i, _, _ in got] == list(range(60, 70))
    assert all(img.dtype == np.uint16 for _, _, img in got)
    assert [int(img[0, 0]) for _, _, img in got] == [int(p[0, 0]) for p in pages[60:70]]
    assert got[0][1] == pytest.approx(0.060)
    # a single-page TIFF is one image, not footage
    cv2.imwrite(str(tmp_path / "one.tif"), pages[0])
    with pytest.raises(BadInputError, match="is a single image"):
        open_frames(tmp_path / "one.tif", fps=50.0)
    # a damaged stack
    (tmp_path / "cut.tif").write_bytes(path.read_bytes()[:200])
    with pytest.raises(BadInputError, match="could not be read as a TIFF|could not be read"):
        src = open_frames(tmp_path / "cut.tif", fps=50.0)
        list(src.frames())


def test_frame_of_another_size_is_named(tmp_path):
    _write(tmp_path / "seq", [(f"img_{k:03d}.png", k) for k in range(3)])
    cv2.imwrite(str(tmp_path / "seq" / "img_003.png"), np.zeros((10, 10), np.uint8))
    src = open_frames(tmp_path / "seq", fps=50.0)
    with pytest.raises(BadInputError, match=r"img_003.png' \(frame 3\) is 10 x 10 px"):
        list(src.frames())


def test_high_speed_camera_formats_get_export_advice(tmp_path):
    path = tmp_path / "run1.cine"
    path.write_bytes(b"CI" + bytes(100))
    with pytest.raises(BadInputError, match=r"Phantom.*export the recording.*TIFF sequence"):
        open_frames(path, fps=1000.0)
