"""Stereo DIC geometry: triangulation with propagated uncertainty, epipolar checks, noise floor."""

from __future__ import annotations

import numpy as np

from jointwear.dic._calib import Camera, StereoCalibration
from jointwear.errors import BadInputError

__all__ = ["triangulate", "epipolar_distance", "stereo_noise_floor"]


def _undistorted_pixels(cam: Camera, uv: np.ndarray) -> np.ndarray:
    xy = cam.pixels_to_normalized(uv)
    K = cam.matrix
    return np.stack(
        [K[0, 0] * xy[:, 0] + K[0, 1] * xy[:, 1] + K[0, 2], K[1, 1] * xy[:, 1] + K[1, 2]], axis=1
    )


def _project_undistorted(cam: Camera, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Undistorted pixel projection of X (N, 3) and its Jacobian (N, 2, 3)."""
    K = cam.matrix
    Xc = X @ cam.rotation.T + cam.translation
    x, y, z = Xc[:, 0], Xc[:, 1], Xc[:, 2]
    fx, s, cx, fy, cy = K[0, 0], K[0, 1], K[0, 2], K[1, 1], K[1, 2]
    u = (fx * x + s * y) / z + cx
    v = fy * y / z + cy
    J = np.zeros((len(X), 2, 3))
    J[:, 0, 0] = fx / z
    J[:, 0, 1] = s / z
    J[:, 0, 2] = -(fx * x + s * y) / z**2
    J[:, 1, 1] = fy / z
    J[:, 1, 2] = -fy * y / z**2
    return np.stack([u, v], axis=1), J @ cam.rotation


def triangulate(
    calibration: StereoCalibration,
    uv_left: np.ndarray,
    uv_right: np.ndarray,
    *,
    sigma_px: float | np.ndarray = 0.02,
    iterations: int = 3,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Triangulate matched image points into world points, with their covariance.

    The (distorted) pixel coordinates are undistorted with each camera's lens model, an initial
    point is found by the linear (DLT) method and refined by Gauss–Newton minimisation of the
    reprojection error in both images. The covariance propagates an isotropic matching
    uncertainty ``sigma_px`` in each image: ``cov = sigma^2 (J^T J)^-1``.

    Parameters
    ----------
    calibration : StereoCalibration
    uv_left, uv_right : (N, 2) arrays
        Matched points in the left and right images [pixel]; NaN rows give NaN results.
    sigma_px : float or (N,) array
        Standard uncertainty of the image matches [pixel].
    iterations : int
        Gauss–Newton iterations.

    Returns
    -------
    X : (N, 3) array
        World points [m].
    cov : (N, 3, 3) array
        Their covariance [m^2].
    reprojection : (N,) array
        RMS reprojection residual over the four image coordinates [pixel] (large values mean a
        wrong match: the two rays do not meet).
    """
    import cv2

    uvl = np.asarray(uv_left, dtype=float).reshape(-1, 2)
    uvr = np.asarray(uv_right, dtype=float).reshape(-1, 2)
    if uvl.shape != uvr.shape:
        raise BadInputError(
            f"triangulate: left and right point arrays differ in shape ({uvl.shape} vs {uvr.shape})"
        )
    n = len(uvl)
    X = np.full((n, 3), np.nan)
    cov = np.full((n, 3, 3), np.nan)
    rep = np.full(n, np.nan)
    ok = np.all(np.isfinite(uvl), axis=1) & np.all(np.isfinite(uvr), axis=1)
    if not ok.any():
        return X, cov, rep
    L, R = calibration.left, calibration.right
    ul = _undistorted_pixels(L, uvl[ok])
    ur = _undistorted_pixels(R, uvr[ok])
    H = cv2.triangulatePoints(L.projection_matrix, R.projection_matrix, ul.T, ur.T)
    Xk = (H[:3] / H[3]).T
    for _ in range(iterations):
        pl, Jl = _project_undistorted(L, Xk)
        pr, Jr = _project_undistorted(R, Xk)
        r = np.concatenate([ul - pl, ur - pr], axis=1)  # (m, 4)
        J = np.concatenate([Jl, Jr], axis=1)  # (m, 4, 3)
        JtJ = np.einsum("nij,nik->njk", J, J)
        Jtr = np.einsum("nij,ni->nj", J, r)
        Xk = Xk + np.linalg.solve(JtJ, Jtr[..., None])[..., 0]
    pl, Jl = _project_undistorted(L, Xk)
    pr, Jr = _project_undistorted(R, Xk)
    r = np.concatenate([ul - pl, ur - pr], axis=1)
    J = np.concatenate([Jl, Jr], axis=1)
    JtJ = np.einsum("nij,nik->njk", J, J)
    sig = np.broadcast_to(np.asarray(sigma_px, dtype=float), (n,))[ok]
    X[ok] = Xk
    cov[ok] = np.linalg.inv(JtJ) * (sig**2)[:, None, None]
    rep[ok] = np.sqrt(np.mean(r**2, axis=1))
    return X, cov, rep


def epipolar_distance(
    calibration: StereoCalibration, uv_left: np.ndarray, uv_right: np.ndarray
) -> np.ndarray:
    """Distance of each right point from the epipolar line of its left point [pixel]
    (undistorted right image)."""
    ul = _undistorted_pixels(calibration.left, np.asarray(uv_left, dtype=float).reshape(-1, 2))
    ur = _undistorted_pixels(calibration.right, np.asarray(uv_right, dtype=float).reshape(-1, 2))
    F = calibration.fundamental_matrix()
    hl = np.concatenate([ul, np.ones((len(ul), 1))], axis=1)
    hr = np.concatenate([ur, np.ones((len(ur), 1))], axis=1)
    lines = hl @ F.T
    return np.abs(np.sum(lines * hr, axis=1)) / np.hypot(lines[:, 0], lines[:, 1])


def stereo_noise_floor(calibration: StereoCalibration, point: np.ndarray, sigma_px: float) -> float:
    """Out-of-plane (depth) noise floor of one matched point: ``Z^2 / (f B) * sqrt(2) * sigma``.

    ``Z`` is the point's depth in the left camera, ``f`` the mean focal length of the left
    camera [pixel] and ``B`` the baseline [m]; returns a standard deviation [m].
    """
    Z = float(calibration.left.world_to_camera(np.asarray(point, dtype=float).reshape(1, 3))[0, 2])
    f = float(np.mean(calibration.left.focal))
    return Z**2 / (f * calibration.baseline) * np.sqrt(2.0) * sigma_px
