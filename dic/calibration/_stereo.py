"""Stereo DIC geometry: triangulation with propagated uncertainty, epipolar checks, noise floor."""

from __future__ import annotations

import numpy as np

from jointwear.dic.calibration._camera import Camera, StereoCalibration
from jointwear.errors import BadInputError

__all__ = ["triangulate", "epipolar_distance", "stereo_noise_floor"]


def undistorted_pixels(cam: Camera, uv: np.ndarray) -> np.ndarray:
    """Pixels ``uv`` (N, 2) [px] of ``cam`` with its lens distortion removed (N, 2) [px]."""
    xy = cam.pixels_to_normalized(uv)
    K = cam.matrix
    return np.stack(
        [K[0, 0] * xy[:, 0] + K[0, 1] * xy[:, 1] + K[0, 2], K[1, 1] * xy[:, 1] + K[1, 2]], axis=1
    )


def project_undistorted(cam: Camera, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
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
    ul = undistorted_pixels(L, uvl[ok])
    ur = undistorted_pixels(R, uvr[ok])
    H = cv2.triangulatePoints(L.projection_matrix, R.projection_matrix, ul.T, ur.T)
    Xk = np.ascontiguousarray((H[:3] / H[3]).T)
    sig = np.ascontiguousarray(np.broadcast_to(np.asarray(sigma_px, dtype=float), (n,))[ok])
    m = len(Xk)
    Xo, covo, repo = np.empty((m, 3)), np.empty((m, 3, 3)), np.empty(m)
    _refine_points(
        ul, ur, L.matrix, L.rotation, L.translation, R.matrix, R.rotation, R.translation,
        Xk, int(iterations), sig, Xo, covo, repo,
    )  # fmt: skip
    X[ok] = Xo
    cov[ok] = covo
    rep[ok] = repo
    return X, cov, rep


def epipolar_distance(
    calibration: StereoCalibration, uv_left: np.ndarray, uv_right: np.ndarray
) -> np.ndarray:
    """Distance of each right point from the epipolar line of its left point [pixel]
    (undistorted right image)."""
    ul = undistorted_pixels(calibration.left, np.asarray(uv_left, dtype=float).reshape(-1, 2))
    ur = undistorted_pixels(calibration.right, np.asarray(uv_right, dtype=float).reshape(-1, 2))
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


def _project_jacobian(K, Rw, t, X, J, k0):
    """Undistorted pixel projection of X (3,) into a camera; its Jacobian into rows k0, k0+1
    of J (4, 3). Returns (u, v)."""
    xc = Rw[0, 0] * X[0] + Rw[0, 1] * X[1] + Rw[0, 2] * X[2] + t[0]
    yc = Rw[1, 0] * X[0] + Rw[1, 1] * X[1] + Rw[1, 2] * X[2] + t[1]
    zc = Rw[2, 0] * X[0] + Rw[2, 1] * X[1] + Rw[2, 2] * X[2] + t[2]
    fx, s, cx, fy, cy = K[0, 0], K[0, 1], K[0, 2], K[1, 1], K[1, 2]
    u = (fx * xc + s * yc) / zc + cx
    v = fy * yc / zc + cy
    # d(u, v)/d(xc, yc, zc), then times the rotation (d Xc / d X = R)
    a0, a1, a2 = fx / zc, s / zc, -(fx * xc + s * yc) / (zc * zc)
    b1, b2 = fy / zc, -fy * yc / (zc * zc)
    for j in range(3):
        J[k0, j] = a0 * Rw[0, j] + a1 * Rw[1, j] + a2 * Rw[2, j]
        J[k0 + 1, j] = b1 * Rw[1, j] + b2 * Rw[2, j]
    return u, v


def _refine_points_impl(ul, ur, KL, RL, tL, KR, RR, tR, X0, iterations, sig, X, cov, rep):
    """Gauss-Newton refinement of each point's reprojection error in both undistorted
    images, then its covariance ``sigma^2 (J^T J)^-1`` and RMS residual."""
    J = np.empty((4, 3))
    r = np.empty(4)
    A = np.empty((3, 3))
    b = np.empty(3)
    for i in range(X0.shape[0]):
        x = X0[i].copy()
        for it in range(iterations + 1):
            u0, v0 = _project_jacobian(KL, RL, tL, x, J, 0)
            u1, v1 = _project_jacobian(KR, RR, tR, x, J, 2)
            r[0], r[1] = ul[i, 0] - u0, ul[i, 1] - v0
            r[2], r[3] = ur[i, 0] - u1, ur[i, 1] - v1
            for p in range(3):
                b[p] = 0.0
                for q in range(3):
                    A[p, q] = 0.0
                for k in range(4):
                    b[p] += J[k, p] * r[k]
                    for q in range(3):
                        A[p, q] += J[k, p] * J[k, q]
            if it == iterations:
                break
            x += np.linalg.solve(A, b)
        X[i] = x
        Ai = np.linalg.inv(A)
        s2 = sig[i] * sig[i]
        for p in range(3):
            for q in range(3):
                cov[i, p, q] = Ai[p, q] * s2
        rep[i] = np.sqrt((r[0] ** 2 + r[1] ** 2 + r[2] ** 2 + r[3] ** 2) / 4.0)


def _refine_points(*args):
    """Compiled on first use (numba), so importing this module stays light."""
    global _refine_points, _project_jacobian
    from numba import njit

    _project_jacobian = njit(cache=True, inline="always")(_project_jacobian)
    _refine_points = njit(cache=True, nogil=True)(_refine_points_impl)
    _refine_points(*args)
