"""Stereo calibration: recovery of the virtual rig's cameras, importers, errors."""

from __future__ import annotations

import numpy as np
import pytest

from jointwear.datasets.rig import RigConfig, VirtualRig
from jointwear.dic._calib import (
    Camera,
    StereoCalibration,
    cardan_to_matrix,
    matrix_to_cardan,
    read_calibration,
    read_opencv_calibration,
    read_vic3d_calibration,
)
from jointwear.dic._calib_board import CalibrationBoard, board_world_frame, calibrate_stereo
from jointwear.errors import BadInputError, CalibrationError


@pytest.fixture(scope="module")
def rig():
    # reduced size: 640 x 512 px over the same 0.42 m field of view
    return VirtualRig(RigConfig(width=640, height=512, board_views=10))


@pytest.fixture(scope="module")
def boards(rig):
    return rig.board_images()


@pytest.fixture(scope="module")
def board(rig):
    c = rig.config
    return CalibrationBoard("chessboard", *c.board_squares, c.board_square_size)


@pytest.fixture(scope="module")
def calibration(boards, board):
    return calibrate_stereo([b[0] for b in boards], [b[1] for b in boards], board)


def test_calibration_recovers_generated_cameras(rig, calibration):
    true = rig.calibration
    for name in ("left", "right"):
        est, ref = calibration.cameras[name], true.cameras[name]
        for fe, ft in zip(est.focal, ref.focal, strict=True):
            assert abs(fe / ft - 1) < 2e-3
        assert np.allclose(est.matrix[:2, 2], ref.matrix[:2, 2], atol=2.0)
    assert abs(calibration.baseline / true.baseline - 1) < 2e-3
    assert calibration.rms < 0.1
    assert np.all(calibration.per_view_rms < 0.1)
    assert calibration.views_used == len(rig.board_poses()) and calibration.views_rejected == 0
    # relative pose: rotation angle error below 0.05 degree
    R_est, _ = calibration.relative_pose
    R_true, _ = true.relative_pose
    angle = np.degrees(np.arccos(np.clip((np.trace(R_est.T @ R_true) - 1) / 2, -1, 1)))
    assert angle < 0.05


def test_world_frame_from_board(rig, calibration, boards, board):
    cal = board_world_frame(calibration, boards[-1][0], board)
    # the world frame is the mechanism frame shifted to the board's first inner corner
    origin = rig.world_board_origin()
    X = np.array([[0.3, 0.2, 0.0], [0.25, 0.05, 0.004]])
    uv_true = rig.calibration.left.project(X)
    uv_est = cal.left.project(X - origin)
    assert np.max(np.abs(uv_true - uv_est)) < 0.5
    assert "board" in cal.world_frame


def test_too_few_views(boards, board):
    with pytest.raises(CalibrationError, match=r"only 3 of 3 calibration view\(s\).*at least 6"):
        calibrate_stereo([b[0] for b in boards[:3]], [b[1] for b in boards[:3]], board)
    blank = np.zeros((48, 64), np.uint8)
    with pytest.raises(
        CalibrationError, match=r"only 0 of 6 .*view 0: board not found \(both cameras\)"
    ):
        calibrate_stereo([blank] * 6, [blank] * 6, board)
    with pytest.raises(BadInputError, match="3 left and 2 right"):
        calibrate_stereo([blank] * 3, [blank] * 2, board)


def test_rejected_views_are_counted_with_their_reason(boards, board):
    blank = np.zeros_like(boards[0][0])
    lefts = [b[0] for b in boards[:7]] + [blank]
    rights = [b[1] for b in boards[:7]] + [boards[7][1]]
    cal = calibrate_stereo(lefts, rights, board)
    assert cal.views_used == 7 and cal.views_rejected == 1
    assert cal.rejected == ("view 7: board not found (left)",)


def test_save_and_read_round_trip(tmp_path, calibration):
    path = calibration.save(tmp_path / "cal.nc")
    back = read_calibration(path)
    for name in ("left", "right"):
        a, b = calibration.cameras[name], back.cameras[name]
        assert np.allclose(a.matrix, b.matrix) and np.allclose(a.distortion, b.distortion)
        assert np.allclose(a.rotation, b.rotation) and np.allclose(a.translation, b.translation)
    assert back.rms == pytest.approx(calibration.rms)
    assert back.views_used == calibration.views_used
    assert back.rejected == calibration.rejected


def test_undistortion_inverts_distortion():
    cam = Camera(
        np.array([[2000.0, 1.5, 640], [0, 2001.0, 512], [0, 0, 1]]),
        [-0.2, 0.15, 1e-3, -5e-4, -0.05],
        image_size=(1280, 1024),
    )
    rng = np.random.default_rng(1)
    xy = rng.uniform(-0.3, 0.3, (500, 2))
    uv = cam.normalized_to_pixels(xy)
    assert np.max(np.abs(cam.pixels_to_normalized(uv) - xy)) < 1e-10
    # the rational model (k4..k6) too, and NaN rows stay NaN without disturbing the others
    rational = Camera(
        cam.matrix, [0.3, -0.1, 5e-4, 1e-3, 0.02, 0.2, -0.05, 0.01], image_size=(1280, 1024)
    )
    uv = rational.normalized_to_pixels(xy)
    uv[7] = np.nan
    back = rational.pixels_to_normalized(uv)
    assert np.isnan(back[7]).all()
    assert np.max(np.abs(np.delete(back, 7, 0) - np.delete(xy, 7, 0))) < 1e-10


def test_cardan_round_trip():
    R = cardan_to_matrix(12.0, -7.0, 95.0)
    assert np.allclose(R @ R.T, np.eye(3))
    assert np.allclose(matrix_to_cardan(R), (12.0, -7.0, 95.0))
    # Rz(gamma) alone: x -> y for 90 degrees
    assert np.allclose(cardan_to_matrix(0, 0, 90) @ [1, 0, 0], [0, 1, 0])


def test_opencv_yaml_import(tmp_path, rig):
    import cv2

    true = rig.calibration
    R, T = true.relative_pose
    path = tmp_path / "stereo.yml"
    fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_WRITE)
    fs.write("K1", true.left.matrix)
    fs.write("D1", true.left.distortion[:5].reshape(1, 5))
    fs.write("K2", true.right.matrix)
    fs.write("D2", true.right.distortion[:5].reshape(1, 5))
    fs.write("R", R)
    fs.write("T", T.reshape(3, 1) * 1000.0)  # millimetres
    fs.write("image_width", 640)
    fs.write("image_height", 512)
    fs.release()
    cal = read_opencv_calibration(path, length_unit="mm")
    assert cal.baseline == pytest.approx(true.baseline, rel=1e-12)
    X = np.array([[0.3, 0.2, 0.0]])
    Xl = true.left.world_to_camera(X)
    assert np.allclose(cal.right.project(Xl), true.right.project(X), atol=1e-9)
    assert cal.left.image_size == (640, 512)
    with pytest.raises(BadInputError, match="length_unit 'furlong'"):
        read_opencv_calibration(path, length_unit="furlong")
    bad = tmp_path / "bad.yml"
    fs = cv2.FileStorage(str(bad), cv2.FILE_STORAGE_WRITE)
    fs.write("K1", true.left.matrix)
    fs.release()
    with pytest.raises(BadInputError, match="lacks D1, K2, D2, R, T"):
        read_opencv_calibration(bad, length_unit="mm")


def _vic_xml(cal: StereoCalibration, size=(640, 512)) -> str:
    parts = []
    for i, cam in enumerate((cal.left, cal.right)):
        K, d = cam.matrix, cam.distortion
        a, b, g = matrix_to_cardan(cam.rotation)
        t = cam.translation * 1e3
        intr = [K[0, 2], K[1, 2], K[0, 0], K[1, 1], K[0, 1], d[0], d[1], d[4]]
        parts.append(
            f'  <camera id="{i}">'
            + " ".join(f"{v:.12e}" for v in intr)
            + "<orientation>"
            + " ".join(f"{v:.12e}" for v in (a, b, g, *t))
            + "</orientation>\n  </camera>"
        )
    return (
        '<?xml version="1.0" encoding="ISO-8859-1"?>\n<!DOCTYPE vpml>\n<project>\n'
        '<calibration lri="calibration">\n' + "\n".join(parts) + "\n</calibration>\n"
        f'<projectaois><aoinode><polygonmask width="{size[0]}" height="{size[1]}"/></aoinode>'
        "</projectaois>\n</project>\n"
    )


def test_vic3d_import(tmp_path):
    # a camera pair with skew and no tangential distortion (VIC-3D's model), world frame between
    # the cameras as VIC-3D sets it
    left = Camera(
        np.array([[2468.5, -0.17, 638.9], [0, 2468.2, 407.3], [0, 0, 1]]),
        [-0.17, 0.064, 0, 0, 0.01],
        cardan_to_matrix(179.96, 9.015, 0.0337),
        np.array([-0.06323, -0.000337, 0.0187]),
        (1280, 800),
    )
    right = Camera(
        np.array([[2377.1, 0.09, 628.6], [0, 2376.9, 394.6], [0, 0, 1]]),
        [0.062, 0.0, 0, 0, 0.0],
        cardan_to_matrix(-179.96, -9.015, -0.0397),
        np.array([0.06484, -0.000876, 0.01535]),
        (1280, 800),
    )
    true = StereoCalibration(left, right)
    path = tmp_path / "cal.xml"
    path.write_text(_vic_xml(true, (1280, 800)))
    cal = read_vic3d_calibration(path)
    assert cal.left.image_size == (1280, 800)
    X = np.array([[0.01, 0.02, -0.3], [-0.02, 0.01, -0.28]])
    for name in ("left", "right"):
        assert np.allclose(cal.cameras[name].project(X), true.cameras[name].project(X), atol=1e-6)
    assert cal.baseline == pytest.approx(true.baseline, rel=1e-9)
    path.write_text("<project><calibration><camera id='0'>1 2 3</camera></calibration></project>")
    with pytest.raises(BadInputError, match="eight intrinsic values"):
        read_vic3d_calibration(path)
    with pytest.raises(BadInputError, match="looks like a VIC-3D calibration"):
        read_calibration(path)


def test_import_calibration_cli(tmp_path, rig, capsys):
    from jointwear.cli import main

    path = tmp_path / "cal.xml"
    path.write_text(_vic_xml(rig.calibration, (640, 512)))
    out = tmp_path / "imported.nc"
    assert (
        main(["dic", "import-calibration", str(path), "--format", "vic3d", "--out", str(out)]) == 0
    )
    cal = read_calibration(out)
    X = np.array([[0.3, 0.2, 0.0]])
    assert np.allclose(cal.right.project(X), rig.calibration.right.project(X), atol=1e-6)
    assert cal.source == "vic3d:cal.xml"
    # OpenCV files need the unit of T: exit code 3 and a message saying so
    assert main(["dic", "import-calibration", str(path), "--format", "opencv"]) == 3
    assert "--length-unit is required" in capsys.readouterr().err
