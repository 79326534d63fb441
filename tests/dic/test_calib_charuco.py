"""ChArUco calibration on the virtual rig, in OpenCV's current and legacy (< 4.6) layouts."""

from __future__ import annotations

import numpy as np
import pytest

from jointwear.datasets.rig import RigConfig, VirtualRig
from jointwear.dic.calibration._board import CalibrationBoard, calibrate_stereo, detect_board
from jointwear.errors import BadInputError


@pytest.mark.parametrize("legacy", [False, True])
def test_charuco_calibration_recovers_the_cameras(legacy):
    # 960 x 768 px over the study-like 0.42 m field of view: 57 px squares, 6 px marker cells
    rig = VirtualRig(
        RigConfig(width=960, height=768, board_kind="charuco", board_views=8, board_legacy=legacy)
    )
    views = rig.board_images()
    board = CalibrationBoard("charuco", 10, 8, 0.025, 0.01875, "DICT_5X5_100")
    # every view is found, all 63 inner corners (a board of the other layout would give none)
    assert [len(detect_board(v[0], board)[0]) for v in views] == [63] * len(views)
    cal = calibrate_stereo(
        [v[0] for v in views], [v[1] for v in views], board, world_view=len(views) - 1
    )
    true = rig.calibration
    assert cal.views_used == len(views) and cal.rms < 0.1
    for name in ("left", "right"):
        err = np.array(cal.cameras[name].focal) / np.array(true.cameras[name].focal) - 1
        assert np.all(np.abs(err) < 2e-3)
    assert abs(cal.baseline / true.baseline - 1) < 2e-3
    # world frame = the last board view: a mechanism point projects where the true cameras put it
    X = np.array([[0.30, 0.20, 0.0], [0.25, 0.12, 0.01]])
    for name in ("left", "right"):
        got = cal.cameras[name].project(X - rig.world_board_origin())
        assert np.allclose(got, true.cameras[name].project(X), atol=0.1)


def test_board_kind_is_checked():
    with pytest.raises(
        BadInputError,
        match=r"rig\.board_kind: expected one of \['chessboard', 'charuco'\], got 'circles'",
    ):
        RigConfig(board_kind="circles")
