"""Footage tracking: SIFT features and the homography that starts (or restarts) tracking."""

from __future__ import annotations

import numpy as np

from jointwear.dic._stereo import epipolar_distance


def _sift_features(img: np.ndarray, poly: np.ndarray | None = None, margin: int = 10):
    """SIFT keypoints and descriptors of ``img`` (inside ``poly`` grown by ``margin`` px)."""
    import cv2

    if poly is None:
        return cv2.SIFT_create().detectAndCompute(_as_uint8(img), None)
    # the region's bounding box only (a mask alone still builds the whole image's pyramid)
    h, w = img.shape
    pad = margin + 16
    x0, y0 = np.clip(np.floor(poly.min(0)).astype(int) - pad, 0, None)
    x1, y1 = np.ceil(poly.max(0)).astype(int) + pad + 1
    x1, y1 = min(x1, w), min(y1, h)
    mask = np.zeros((y1 - y0, x1 - x0), np.uint8)
    cv2.fillPoly(mask, [np.rint(poly - [x0, y0]).astype(np.int32)], 255)
    mask = cv2.dilate(mask, np.ones((2 * margin + 1,) * 2, np.uint8))
    kps, desc = cv2.SIFT_create().detectAndCompute(_as_uint8(img[y0:y1, x0:x1]), mask)
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


def _sift_homography(ref_features, target_features, *, calibration=None) -> np.ndarray | None:
    """Homography from a reference region to a target image by SIFT matching (ratio test,
    epipolar filter when ``calibration`` is given) and RANSAC."""
    import cv2

    (k1, d1), (k2, d2) = ref_features, target_features
    if d1 is None or d2 is None or len(k1) < 8 or len(k2) < 8:
        return None
    matches = cv2.BFMatcher(cv2.NORM_L2).knnMatch(d1, d2, k=2)
    good = [m[0] for m in matches if len(m) == 2 and m[0].distance < 0.8 * m[1].distance]
    if len(good) < 8:
        return None
    p1 = np.float64([k1[m.queryIdx].pt for m in good])
    p2 = np.float64([k2[m.trainIdx].pt for m in good])
    if calibration is not None:
        ok = epipolar_distance(calibration, p1, p2) < 3.0
        p1, p2 = p1[ok], p2[ok]
        if len(p1) < 8:
            return None
    H, inl = cv2.findHomography(p1, p2, cv2.RANSAC, 2.0)
    if H is None or inl.sum() < 8:
        return None
    return H


def _homography_guess(H: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """Affine initial guesses (u, du/dx, du/dy, v, dv/dx, dv/dy) from a homography."""
    hp = np.column_stack([pts, np.ones(len(pts))]) @ H.T
    w = hp[:, 2]
    q = hp[:, :2] / w[:, None]
    # Jacobian of the homography at each point
    J = (H[None, :2, :2] - q[:, :, None] * H[None, 2:3, :2]) / w[:, None, None]
    return np.column_stack(
        [
            q[:, 0] - pts[:, 0],
            J[:, 0, 0] - 1,
            J[:, 0, 1],
            q[:, 1] - pts[:, 1],
            J[:, 1, 0],
            J[:, 1, 1] - 1,
        ]
    )
