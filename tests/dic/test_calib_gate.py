"""Stereo calibration that cannot fail silently: one corner order for both cameras, both
detectors, the sanity gate, views named by file, unit-less boards, the length uncertainty."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from jointwear.datasets.rig import RigConfig, VirtualRig
from jointwear.dic.calibration._board import CalibrationBoard, calibrate_stereo
from jointwear.dic.calibration._gate import PoorCalibration
from jointwear.dic.calibration._importers import read_calibration
from jointwear.errors import BadInputError, CalibrationError


def _rz(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


@pytest.fixture(scope="module")
def rig():
    # a 9 x 6 inner-corner board (10 x 7 squares), the common printed target
    return VirtualRig(RigConfig(width=640, height=512, board_views=9, board_squares=(10, 7)))


@pytest.fixture(scope="module")
def board(rig):
    c = rig.config
    return CalibrationBoard("chessboard", *c.board_squares, c.board_square_size)


@pytest.fixture(scope="module")
def rotated_boards(rig):
    """Views of the board turned in its plane by 90-270 degrees: upside down, and near the
    diagonal where an image-based 'first corner top-left' rule flips in one camera only."""
    c = rig.config
    half = np.array([c.board_squares[0], c.board_squares[1], 0.0]) * c.board_square_size / 2
    turns = [180, 170, 195, 135, 225, 150, 215, 100, 260]
    out = []
    for i, ((R, origin), turn) in enumerate(zip(rig.board_poses()[:-1], turns, strict=True)):
        centre = origin + R @ half
        R2 = R @ _rz(np.deg2rad(turn))
        o2 = centre - R2 @ half
        out.append(
            (rig.render_board("left", R2, o2, index=i), rig.render_board("right", R2, o2, index=i))
        )
    return out


def _check_truth(cal, true, *, focal_rel=3e-3, rot_deg=0.1):
    for name in ("left", "right"):
        for fe, ft in zip(cal.cameras[name].focal, true.cameras[name].focal, strict=True):
            assert abs(fe / ft - 1) < focal_rel
    assert abs(cal.baseline / true.baseline - 1) < 3e-3
    R_est, _ = cal.relative_pose
    R_true, _ = true.relative_pose
    angle = np.degrees(np.arccos(np.clip((np.trace(R_est.T @ R_true) - 1) / 2, -1, 1)))
    assert angle < rot_deg
    assert cal.rms < 0.1


def test_board_turned_upside_down_recovers_truth(rig, board, rotated_boards):
    cal = calibrate_stereo([b[0] for b in rotated_boards], [b[1] for b in rotated_boards], board)
    _check_truth(cal, rig.calibration)
    assert cal.views_used == len(rotated_boards) and cal.rejected == ()
    # the baseline's relative uncertainty covers its actual error and is not vacuous
    err = abs(cal.baseline / rig.calibration.baseline - 1)
    assert cal.length_scale_u_rel is not None and err < 3 * cal.length_scale_u_rel < 3e-2


def test_camera_mounted_upside_down(rig, board, rotated_boards, monkeypatch):
    # the right camera turned 180 degrees about its axis: every right image is rotated, so the
    # two cameras' detectors start their corner lists at opposite board corners
    rights = [np.ascontiguousarray(b[1][::-1, ::-1]) for b in rotated_boards]
    lefts = [b[0] for b in rotated_boards]
    cal = calibrate_stereo(lefts, rights, board)
    assert cal.rms < 0.1 and cal.views_used == len(lefts)
    assert abs(cal.baseline / rig.calibration.baseline - 1) < 3e-3
    w, h = rig.config.width, rig.config.height
    cx, cy = rig.calibration.right.matrix[:2, 2]
    assert np.allclose(cal.right.matrix[:2, 2], [w - 1 - cx, h - 1 - cy], atol=3.0)
    # without the geometric ordering the same images give a calibration that the gate refuses
    import jointwear.dic.calibration._order as order

    monkeypatch.setattr(order, "consistent_order", lambda cands: ([0] * len(cands), cands[0][0]))
    with pytest.raises(PoorCalibration, match="reprojection RMS"):
        calibrate_stereo(lefts, rights, board)


def test_mismatched_and_swapped_pairs(rig, board, rotated_boards):
    lefts = [b[0] for b in rotated_boards]
    rights = [b[1] for b in rotated_boards]
    # pairs out of step (the right list shifted by one): refused, not calibrated
    with pytest.raises(CalibrationError, match="not simultaneous pairs"):
        calibrate_stereo(lefts, rights[1:] + rights[:1], board)
    # one pair with its files swapped is rejected by name, the rest calibrates
    L2, R2 = list(lefts), list(rights)
    L2[3], R2[3] = rights[3], lefts[3]
    names = [f"L{i:02d}.png / R{i:02d}.png" for i in range(len(lefts))]
    cal = calibrate_stereo(L2, R2, board, view_names=names)
    assert cal.views_used == len(lefts) - 1
    assert len(cal.rejected) == 1 and cal.rejected[0].startswith("L03.png / R03.png: the left")
    assert "L03.png / R03.png" not in cal.view_names
    # the whole set swapped (--left and --right exchanged): the gate refuses it
    with pytest.raises(PoorCalibration, match="right camera sits to the LEFT") as exc:
        calibrate_stereo(rights, lefts, board)
    assert exc.value.exit_code == 1 and exc.value.calibration.status.startswith("rejected")


def test_classic_detector_takes_over(rig, board, rotated_boards, monkeypatch):
    # where the sector-based detector finds nothing, the classic one is tried
    lefts = [b[0] for b in rotated_boards]
    rights = [b[1] for b in rotated_boards]
    monkeypatch.setattr(cv2, "findChessboardCornersSB", lambda *a, **k: (False, None))
    cal = calibrate_stereo(lefts, rights, board)
    _check_truth(cal, rig.calibration, focal_rel=5e-3, rot_deg=0.2)


def test_cli_gate_rejected_file_and_view_table(tmp_path, rig, rotated_boards, capsys):
    from jointwear.cli import main

    for cam, k in (("left", 0), ("right", 1)):
        (tmp_path / cam).mkdir()
        for i, pair in enumerate(rotated_boards):
            cv2.imwrite(str(tmp_path / cam / f"{cam}{i:02d}.png"), pair[k])
    # one pair's files exchanged on disk
    a, b = tmp_path / "left/left04.png", tmp_path / "right/right04.png"
    tmp = a.read_bytes()
    a.write_bytes(b.read_bytes())
    b.write_bytes(tmp)
    c = rig.config
    base = ["dic", "calibrate", "--squares", *map(str, c.board_squares)]
    size = ["--square", str(c.board_square_size * 1e3), "--unit", "mm"]
    out = tmp_path / "cal.nc"
    args = [*base, *size, "--left", str(tmp_path / "left"), "--right", str(tmp_path / "right")]
    assert main([*args, "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "left00.png / right00.png" in text
    assert "rejected left04.png / right04.png: the left and right images" in text
    cal = read_calibration(out)
    assert "left04.png / right04.png" not in cal.view_names and len(cal.view_names) == 8
    assert 0 < cal.length_scale_u_rel < 1e-2
    # --left/--right exchanged: exit 1, nothing at --out, the result kept as .rejected.nc
    bad = tmp_path / "swapped.nc"
    swapped = [*base, *size, "--left", str(tmp_path / "right"), "--right", str(tmp_path / "left")]
    assert main([*swapped, "--out", str(bad)]) == 1
    err = capsys.readouterr().err
    assert "right camera sits to the LEFT" in err and "swapped.rejected.nc" in err
    assert not bad.exists() and (tmp_path / "swapped.rejected.nc").exists()
    with pytest.raises(BadInputError, match="failed its sanity checks"):
        read_calibration(tmp_path / "swapped.rejected.nc")
    assert read_calibration(tmp_path / "swapped.rejected.nc", allow_rejected=True).rms < 0.1
    assert main([*swapped, "--out", str(bad), "--accept-poor"]) == 0
    assert read_calibration(bad).status.startswith("accepted with --accept-poor")
    # a board of unknown size: lengths in squares, refused for measuring
    sq = tmp_path / "squares.nc"
    dirs = ["--left", str(tmp_path / "left"), "--right", str(tmp_path / "right")]
    assert main([*base, *dirs, "--square", "1", "--unit", "square", "--out", str(sq)]) == 0
    with pytest.raises(BadInputError, match="in board squares"):
        read_calibration(sq)
    cal_sq = read_calibration(sq, allow_unitless=True)
    assert cal_sq.baseline * c.board_square_size == pytest.approx(cal.baseline, rel=1e-3)
    # the square size must be given
    assert main([*base, *dirs, "--out", str(tmp_path / "x.nc")]) == 2
