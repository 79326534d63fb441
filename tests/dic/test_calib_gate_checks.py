"""Each check of the calibration sanity gate, on constructed calibrations: the numbers of the
silently wrong real calibration (issue: RMS 31 px, baseline 85 squares, focal 144/3626 px)
and a plausible one."""

from __future__ import annotations

import numpy as np

from jointwear.dic.calibration._camera import Camera, StereoCalibration
from jointwear.dic.calibration._gate import check_calibration, view_table


def _cal(f_left=800.0, f_right=805.0, baseline=3.34, rms=0.3, cx=320.0, aspect=1.0, side=1.0):
    def K(f, c):
        return np.array([[f, 0, c], [0, f * aspect, 240.0], [0, 0, 1.0]])

    ang = np.deg2rad(8.0) * side
    R = np.array([[np.cos(ang), 0, -np.sin(ang)], [0, 1, 0], [np.sin(ang), 0, np.cos(ang)]])
    centre_right = np.array([side * baseline, 0.0, 0.0])  # in the left camera frame
    left = Camera(K(f_left, cx), np.zeros(5), np.eye(3), np.zeros(3), (640, 480))
    right = Camera(K(f_right, 320.0), np.zeros(5), R, -R @ centre_right, (640, 480))
    return StereoCalibration(
        left, right, rms=rms, per_view_rms=np.full((2, 2), rms), views_used=2,
        view_names=("left01.jpg / right01.jpg", "left02.jpg / right02.jpg"),
        rejected=("left03.jpg / right03.jpg: board not found (left) by either detector",),
    )  # fmt: skip


def test_plausible_calibration_passes():
    # lengths in squares, the board ~30 squares away
    assert check_calibration(_cal(), board_distance=30.0) == []


def test_the_silently_wrong_real_calibration_is_refused():
    problems = check_calibration(
        _cal(f_left=144.0, f_right=3626.0, baseline=85.0, rms=31.0), board_distance=30.0
    )
    text = "\n".join(problems)
    assert "RMS 31 px exceeds 1 px" in text
    assert "left camera: focal length 144.0 px gives a 131.5 degree field of view" in text
    assert "differ by more than 3x" in text
    assert "baseline 85 is 2.83 times the board distance" in text


def test_each_check():
    def only(cal, **kw):
        return "\n".join(check_calibration(cal, **kw))

    assert "exceeds 0.2 px (--max-rms)" in only(_cal(rms=0.3), max_rms=0.2)
    assert "fx 800.0 px and fy 880.0 px differ by 9%" in only(_cal(aspect=1.1))
    assert "principal point (20, 240) px is far from the centre" in only(_cal(cx=20.0))
    assert "baseline 0.1 is 0.00333 times the board distance 30" in only(
        _cal(baseline=0.1), board_distance=30.0
    )
    assert "right camera sits to the LEFT" in only(_cal(side=-1.0))
    assert check_calibration(_cal(side=1.0)) == []


def test_view_table_names_files():
    lines = view_table(_cal())
    assert lines[1].split()[:3] == ["left01.jpg", "/", "right01.jpg"]
    assert (
        lines[-1]
        == "  rejected left03.jpg / right03.jpg: board not found (left) by either detector"
    )
