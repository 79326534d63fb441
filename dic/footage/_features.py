"""Footage tracking: SIFT features and the homography that starts (or restarts) tracking.

Matching is approximate-nearest-neighbour (FLANN, randomised k-d trees) instead of brute force,
and in stereo it is guided by the calibration: the right image's features are detected only in
the band of the right image where the region's epipolar lines fall (:func:`epipolar_band`), and
each left feature takes, among its nearest descriptors, the best one within ``max_epipolar_px``
of its epipolar line, with Lowe's ratio test against the second best there. A 1920 x 1200 pair
that took minutes with brute-force matching of whole-image features takes seconds.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from jointwear.dic.calibration import epipolar_distance

#: candidates per feature in the epipolar-guided matching
_K_CANDIDATES = 8
#: Lowe's ratio (best / second best descriptor distance)
_RATIO = 0.8
#: least share of the matches one homography must explain
_MIN_INLIER_SHARE = 0.25
#: grid step of the epipolar band mask [pixel]
_BAND_STEP = 16


def _sift_features(
    img: np.ndarray,
    poly: np.ndarray | None = None,
    margin: int = 10,
    *,
    mask: np.ndarray | None = None,
):
    """SIFT keypoints and descriptors of ``img`` (inside ``poly`` grown by ``margin`` px, or
    where the full-size ``mask`` is non-zero)."""
    import cv2

    h, w = img.shape
    if poly is None and mask is None:
        return cv2.SIFT_create().detectAndCompute(_as_uint8(img), None)
    # the region's bounding box only (a mask alone still builds the whole image's pyramid)
    if poly is not None:
        pad = margin + 16
        x0, y0 = np.clip(np.floor(poly.min(0)).astype(int) - pad, 0, None)
        x1, y1 = np.ceil(poly.max(0)).astype(int) + pad + 1
        x1, y1 = min(x1, w), min(y1, h)
        sub = np.zeros((y1 - y0, x1 - x0), np.uint8)
        cv2.fillPoly(sub, [np.rint(poly - [x0, y0]).astype(np.int32)], 255)
        sub = cv2.dilate(sub, np.ones((2 * margin + 1,) * 2, np.uint8))
    else:
        ys, xs = np.nonzero(mask)
        if len(xs) == 0:
            return (), None
        x0, y0 = max(int(xs.min()) - 16, 0), max(int(ys.min()) - 16, 0)
        x1, y1 = min(int(xs.max()) + 17, w), min(int(ys.max()) + 17, h)
        sub = np.ascontiguousarray(mask[y0:y1, x0:x1])
    kps, desc = cv2.SIFT_create().detectAndCompute(_as_uint8(img[y0:y1, x0:x1]), sub)
    for kp in kps:
        kp.pt = (kp.pt[0] + x0, kp.pt[1] + y0)
    return kps, desc


def _as_uint8(img: np.ndarray) -> np.ndarray:
    """8-bit copy for feature detection: 8-bit as is, deeper images (12/16 bit) scaled by
    their largest value instead of clipped at 255."""
    if img.dtype == np.uint8:
        return img
    a = np.nan_to_num(np.asarray(img, dtype=np.float32))
    top = float(a.max(initial=0.0))
    if top > 255.0:
        a = a * (255.0 / top)
    return np.clip(a, 0, 255).astype(np.uint8)


def epipolar_band(
    calibration, polygons: list[np.ndarray], shape: tuple[int, int], band_px: float
) -> np.ndarray:
    """Mask (uint8, image ``shape``) of the right-image pixels whose epipolar line in the left
    image passes within ``band_px`` of one of the left ``polygons`` (whatever the depth):
    where the regions' matches can lie. Computed on a 16-pixel grid and dilated by a cell.
    """
    import cv2

    from jointwear.dic.calibration import undistorted_pixels as _undistorted_pixels

    h, w = shape
    gx = np.arange(0, w + _BAND_STEP, _BAND_STEP, dtype=float)
    gy = np.arange(0, h + _BAND_STEP, _BAND_STEP, dtype=float)
    X, Y = np.meshgrid(np.minimum(gx, w - 1), np.minimum(gy, h - 1))
    ur = _undistorted_pixels(calibration.right, np.column_stack([X.ravel(), Y.ravel()]))
    F = calibration.fundamental_matrix()
    lines = np.column_stack([ur, np.ones(len(ur))]) @ F  # epipolar lines in the left image
    norm = np.hypot(lines[:, 0], lines[:, 1])
    inside = np.zeros(len(ur), dtype=bool)
    # the grid cell's own extent and distortion: a margin of a cell's diagonal in the left image
    margin = band_px + _BAND_STEP * 1.5
    for poly in polygons:
        pl = _undistorted_pixels(calibration.left, np.asarray(poly, dtype=float))
        d = (lines @ np.column_stack([pl, np.ones(len(pl))]).T) / norm[:, None]
        inside |= (d.min(axis=1) <= margin) & (d.max(axis=1) >= -margin)
    coarse = inside.reshape(X.shape).astype(np.uint8) * 255
    coarse = cv2.dilate(coarse, np.ones((3, 3), np.uint8))
    full = cv2.resize(coarse, (len(gx) * _BAND_STEP, len(gy) * _BAND_STEP), cv2.INTER_NEAREST)
    return np.ascontiguousarray(full[:h, :w])


@dataclass
class MatchReport:
    """What a feature matching found (for diagnostics)."""

    features_ref: int = 0
    features_target: int = 0
    matches: int = 0
    epipolar_inliers: int = 0
    homography_inliers: int = 0
    #: median epipolar distance of the matches a homography explains, ignoring the
    #: calibration [pixel]: how far the calibration is off these images (None: not measured)
    measured_epipolar_px: float | None = None


def _knn(d1: np.ndarray, d2: np.ndarray, k: int):
    """``k`` nearest descriptors of ``d2`` for each of ``d1`` (FLANN k-d trees; brute force
    for small sets) as (indices, distances) arrays (n1, k), padded with -1 / inf."""
    import cv2

    d1 = np.ascontiguousarray(d1, dtype=np.float32)
    d2 = np.ascontiguousarray(d2, dtype=np.float32)
    k = min(k, len(d2))
    if len(d1) * len(d2) < 2_000_000:
        matcher = cv2.BFMatcher(cv2.NORM_L2)
    else:
        matcher = cv2.FlannBasedMatcher({"algorithm": 1, "trees": 4}, {"checks": 64})
    idx = np.full((len(d1), k), -1, dtype=np.int64)
    dist = np.full((len(d1), k), np.inf)
    for i, ms in enumerate(matcher.knnMatch(d1, d2, k=k)):
        for j, m in enumerate(ms[:k]):
            idx[i, j], dist[i, j] = m.trainIdx, m.distance
    return idx, dist


def _ratio_pairs(idx: np.ndarray, dist: np.ndarray, allowed: np.ndarray | None = None):
    """Query and train indices passing the ratio test, among the ``allowed`` candidates."""
    ok = idx >= 0 if allowed is None else (idx >= 0) & allowed
    d = np.where(ok, dist, np.inf)
    order = np.argsort(d, axis=1)
    best = np.take_along_axis(d, order[:, :1], axis=1)[:, 0]
    second = (
        np.take_along_axis(d, order[:, 1:2], axis=1)[:, 0]
        if d.shape[1] > 1
        else np.full(len(d), np.inf)
    )
    good = np.isfinite(best) & (best < _RATIO * second)
    if allowed is None:  # plain matching: the second neighbour must exist
        good &= np.isfinite(second)
    q = np.flatnonzero(good)
    return q, np.take_along_axis(idx, order[:, :1], axis=1)[q, 0]


def _sift_homography(
    ref_features,
    target_features,
    *,
    calibration=None,
    max_epipolar_px: float = 3.0,
    report: MatchReport | None = None,
) -> np.ndarray | None:
    """Homography from a reference region to a target image by SIFT matching and RANSAC.

    Without ``calibration``: Lowe's ratio test on the two nearest descriptors. With it (a
    left region into the right image): each feature's nearest descriptors within
    ``max_epipolar_px`` [pixel] of its epipolar line, ratio test among those. ``report`` (a
    :class:`MatchReport`) is filled in, with the measured epipolar offset when the
    calibration refuses most matches.
    """
    import cv2

    (k1, d1), (k2, d2) = ref_features, target_features
    rep = report if report is not None else MatchReport()
    rep.features_ref, rep.features_target = len(k1), len(k2)
    if d1 is None or d2 is None or len(k1) < 8 or len(k2) < 8:
        return None
    p1_all = np.float64([kp.pt for kp in k1])
    p2_all = np.float64([kp.pt for kp in k2])
    k = _K_CANDIDATES if calibration is not None else 2
    idx, dist = _knn(d1, d2, k)
    if calibration is None:
        q, t = _ratio_pairs(idx, dist)
        rep.matches = rep.epipolar_inliers = len(q)
    else:
        n, kk = idx.shape
        rows = np.repeat(np.arange(n), kk)
        safe = np.where(idx >= 0, idx, 0).ravel()
        epi = epipolar_distance(calibration, p1_all[rows], p2_all[safe]).reshape(n, kk)
        q, t = _ratio_pairs(idx, dist, epi < max_epipolar_px)
        rep.matches = len(_ratio_pairs(idx[:, :2], dist[:, :2])[0])
        rep.epipolar_inliers = len(q)
    H = None
    if len(q) >= 8:
        H, inl = cv2.findHomography(p1_all[q], p2_all[t], cv2.RANSAC, 2.0)
        n_in = int(inl.sum()) if H is not None else 0
        rep.homography_inliers = n_in
        # a region maps by one homography: a few agreeing matches among many are chance
        if n_in < max(8, _MIN_INLIER_SHARE * len(q)):
            H = None
    if H is None and calibration is not None:
        rep.measured_epipolar_px = _measured_offset(calibration, p1_all, p2_all, idx, dist)
    return H


def _measured_offset(calibration, p1_all, p2_all, idx, dist) -> float | None:
    """Median epipolar distance of the plain (ratio-test) matches that one homography
    explains: the calibration's offset from these images [pixel]."""
    import cv2

    q, t = _ratio_pairs(idx[:, :2], dist[:, :2])
    if len(q) < 8:
        return None
    H, inl = cv2.findHomography(p1_all[q], p2_all[t], cv2.RANSAC, 2.0)
    if H is None or inl.sum() < 8:
        return None
    sel = inl.ravel().astype(bool)
    return float(np.median(epipolar_distance(calibration, p1_all[q][sel], p2_all[t][sel])))


def _homography_guess(H: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """Affine initial guesses (u, du/dx, du/dy, v, dv/dx, dv/dy) from a homography."""
    hp = np.column_stack([pts, np.ones(len(pts))]) @ H.T
    w = hp[:, 2]
    q = hp[:, :2] / w[:, None]
    # Jacobian of the homography at each point
    J = (H[None, :2, :2] - q[:, :, None] * H[None, 2:3, :2]) / w[:, None, None]
    return affine_guess(pts, q, J)


def affine_guess(pts: np.ndarray, moved: np.ndarray, J: np.ndarray) -> np.ndarray:
    """Affine subset parameters (u, du/dx, du/dy, v, dv/dx, dv/dy) of points ``pts`` (N, 2)
    mapped to ``moved`` [pixel] with the map's Jacobian ``J`` (N, 2, 2) there."""
    return np.column_stack(
        [
            moved[:, 0] - pts[:, 0],
            J[:, 0, 0] - 1.0,
            J[:, 0, 1],
            moved[:, 1] - pts[:, 1],
            J[:, 1, 0],
            J[:, 1, 1] - 1.0,
        ]
    )
