"""``dic track`` refuses a folder of frames holding a stray image, naming it, as ``dic correlate``
and ``dic field`` do (one check, :func:`jointwear.dic.subset._sequence.check_frame_names`)."""

from __future__ import annotations

import shutil

import numpy as np
import pytest

from jointwear.cli import main
from jointwear.datasets.rig import RigConfig, VirtualRig, generate_rig

cv2 = pytest.importorskip("cv2")
pytest.importorskip("jointwear.dic.subset._correlator")  # the 2D engine (DIC part 1)


@pytest.fixture(scope="module")
def tiny(tmp_path_factory):
    """A few frames of a reduced rig (two cameras, images only) and its exact calibration."""
    out = tmp_path_factory.mktemp("tiny_rig")
    cfg = RigConfig(width=640, height=512, duration=0.1)
    written = generate_rig(out, cfg, video=False, images=True, calibration_images=False)
    cal = VirtualRig(cfg).calibration.save(out / "calibration.nc")
    return written, cal


def _copy(folder, dest):
    shutil.copytree(folder, dest)
    return dest


def _track(capsys, *args):
    capsys.readouterr()
    code = main(["dic", "track", *(str(a) for a in args), "--fps", "50"])
    return code, capsys.readouterr().err


def test_a_stray_image_in_the_left_folder_is_refused_naming_it(tiny, tmp_path, capsys):
    written, _ = tiny
    left = _copy(written["left_images"], tmp_path / "left")
    cv2.imwrite(str(left / "mask.png"), np.full((512, 640), 255, np.uint8))
    out = tmp_path / "motion.nc"
    code, err = _track(capsys, "--left", left, "--bodies", written["bodies"], "--out", out)
    assert code == 3
    assert "'mask.png'" in err and "left footage folder" in err
    assert str(left / "frame_*.png") in err and "move the other files out" in err
    assert not out.exists()
    # the fix the message names: a pattern selecting the frames
    code, err = _track(capsys, "--left", left / "frame_*.png", "--bodies", written["bodies"],
                       "--out", out, "--max-frames", "3")  # fmt: skip
    assert code == 0, err
    assert out.is_file()


def test_a_stray_image_in_the_right_folder_is_refused_naming_it(tiny, tmp_path, capsys):
    written, cal = tiny
    right = _copy(written["right_images"], tmp_path / "right")
    cv2.imwrite(str(right / "roi.png"), np.full((512, 640), 255, np.uint8))
    out = tmp_path / "motion.nc"
    code, err = _track(capsys, "--left", written["left_images"], "--right", right, "--bodies",
                       written["bodies"], "--calibration", cal, "--out", out)  # fmt: skip
    assert code == 3
    assert "'roi.png'" in err and "right footage folder" in err
    assert str(right / "frame_*.png") in err
    assert not out.exists()


def test_clean_folders_still_track(tiny, tmp_path, capsys):
    written, cal = tiny
    left = _copy(written["left_images"], tmp_path / "left")
    (left / "notes.txt").write_text("not an image: ignored, as by dic correlate\n")
    out = tmp_path / "motion.nc"
    code, err = _track(capsys, "--left", left, "--right", written["right_images"], "--bodies",
                       written["bodies"], "--calibration", cal, "--out", out, "--max-frames",
                       "3")  # fmt: skip
    assert code == 0, err
    assert out.is_file()
