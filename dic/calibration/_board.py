"""Stereo calibration from images of a chessboard or ChArUco board (OpenCV)."""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import numpy as np

from jointwear.dic.calibration._camera import Camera, StereoCalibration, _check_enough_views
from jointwear.dic.calibration._defaults import (
    BOARD_KIND,
    BOARD_SQUARES,
    CHARUCO_DICTIONARY,
    MAX_RMS_PX,
    MAX_VIEW_RMS_PX,
    MIN_VIEWS,
)
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
    length_unit : {"m", "square"}
        Unit of ``square_size`` and ``marker_size``: metres, or ``"square"`` for a board of
        unknown size (``square_size = 1``; the calibration's lengths are then in squares).
    square_size_u : float, optional
        Standard uncertainty of ``square_size`` (same unit), e.g. from measuring the printed
        board; None: not assessed.
    """

    kind: Literal["chessboard", "charuco"] = BOARD_KIND
    squares_x: int = BOARD_SQUARES[0]
    squares_y: int = BOARD_SQUARES[1]
    square_size: float = 0.01
    marker_size: float = 0.0075
    dictionary: str = CHARUCO_DICTIONARY
    length_unit: str = "m"
    square_size_u: float | None = None

    def __post_init__(self) -> None:
        if self.length_unit not in ("m", "square"):
            raise BadInputError(f"board length_unit {self.length_unit!r}: expected 'm' or 'square'")
        if self.square_size_u is not None and not self.square_size_u >= 0:
            raise BadInputError(f"board square_size_u must be >= 0, got {self.square_size_u}")
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


def detect_board(image: np.ndarray, board: CalibrationBoard, *, with_detector: bool = False):
    """Find the board's inner corners in a grey image.

    Chessboards are searched with OpenCV's sector-based detector, then with the classic one.

    Returns
    -------
    (ids, corners) or None
        Corner indices into :meth:`CalibrationBoard.object_points` (M,) and their sub-pixel
        image positions (M, 2) [pixel]; None when the board is not found. With
        ``with_detector``, a third element names the detector that found the board.
    """
    import cv2

    img = np.asarray(image)
    if img.ndim == 3:
        img = cv2.cvtColor(img, cv2.COLOR_BGR2GRAY)
    if img.dtype != np.uint8:
        lo, hi = float(img.min()), float(img.max())
        img = np.clip((img - lo) / max(hi - lo, 1e-12) * 255, 0, 255).astype(np.uint8)
    if board.kind == "chessboard":
        found = _find_chessboard(img, board.inner_corners)
        if found is None:
            return None
        corners, detector = found
        # OpenCV may return the grid in either of two orders; fix it so that the first corner
        # is the top-left one in this image (a convention for a single image, such as the
        # world-frame view; the two cameras of a calibration pair are made consistent by
        # geometry, see jointwear.dic.calibration._order)
        if (corners[-1] - corners[0]) @ np.array([1.0, 1.0]) < 0:
            corners = corners[::-1].copy()
        return (
            (np.arange(len(corners)), corners, detector)
            if with_detector
            else (np.arange(len(corners)), corners)
        )
    # boards printed from OpenCV < 4.6 (or tools following it) with an even number of rows
    # place their markers differently; their corners sit at the same board positions
    layouts = (False, True) if board.squares_y % 2 == 0 else (False,)
    for legacy in layouts:
        detector = cv2.aruco.CharucoDetector(board._charuco(legacy))
        ch_corners, ch_ids, _, _ = detector.detectBoard(img)
        if ch_ids is not None and len(ch_ids) >= 6:
            ids = ch_ids.ravel().astype(int)
            pts = ch_corners.reshape(-1, 2).astype(np.float64)
            return (ids, pts, "charuco") if with_detector else (ids, pts)
    return None


def _check_square_count(board: CalibrationBoard, missed: list[np.ndarray]) -> None:
    """Too few views found the chessboard: if the images show a board with one more square each
    way, the count given was the inner corners' (``--squares 9 6`` for a 10 x 7 board): say so."""
    if board.kind != "chessboard" or not missed:
        return
    bigger = (board.squares_x + 1, board.squares_y + 1)
    pattern = (bigger[0] - 1, bigger[1] - 1)
    if any(_find_chessboard(img, pattern) is not None for img in missed):
        raise CalibrationError(
            f"the board was not found as {board.squares_x} x {board.squares_y} squares "
            f"({board.squares_x - 1} x {board.squares_y - 1} inner corners), but these images "
            f"show one of {bigger[0]} x {bigger[1]} squares ({board.squares_x} x "
            f"{board.squares_y} inner corners): --squares counts squares, not inner corners; "
            f"give --squares {bigger[0]} {bigger[1]}"
        )


def _find_chessboard(img: np.ndarray, pattern: tuple[int, int]):
    """Inner corners (N, 2) [pixel] and the detector that found them, or None.

    The sector-based detector (``findChessboardCornersSB``) first; where it finds no board, the
    classic detector (``findChessboardCorners`` with sub-pixel refinement), which finds some
    boards the former misses (strong perspective, JPEG artefacts, a board touching the edge).
    """
    import cv2

    ok, corners = cv2.findChessboardCornersSB(
        img, pattern, flags=cv2.CALIB_CB_EXHAUSTIVE | cv2.CALIB_CB_ACCURACY
    )
    if ok and corners is not None:
        return corners.reshape(-1, 2).astype(np.float64), "sector-based"
    flags = cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE
    ok, corners = cv2.findChessboardCorners(img, pattern, flags=flags)
    if not ok or corners is None:
        return None
    # refinement window: a third of the smallest corner spacing, at most 11 px
    c = corners.reshape(-1, 2)
    grid = c.reshape(pattern[1], pattern[0], 2)
    spacing = min(
        np.min(np.linalg.norm(np.diff(grid, axis=1), axis=2)),
        np.min(np.linalg.norm(np.diff(grid, axis=0), axis=2)),
    )
    win = int(np.clip(spacing / 3, 2, 11))
    crit = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_COUNT, 100, 1e-4)
    corners = cv2.cornerSubPix(img, corners.astype(np.float32), (win, win), (-1, -1), crit)
    return corners.reshape(-1, 2).astype(np.float64), "classic"


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


def _view_name(li, ri, i: int) -> str:
    if isinstance(li, (str, Path)) and isinstance(ri, (str, Path)):
        return f"{Path(li).name} / {Path(ri).name}"
    return f"view {i}"


def calibrate_stereo(
    left_images: Sequence | Iterable,
    right_images: Sequence | Iterable,
    board: CalibrationBoard,
    *,
    min_views: int = MIN_VIEWS,
    max_view_rms: float = MAX_VIEW_RMS_PX,
    fix_k3: bool = False,
    rational: bool = False,
    world_view: int | None = None,
    max_rms: float = MAX_RMS_PX,
    accept_poor: bool = False,
    view_names: Sequence[str] | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> StereoCalibration:
    """Calibrate a camera pair from simultaneous views of a board.

    ``progress(done, total)`` is called after the board search of each view pair (the slow
    part), for a progress display.

    Boards are found with both of OpenCV's chessboard detectors (sector-based, then classic).
    The corner order of the two cameras is made consistent by geometry
    (:mod:`jointwear.dic.calibration._order`): a view whose left and right images do not show the
    board in the pose the other views agree on is rejected. Each camera is then calibrated on
    its own (``cv2.calibrateCameraExtended``); views whose reprojection RMS exceeds
    ``max_view_rms`` are rejected and the calibration is repeated; then ``cv2.stereoCalibrate``
    refines intrinsics and the relative pose (``CALIB_USE_INTRINSIC_GUESS``). Finally the result
    passes a sanity gate (:func:`~jointwear.dic.calibration._gate.check_calibration`): stereo RMS,
    field of view, pixel aspect, principal point, baseline against the board distance, and
    which side the right camera is on.

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
    max_rms : float
        Largest acceptable stereo reprojection RMS [pixel] (sanity gate).
    accept_poor : bool
        Return a calibration that fails the sanity gate (its ``status`` says so) instead of
        raising :class:`~jointwear.dic.calibration._gate.PoorCalibration`.
    view_names : sequence of str, optional
        Names of the views in messages and in the per-view table; default: the image file
        names, or ``"view <i>"`` for arrays.

    Returns
    -------
    StereoCalibration
        With overall RMS, per-view RMS (with the view names), the counts of used/rejected
        views and the relative length uncertainty (baseline scatter over the views, and the
        square size uncertainty when given).

    Raises
    ------
    CalibrationError
        Too few usable views (exit code 3).
    PoorCalibration
        The result failed the sanity gate (exit code 1; the result is attached).
    """
    import cv2

    left_images = list(left_images)
    right_images = list(right_images)
    names = _view_names(left_images, right_images, view_names)
    n_total = len(names)
    obj_all = board.object_points() if board.kind == "chessboard" else _charuco_obj(board)
    reasons: list[str] = []
    views, missed, size = _detect_views(
        left_images, right_images, board, obj_all, names, reasons, progress
    )
    if len(views) < min_views:
        _check_square_count(board, missed)
    _check_enough_views(len(views), n_total, min_views, reasons)

    flags = cv2.CALIB_FIX_K3 if fix_k3 else 0
    if rational:
        flags |= cv2.CALIB_RATIONAL_MODEL
    mono = _MonoCalibration(size, flags)
    views, pair_T = _consistent_views(views, board, obj_all, names, reasons, mono, min_views)
    _check_enough_views(len(views), n_total, min_views, reasons)
    views, pair_T, (KL, DL, KR, DR) = _reject_poor_views(
        views, pair_T, mono, max_view_rms, names, reasons, n_total, min_views
    )

    objp = [v[1].astype(np.float32) for v in views]
    lp = [v[2].astype(np.float32).reshape(-1, 1, 2) for v in views]
    rp = [v[3].astype(np.float32).reshape(-1, 1, 2) for v in views]
    sflags = flags | cv2.CALIB_USE_INTRINSIC_GUESS
    out = cv2.stereoCalibrateExtended(
        objp, lp, rp, KL, DL, KR, DR, size, None, None, flags=sflags, criteria=mono.criteria
    )
    rms, KL, DL, KR, DR, R, T = out[:7]
    per_view = np.asarray(out[-1]).reshape(len(views), 2)
    board_dist = []
    for v in views:  # distance of the board from the left camera (baseline plausibility)
        ok, _, tvec = cv2.solvePnP(v[1].astype(np.float64), v[2].astype(np.float64), KL, DL)
        if ok:
            board_dist.append(float(np.linalg.norm(tvec)))
    left = Camera(KL, DL.ravel(), np.eye(3), np.zeros(3), size)
    right = Camera(KR, DR.ravel(), R, T.ravel(), size)
    u_rel = _length_u_rel(np.asarray(pair_T), board)
    cal = StereoCalibration(
        left,
        right,
        rms=float(rms),
        per_view_rms=per_view,
        views_used=len(views),
        views_rejected=n_total - len(views),
        source="jointwear calibrate",
        rejected=tuple(reasons),
        view_names=tuple(names[v[0]] for v in views),
        length_unit=board.length_unit,
        length_scale_u_rel=u_rel,
    )
    if world_view is not None:
        if not 0 <= world_view < n_total:
            raise BadInputError(f"world_view {world_view} is outside the {n_total} views")
        cal = board_world_frame(cal, _read_gray(left_images[world_view], "left"), board)
    return _sanity_gate(cal, max_rms, board_dist, accept_poor)


def _view_names(left_images: list, right_images: list, view_names) -> list[str]:
    """The views' names (given, or from the image files); checks the two lists pair up."""
    if len(left_images) != len(right_images):
        raise BadInputError(
            f"calibration needs simultaneous left/right views: got {len(left_images)} left and "
            f"{len(right_images)} right images; give the same number, in the same order"
        )
    n_total = len(left_images)
    names = (
        list(view_names)
        if view_names is not None
        else [
            _view_name(li, ri, i)
            for i, (li, ri) in enumerate(zip(left_images, right_images, strict=True))
        ]
    )
    if len(names) != n_total:
        raise BadInputError(f"view_names: {len(names)} names for {n_total} views")
    return names


def _detect_views(left_images, right_images, board, obj_all, names, reasons, progress):
    """The board's corners seen by both cameras in every view pair: ``views`` (index, object
    points, left points, right points), a few images where the board was not found, and the
    image size; the views without the board are counted in ``reasons``."""
    views = []  # (index, obj, left_pts, right_pts)
    missed: list[np.ndarray] = []  # a few images where the board was not found
    size = None
    for i, (li, ri) in enumerate(zip(left_images, right_images, strict=True)):
        L = _read_gray(li, "left calibration")
        Rimg = _read_gray(ri, "right calibration")
        if size is None:
            size = (L.shape[1], L.shape[0])
        if (L.shape[1], L.shape[0]) != size or (Rimg.shape[1], Rimg.shape[0]) != size:
            raise BadInputError(
                f"calibration view {names[i]}: image size {L.shape[1]}x{L.shape[0]} / "
                f"{Rimg.shape[1]}x{Rimg.shape[0]} differs from the first view's {size[0]}x{size[1]}"
            )
        fl, fr = detect_board(L, board), detect_board(Rimg, board)
        if progress is not None:
            progress(i + 1, len(names))
        if fl is None or fr is None:
            which = (
                "both cameras" if fl is None and fr is None else ("left" if fl is None else "right")
            )
            reasons.append(f"{names[i]}: board not found ({which}) by either detector")
            if len(missed) < 3:
                missed.append(L if fl is None else Rimg)
            continue
        common = np.intersect1d(fl[0], fr[0])
        if len(common) < 6:
            reasons.append(f"{names[i]}: only {len(common)} corners seen by both cameras")
            continue
        li_idx = np.searchsorted(fl[0], common)
        ri_idx = np.searchsorted(fr[0], common)
        views.append((i, obj_all[common], fl[1][li_idx], fr[1][ri_idx]))
    return views, missed, size


class _MonoCalibration:
    """One camera calibrated on its own (``cv2.calibrateCameraExtended``) over given views."""

    def __init__(self, size, flags: int):
        import cv2

        self.size, self.flags = size, flags
        #: termination criteria, shared with the stereo calibration
        self.criteria = (cv2.TERM_CRITERIA_COUNT + cv2.TERM_CRITERIA_EPS, 200, 1e-12)

    def __call__(self, k: int, sel):
        """Camera ``k`` (0 left, 1 right): matrix, distortion and per-view RMS [pixel]."""
        import cv2

        objp = [v[1].astype(np.float32) for v in sel]
        imgp = [v[2 + k].astype(np.float32).reshape(-1, 1, 2) for v in sel]
        rms, K, D, _, _, _, _, per_view = cv2.calibrateCameraExtended(
            objp, imgp, self.size, None, None, flags=self.flags, criteria=self.criteria
        )
        return K, D, per_view.ravel()


def _consistent_views(views, board, obj_all, names, reasons, mono, min_views):
    """One corner order for both cameras: the relabelling of the right corners whose
    left-to-right pose agrees with the other views. Returns the views kept (right corners
    relabelled) and each one's baseline length from its own pose."""
    from jointwear.dic.calibration._order import consistent_order, grid_symmetries, pair_poses

    KL, DL, _ = mono(0, views)
    KR, DR, _ = mono(1, views)
    perms_full = grid_symmetries(*board.inner_corners) if board.kind == "chessboard" else None
    cands = []
    for v in views:
        perms = perms_full if perms_full is not None and len(v[1]) == len(obj_all) else None
        perms = perms or [np.arange(len(v[1]))]
        cands.append(pair_poses(v[1], v[2], v[3], (KL, DL), (KR, DR), perms, v[0]))
    relabel, _ = consistent_order(cands)
    kept, pair_T = [], []
    for v, k, cs in zip(views, relabel, cands, strict=True):
        if k is None:
            reasons.append(
                f"{names[v[0]]}: the left and right images do not show the board in the pose "
                "the other views agree on (mismatched or swapped pair, or the board moved "
                "between the two exposures)"
            )
            continue
        perm = perms_full[k] if perms_full is not None and len(v[1]) == len(obj_all) else None
        kept.append(v if perm is None else (v[0], v[1], v[2], v[3][perm]))
        pair_T.append(np.linalg.norm(next(c.T for c in cs if c.relabel == k)))
    n_disagree = len(views) - len(kept)
    if len(kept) < min_views and n_disagree >= len(views) / 2:
        raise CalibrationError(
            f"in {n_disagree} of {len(views)} views the left and right images do not show the "
            "board in one common pose: the two image lists are not simultaneous pairs in the "
            "same order (check that both folders hold the same views sorted alike, and that "
            f"--left/--right are not mixed up); e.g. {reasons[-1]}"
        )
    return kept, pair_T


def _reject_poor_views(views, pair_T, mono, max_view_rms, names, reasons, n_total, min_views):
    """Calibrate each camera, reject the views whose reprojection RMS exceeds
    ``max_view_rms`` and calibrate again (twice at most). Returns the views and baselines
    kept and the cameras' matrices and distortions ``(KL, DL, KR, DR)``."""
    for _ in range(2):
        KL, DL, pv_l = mono(0, views)
        KR, DR, pv_r = mono(1, views)
        bad = (pv_l > max_view_rms) | (pv_r > max_view_rms)
        if not np.any(bad):
            break
        for j in np.flatnonzero(bad):
            reasons.append(
                f"{names[views[j][0]]}: reprojection RMS {pv_l[j]:.2f}/{pv_r[j]:.2f} px > "
                f"{max_view_rms} (--max-view-rms)"
            )
        pair_T = [t for t, b in zip(pair_T, bad, strict=True) if not b]
        views = [v for v, b in zip(views, bad, strict=True) if not b]
        _check_enough_views(len(views), n_total, min_views, reasons)
    return views, pair_T, (KL, DL, KR, DR)


def _sanity_gate(cal, max_rms, board_dist, accept_poor) -> StereoCalibration:
    """``cal`` if it passes the sanity gate; else refused (:class:`PoorCalibration`), or with
    ``accept_poor`` returned with a status that says so."""
    import dataclasses

    from jointwear.dic.calibration._gate import PoorCalibration, check_calibration

    problems = check_calibration(
        cal, max_rms=max_rms, board_distance=float(np.median(board_dist)) if board_dist else None
    )
    if not problems:
        return cal
    if not accept_poor:
        bad = dataclasses.replace(cal, status="rejected: " + "; ".join(problems))
        raise PoorCalibration(
            "the stereo calibration is not plausible: "
            + "; ".join(problems)
            + ". Check that --left and --right are the right cameras, that the views are "
            "simultaneous pairs in the same order, and --squares; accept it anyway with "
            "--accept-poor",
            bad,
            tuple(problems),
        )
    return dataclasses.replace(cal, status="accepted with --accept-poor: " + "; ".join(problems))


def _length_u_rel(pair_T: np.ndarray, board: CalibrationBoard) -> float | None:
    """Relative standard uncertainty of lengths: the standard error of the baseline over the
    views (each view's left-to-right translation from the cameras calibrated on their own),
    combined with the square size's relative uncertainty when it is known."""
    if len(pair_T) < 3:
        return None
    u_b = float(np.std(pair_T, ddof=1) / np.sqrt(len(pair_T)) / np.mean(pair_T))
    if board.square_size_u is None:
        return u_b
    return float(np.hypot(u_b, board.square_size_u / board.square_size))
