"""Stereo calibration from images of a chessboard or ChArUco board (OpenCV)."""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import numpy as np

from jointwear.dic._calib import Camera, StereoCalibration, _check_enough_views
from jointwear.errors import BadInputError, CalibrationError

__all__ = ["CalibrationBoard", "calibrate_stereo", "detect_board", "board_world_frame"]


@dataclass(frozen=True)
class CalibrationBoard:
    """A planar calibration target.

    Parameters
    ----------
    kind : {"chessboard", "charuco"}
        Plain chessboard (inner corners found with ``findChessboardCornersSB``) or ChArUco.
    squares_x, squares_y : int
        Number of squares along the board's x (columns) and y (rows); a chessboard of 10 x 7
        squares has 9 x 6 inner corners.
    square_size : float
        Side of one square [m].
    marker_size : float
        Side of the ArUco markers of a ChArUco board [m].
    dictionary : str
        ArUco dictionary of a ChArUco board (``"DICT_5X5_100"``, ...).
    """

    kind: Literal["chessboard", "charuco"] = "chessboard"
    squares_x: int = 10
    squares_y: int = 7
    square_size: float = 0.01
    marker_size: float = 0.0075
    dictionary: str = "DICT_5X5_100"

    def __post_init__(self) -> None:
        if self.kind not in ("chessboard", "charuco"):
            raise BadInputError(f"board kind {self.kind!r}: expected 'chessboard' or 'charuco'")
        if self.squares_x < 3 or self.squares_y < 3:
            raise BadInputError(
                f"board of {self.squares_x} x {self.squares_y} squares is too small; "
                "give the number of squares (not inner corners), at least 3 x 3"
            )
        if not self.square_size > 0:
            raise BadInputError(f"board square_size must be positive [m], got {self.square_size}")
        if self.kind == "charuco" and not 0 < self.marker_size < self.square_size:
            raise BadInputError(
                f"ChArUco marker_size {self.marker_size} m must be between 0 and the square "
                f"size {self.square_size} m"
            )

    @property
    def inner_corners(self) -> tuple[int, int]:
        """(columns, rows) of inner corners."""
        return self.squares_x - 1, self.squares_y - 1

    def object_points(self) -> np.ndarray:
        """Inner-corner positions in the board frame (N, 3) [m], row by row."""
        nx, ny = self.inner_corners
        gx, gy = np.meshgrid(np.arange(1, nx + 1), np.arange(1, ny + 1))
        pts = np.stack([gx.ravel(), gy.ravel(), np.zeros(gx.size)], axis=1)
        return pts * self.square_size

    def _charuco(self, legacy: bool = False):
        """OpenCV's board; ``legacy``: the layout of OpenCV < 4.6 (and of boards printed from
        it), which differs from the current one when ``squares_y`` is even."""
        import cv2

        name = self.dictionary.upper()
        if not hasattr(cv2.aruco, name):
            raise BadInputError(f"ArUco dictionary {self.dictionary!r} is unknown to OpenCV")
        d = cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, name))
        board = cv2.aruco.CharucoBoard(
            (self.squares_x, self.squares_y), self.square_size, self.marker_size, d
        )
        if legacy:
            board.setLegacyPattern(True)
        return board


def detect_board(
    image: np.ndarray, board: CalibrationBoard
) -> tuple[np.ndarray, np.ndarray] | None:
    """Find the board's inner corners in a grey image.

    Returns
    -------
    (ids, corners) or None
        Corner indices into :meth:`CalibrationBoard.object_points` (M,) and their sub-pixel
        image positions (M, 2) [pixel]; None when the board is not found.
    """
    import cv2

    img = np.asarray(image)
    if img.ndim == 3:
        img = cv2.cvtColor(img, cv2.COLOR_BGR2GRAY)
    if img.dtype != np.uint8:
        lo, hi = float(img.min()), float(img.max())
        img = np.clip((img - lo) / max(hi - lo, 1e-12) * 255, 0, 255).astype(np.uint8)
    if board.kind == "chessboard":
        pattern = board.inner_corners
        ok, corners = cv2.findChessboardCornersSB(
            img, pattern, flags=cv2.CALIB_CB_EXHAUSTIVE | cv2.CALIB_CB_ACCURACY
        )
        if not ok or corners is None:
            return None
        corners = corners.reshape(-1, 2).astype(np.float64)
        # OpenCV may return the grid in either of two orders; fix it so that the first corner
        # is the top-left one in the image (the board must not be upside down in either view)
        if (corners[-1] - corners[0]) @ np.array([1.0, 1.0]) < 0:
            corners = corners[::-1].copy()
        return np.arange(len(corners)), corners
    # boards printed from OpenCV < 4.6 (or tools following it) with an even number of rows
    # place their markers differently; their corners sit at the same board positions
    layouts = (False, True) if board.squares_y % 2 == 0 else (False,)
    for legacy in layouts:
        detector = cv2.aruco.CharucoDetector(board._charuco(legacy))
        ch_corners, ch_ids, _, _ = detector.detectBoard(img)
        if ch_ids is not None and len(ch_ids) >= 6:
            return ch_ids.ravel().astype(int), ch_corners.reshape(-1, 2).astype(np.float64)
    return None


def _read_gray(item, what: str) -> np.ndarray:
    import cv2

    if isinstance(item, np.ndarray):
        return item
    path = Path(item)
    img = cv2.imread(str(path), cv2.IMREAD_GRAYSCALE)
    if img is None:
        raise BadInputError(f"{what} image '{path}' could not be read (missing or not an image)")
    return img


def board_world_frame(
    calibration: StereoCalibration,
    left_image: np.ndarray,
    board: CalibrationBoard,
    *,
    description: str | None = None,
) -> StereoCalibration:
    """Use the pose of the board seen in ``left_image`` as the world frame.

    Origin at the board's first inner corner; x along the board's columns (to the right in the
    image for a board seen upright), z normal to the board pointing towards the cameras, y = z x x
    (upwards in the image): with the board lying on the mechanism's plane, columns along the
    mechanism's x, this is the mechanism frame (z = out of plane) shifted to that corner.
    """
    import cv2

    found = detect_board(left_image, board)
    if found is None:
        raise CalibrationError(
            "the board defining the world frame was not found in the given left image; use an "
            "image where the whole board is visible"
        )
    ids, corners = found
    obj = board.object_points()[ids] if board.kind == "chessboard" else _charuco_obj(board)[ids]
    obj = obj - np.array([board.square_size, board.square_size, 0.0])  # origin: first inner corner
    cam = calibration.left
    und = cam.pixels_to_normalized(corners)
    ok, rvec, tvec = cv2.solvePnP(
        obj.astype(np.float64),
        und.astype(np.float64),
        np.eye(3),
        None,
        flags=cv2.SOLVEPNP_ITERATIVE,
    )
    if not ok:
        raise CalibrationError("could not compute the board pose for the world frame")
    R_cb = cv2.Rodrigues(rvec)[0]  # board -> left camera
    if R_cb[2, 2] > 0:  # board z points away from the camera: turn the frame so z faces it
        R_cb = R_cb @ np.diag([1.0, -1.0, -1.0])
    # board -> old world: X_old = R_l^T (R_cb X_b + t_cb - t_l)
    R_wn = cam.rotation.T @ R_cb
    t_wn = cam.rotation.T @ (tvec.ravel() - cam.translation)
    return calibration.with_world_frame(
        R_wn,
        t_wn,
        description
        or "calibration board frame (origin at the first inner corner, x along the columns, "
        "z normal to the board towards the cameras, y = z x x)",
    )


def _charuco_obj(board: CalibrationBoard) -> np.ndarray:
    return np.asarray(board._charuco().getChessboardCorners(), dtype=float).reshape(-1, 3)


def calibrate_stereo(
    left_images: Sequence | Iterable,
    right_images: Sequence | Iterable,
    board: CalibrationBoard,
    *,
    min_views: int = 6,
    max_view_rms: float = 1.0,
    fix_k3: bool = False,
    rational: bool = False,
    world_view: int | None = None,
) -> StereoCalibration:
    """Calibrate a camera pair from simultaneous views of a board.

    Each camera is first calibrated on its own (``cv2.calibrateCameraExtended``); views whose
    reprojection RMS exceeds ``max_view_rms`` are rejected and the calibration is repeated; then
    ``cv2.stereoCalibrate`` refines intrinsics and the relative pose on the views both cameras
    saw (``CALIB_USE_INTRINSIC_GUESS``).

    Parameters
    ----------
    left_images, right_images : sequences of arrays or paths
        Simultaneous views (same length, same order).
    board : CalibrationBoard
        The target.
    min_views : int
        Fewest usable views accepted (:class:`~jointwear.errors.CalibrationError` below).
    max_view_rms : float
        Views with a larger per-camera reprojection RMS are rejected [pixel].
    fix_k3, rational : bool
        Fix k3 to zero; use the rational model (k4..k6).
    world_view : int, optional
        Index of a view whose board pose becomes the world frame (z normal to the board).
        Default: the left camera frame.

    Returns
    -------
    StereoCalibration
        With overall RMS, per-view RMS and the counts of used/rejected views.
    """
    import cv2

    left_images = list(left_images)
    right_images = list(right_images)
    if len(left_images) != len(right_images):
        raise BadInputError(
            f"calibration needs simultaneous left/right views: got {len(left_images)} left and "
            f"{len(right_images)} right images; give the same number, in the same order"
        )
    n_total = len(left_images)
    obj_all = board.object_points() if board.kind == "chessboard" else _charuco_obj(board)
    views = []  # (index, obj, left_pts, right_pts)
    reasons: list[str] = []
    size = None
    for i, (li, ri) in enumerate(zip(left_images, right_images, strict=True)):
        L = _read_gray(li, "left calibration")
        Rimg = _read_gray(ri, "right calibration")
        if size is None:
            size = (L.shape[1], L.shape[0])
        if (L.shape[1], L.shape[0]) != size or (Rimg.shape[1], Rimg.shape[0]) != size:
            raise BadInputError(
                f"calibration view {i}: image size {L.shape[1]}x{L.shape[0]} / "
                f"{Rimg.shape[1]}x{Rimg.shape[0]} differs from the first view's {size[0]}x{size[1]}"
            )
        fl, fr = detect_board(L, board), detect_board(Rimg, board)
        if fl is None or fr is None:
            which = (
                "both cameras" if fl is None and fr is None else ("left" if fl is None else "right")
            )
            reasons.append(f"view {i}: board not found ({which})")
            continue
        common = np.intersect1d(fl[0], fr[0])
        if len(common) < 6:
            reasons.append(f"view {i}: only {len(common)} corners seen by both cameras")
            continue
        li_idx = np.searchsorted(fl[0], common)
        ri_idx = np.searchsorted(fr[0], common)
        views.append((i, obj_all[common], fl[1][li_idx], fr[1][ri_idx]))
    _check_enough_views(len(views), n_total, min_views, reasons)

    flags = cv2.CALIB_FIX_K3 if fix_k3 else 0
    if rational:
        flags |= cv2.CALIB_RATIONAL_MODEL
    crit = (cv2.TERM_CRITERIA_COUNT + cv2.TERM_CRITERIA_EPS, 200, 1e-12)

    def mono(k: int, sel):
        objp = [v[1].astype(np.float32) for v in sel]
        imgp = [v[2 + k].astype(np.float32).reshape(-1, 1, 2) for v in sel]
        rms, K, D, _, _, _, _, per_view = cv2.calibrateCameraExtended(
            objp, imgp, size, None, None, flags=flags, criteria=crit
        )
        return K, D, per_view.ravel()

    for _ in range(2):
        KL, DL, pv_l = mono(0, views)
        KR, DR, pv_r = mono(1, views)
        bad = (pv_l > max_view_rms) | (pv_r > max_view_rms)
        if not np.any(bad):
            break
        for j in np.flatnonzero(bad):
            reasons.append(
                f"view {views[j][0]}: reprojection RMS {pv_l[j]:.2f}/{pv_r[j]:.2f} px > {max_view_rms}"
            )
        views = [v for v, b in zip(views, bad, strict=True) if not b]
        _check_enough_views(len(views), n_total, min_views, reasons)

    objp = [v[1].astype(np.float32) for v in views]
    lp = [v[2].astype(np.float32).reshape(-1, 1, 2) for v in views]
    rp = [v[3].astype(np.float32).reshape(-1, 1, 2) for v in views]
    sflags = flags | cv2.CALIB_USE_INTRINSIC_GUESS
    out = cv2.stereoCalibrateExtended(
        objp, lp, rp, KL, DL, KR, DR, size, None, None, flags=sflags, criteria=crit
    )
    rms, KL, DL, KR, DR, R, T = out[:7]
    per_view = np.asarray(out[-1]).reshape(len(views), 2)
    left = Camera(KL, DL.ravel(), np.eye(3), np.zeros(3), size)
    right = Camera(KR, DR.ravel(), R, T.ravel(), size)
    cal = StereoCalibration(
        left,
        right,
        rms=float(rms),
        per_view_rms=per_view,
        views_used=len(views),
        views_rejected=n_total - len(views),
        source="jointwear calibrate",
        rejected=tuple(reasons),
    )
    if world_view is not None:
        if not 0 <= world_view < n_total:
            raise BadInputError(f"world_view {world_view} is outside the {n_total} views")
        cal = board_world_frame(cal, _read_gray(left_images[world_view], "left"), board)
    return cal
