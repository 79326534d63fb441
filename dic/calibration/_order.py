"""One corner order for both cameras of a stereo calibration view.

A chessboard detector returns the inner-corner grid in an order it chooses per image: the same
board may come back starting at either end (a 180 degree relabelling), and a square grid in any
of four rotations. Each camera calibrated on its own does not care, but ``stereoCalibrate``
pairs corner ``j`` of the left list with corner ``j`` of the right list; if one camera's list is
relabelled, the pair describes two different board poses and the calibration comes out wrong
(RMS of tens of pixels, a baseline of many board lengths) without any error.

The order is fixed here by geometry, not by where the corners fall in each image: every camera
is calibrated on its own, each view's right-camera pose is computed for every relabelling the
board's symmetry allows, and the relabelling whose left-to-right pose agrees with the consensus
of all views is kept. A view for which no relabelling agrees (a mismatched pair, swapped files,
a board that moved between the two exposures) is rejected by name.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["grid_symmetries", "PairPose", "consistent_order"]

#: Largest rotation between a view's left-to-right rotation and the consensus [degree]: far
#: above the scatter of per-view poses of a usable calibration (< 1-2 degrees), far below the
#: 90/180 degrees of a wrong relabelling and the 20-45 degrees between the board poses of
#: different views (a mismatched pair).
MAX_ROTATION_DEG = 10.0
#: Largest distance between a view's left-to-right translation and the consensus, relative.
MAX_TRANSLATION_REL = 0.25


def grid_symmetries(nx: int, ny: int) -> list[np.ndarray]:
    """Relabellings of a row-major ``nx`` x ``ny`` corner grid that map the grid onto itself
    by an in-plane rotation: identity and 180 degrees, and 90/270 degrees for a square grid.

    Returns
    -------
    list of (nx * ny,) int arrays
        ``perm[j]`` is the detected corner to pair with board corner ``j``.
    """
    idx = np.arange(nx * ny).reshape(ny, nx)
    perms = [idx.ravel(), idx[::-1, ::-1].ravel()]
    if nx == ny:
        perms += [np.rot90(idx, 1).ravel(), np.rot90(idx, 3).ravel()]
    return [np.ascontiguousarray(p) for p in perms]


@dataclass(frozen=True)
class PairPose:
    """Left-to-right pose of one view under one relabelling of the right corners."""

    view: int
    relabel: int
    R: np.ndarray
    T: np.ndarray


def _angle_deg(Ra: np.ndarray, Rb: np.ndarray) -> float:
    c = (np.trace(Ra.T @ Rb) - 1.0) / 2.0
    return float(np.degrees(np.arccos(np.clip(c, -1.0, 1.0))))


def _agrees(a: PairPose, b: PairPose) -> bool:
    scale = max(np.linalg.norm(a.T), np.linalg.norm(b.T), 1e-12)
    return (
        _angle_deg(a.R, b.R) < MAX_ROTATION_DEG
        and np.linalg.norm(a.T - b.T) < MAX_TRANSLATION_REL * scale
    )


def pair_poses(
    obj: np.ndarray,
    left_corners: np.ndarray,
    right_corners: np.ndarray,
    left_cam: tuple[np.ndarray, np.ndarray],
    right_cam: tuple[np.ndarray, np.ndarray],
    perms: list[np.ndarray],
    view: int,
) -> list[PairPose]:
    """Left-to-right pose of one view for each relabelling of the right corners.

    ``left_cam``/``right_cam`` are (camera matrix, distortion) of the cameras calibrated on
    their own.
    """
    import cv2

    def pose(cam, pts):
        ok, rvec, tvec = cv2.solvePnP(
            obj.astype(np.float64), pts.astype(np.float64), cam[0], cam[1],
            flags=cv2.SOLVEPNP_ITERATIVE,
        )  # fmt: skip
        return (cv2.Rodrigues(rvec)[0], tvec.ravel()) if ok else None

    pl = pose(left_cam, left_corners)
    if pl is None:
        return []
    out = []
    for k, perm in enumerate(perms):
        pr = pose(right_cam, right_corners[perm])
        if pr is None:
            continue
        R = pr[0] @ pl[0].T
        out.append(PairPose(view, k, R, pr[1] - R @ pl[1]))
    return out


def consistent_order(candidates: list[list[PairPose]]) -> tuple[list[int | None], PairPose | None]:
    """Choose, per view, the relabelling that agrees with the consensus left-to-right pose.

    Parameters
    ----------
    candidates : list (one per view) of lists of PairPose
        From :func:`pair_poses`.

    Returns
    -------
    relabel : list of int or None
        Index into the symmetries per view; None when no relabelling of that view agrees.
    consensus : PairPose or None
        The candidate pose most views agree with.
    """
    flat = [c for cands in candidates for c in cands]
    best, best_votes, best_spread = None, -1, np.inf
    for c in flat:
        votes = 0
        spread = 0.0
        for cands in candidates:
            agree = [_angle_deg(c.R, d.R) for d in cands if _agrees(c, d)]
            if agree:
                votes += 1
                spread += min(agree)
        if votes > best_votes or (votes == best_votes and spread < best_spread):
            best, best_votes, best_spread = c, votes, spread
    if best is None:
        return [None] * len(candidates), None
    chosen: list[int | None] = []
    for cands in candidates:
        ok = [d for d in cands if _agrees(best, d)]
        chosen.append(min(ok, key=lambda d: _angle_deg(best.R, d.R)).relabel if ok else None)
    return chosen, best
