"""Camera models and stereo calibration: projection, undistortion, (de)serialisation, importers.

Camera model
------------
A pinhole camera with Brown–Conrady lens distortion in OpenCV's convention. A world point
``X`` [m] goes to camera coordinates ``Xc = R @ X + t``; normalised coordinates
``x = Xc[0] / Xc[2]``, ``y = Xc[1] / Xc[2]`` are distorted with the radial (k1, k2, k3 and the
rational k4..k6) and tangential (p1, p2) terms, then mapped to pixels with
``u = fx * xd + skew * yd + cx`` and ``v = fy * yd + cy``. Pixel coordinates have their origin at
the centre of the top-left pixel, x to the right, y down (OpenCV). The skew term is kept so that
VIC-3D calibrations (which carry one) are represented exactly; OpenCV calibrations have
``skew = 0``.

The world frame is the left camera's frame unless a board pose was chosen as world frame
(:meth:`StereoCalibration.with_world_frame`), in which case z is normal to the board: lay the
board on the mechanism's plane and z becomes the rig's out-of-plane direction.
"""

from __future__ import annotations

import json
import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from jointwear.errors import BadInputError, CalibrationError

__all__ = [
    "Camera",
    "StereoCalibration",
    "cardan_to_matrix",
    "matrix_to_cardan",
    "read_opencv_calibration",
    "read_vic3d_calibration",
    "read_calibration",
    "DISTORTION_NAMES",
]

#: OpenCV's order of the distortion coefficients jointwear supports.
DISTORTION_NAMES = ("k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6")

_LENGTH_UNITS = {"m": 1.0, "mm": 1e-3, "cm": 1e-2, "um": 1e-6, "in": 0.0254}


def _as_matrix3(value: Any, what: str) -> np.ndarray:
    arr = np.asarray(value, dtype=float)
    if arr.shape != (3, 3) or not np.all(np.isfinite(arr)):
        raise BadInputError(f"{what}: expected a finite 3x3 matrix, got shape {arr.shape}")
    return arr


@dataclass(frozen=True, eq=False)
class Camera:
    """One calibrated pinhole camera with lens distortion.

    Parameters
    ----------
    matrix : (3, 3) array
        Intrinsic matrix ``[[fx, skew, cx], [0, fy, cy], [0, 0, 1]]`` [pixel].
    distortion : array
        Distortion coefficients in OpenCV order (k1, k2, p1, p2[, k3[, k4, k5, k6]]) [1].
    rotation : (3, 3) array
        World-to-camera rotation ``R`` (``Xc = R X + t``) [1].
    translation : (3,) array
        World-to-camera translation ``t`` [m].
    image_size : (int, int)
        Image (width, height) [pixel].
    """

    matrix: np.ndarray
    distortion: np.ndarray = field(default_factory=lambda: np.zeros(5))
    rotation: np.ndarray = field(default_factory=lambda: np.eye(3))
    translation: np.ndarray = field(default_factory=lambda: np.zeros(3))
    image_size: tuple[int, int] = (0, 0)

    def __post_init__(self) -> None:
        K = _as_matrix3(self.matrix, "camera matrix")
        if K[0, 0] <= 0 or K[1, 1] <= 0 or abs(K[2, 2] - 1) > 1e-9 or np.any(K[1:, 0] != 0):
            raise BadInputError(
                f"camera matrix {K.tolist()} is not of the form [[fx, skew, cx], [0, fy, cy], "
                "[0, 0, 1]] with positive focal lengths"
            )
        dist = np.zeros(8)
        d = np.asarray(self.distortion, dtype=float).ravel()
        if d.size > 8 and np.any(d[8:] != 0):
            raise BadInputError(
                f"distortion has {d.size} coefficients with non-zero thin-prism/tilt terms "
                "(s1..s4, tauX, tauY); jointwear supports k1, k2, p1, p2, k3, k4, k5, k6 only - "
                "recalibrate without CALIB_THIN_PRISM_MODEL/CALIB_TILTED_MODEL"
            )
        dist[: min(d.size, 8)] = d[:8]
        R = _as_matrix3(self.rotation, "camera rotation")
        if not np.allclose(R @ R.T, np.eye(3), atol=1e-6) or np.linalg.det(R) < 0:
            raise BadInputError("camera rotation is not a proper rotation matrix (R R^T != I)")
        t = np.asarray(self.translation, dtype=float).ravel()
        if t.shape != (3,):
            raise BadInputError(f"camera translation: expected 3 values, got {t.size}")
        w, h = (int(v) for v in self.image_size)
        object.__setattr__(self, "matrix", K)
        object.__setattr__(self, "distortion", dist)
        object.__setattr__(self, "rotation", R)
        object.__setattr__(self, "translation", t)
        object.__setattr__(self, "image_size", (w, h))

    # ---- basic properties -------------------------------------------------------------------
    @property
    def focal(self) -> tuple[float, float]:
        """Focal lengths (fx, fy) [pixel]."""
        return float(self.matrix[0, 0]), float(self.matrix[1, 1])

    @property
    def centre(self) -> np.ndarray:
        """Projection centre in world coordinates [m]."""
        return -self.rotation.T @ self.translation

    @property
    def projection_matrix(self) -> np.ndarray:
        """Projection matrix of the *undistorted* camera ``K [R | t]`` (3, 4)."""
        return self.matrix @ np.hstack([self.rotation, self.translation[:, None]])

    # ---- distortion -------------------------------------------------------------------------
    def distort_normalized(self, xy: np.ndarray) -> np.ndarray:
        """Apply lens distortion to normalised coordinates (N, 2) -> (N, 2)."""
        k1, k2, p1, p2, k3, k4, k5, k6 = self.distortion
        x, y = xy[..., 0], xy[..., 1]
        r2 = x * x + y * y
        radial = (1 + r2 * (k1 + r2 * (k2 + r2 * k3))) / (1 + r2 * (k4 + r2 * (k5 + r2 * k6)))
        xd = x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x)
        yd = y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y
        return np.stack([xd, yd], axis=-1)

    def normalized_to_pixels(self, xy: np.ndarray) -> np.ndarray:
        """Distort normalised coordinates and map them to pixels."""
        d = self.distort_normalized(np.asarray(xy, dtype=float))
        K = self.matrix
        u = K[0, 0] * d[..., 0] + K[0, 1] * d[..., 1] + K[0, 2]
        v = K[1, 1] * d[..., 1] + K[1, 2]
        return np.stack([u, v], axis=-1)

    def pixels_to_normalized(self, uv: np.ndarray, *, iterations: int = 8) -> np.ndarray:
        """Undistort pixel coordinates (N, 2) to normalised coordinates (inverse of the model).

        Fixed-point iteration followed by Newton steps with the model's exact Jacobian;
        accurate to ~1e-12 for the distortion of measurement lenses. NaN rows stay NaN.
        """
        uv = np.asarray(uv, dtype=float)
        K = self.matrix
        yd = (uv[..., 1] - K[1, 2]) / K[1, 1]
        xd = (uv[..., 0] - K[0, 2] - K[0, 1] * yd) / K[0, 0]
        target = np.stack([xd, yd], axis=-1)
        if not np.any(self.distortion):
            return target
        flat = np.ascontiguousarray(target.reshape(-1, 2))
        out = np.empty_like(flat)
        _undistort(flat, np.asarray(self.distortion, dtype=float), int(iterations), out)
        return out.reshape(target.shape)

    # ---- projection -------------------------------------------------------------------------
    def world_to_camera(self, X: np.ndarray) -> np.ndarray:
        """World points (N, 3) [m] -> camera-frame points (N, 3) [m]."""
        return np.asarray(X, dtype=float) @ self.rotation.T + self.translation

    def project(self, X: np.ndarray) -> np.ndarray:
        """Project world points (N, 3) [m] to distorted pixel coordinates (N, 2) [pixel]."""
        Xc = self.world_to_camera(X)
        xy = Xc[..., :2] / Xc[..., 2:3]
        return self.normalized_to_pixels(xy)

    def rays(self, uv: np.ndarray) -> np.ndarray:
        """Unit viewing directions in world coordinates (N, 3) for pixels (N, 2)."""
        xy = self.pixels_to_normalized(uv)
        d = np.concatenate([xy, np.ones(xy.shape[:-1] + (1,))], axis=-1)
        d = d @ self.rotation  # R^T d for row vectors
        return d / np.linalg.norm(d, axis=-1, keepdims=True)

    def transformed(self, R_wn: np.ndarray, t_wn: np.ndarray) -> Camera:
        """The same camera with a new world frame.

        ``X_old = R_wn @ X_new + t_wn`` (the new frame expressed in the old one).
        """
        R = self.rotation @ R_wn
        t = self.rotation @ t_wn + self.translation
        return Camera(self.matrix, self.distortion, R, t, self.image_size)


@dataclass(frozen=True, eq=False)
class StereoCalibration:
    """A calibrated camera pair and how the calibration was obtained.

    Parameters
    ----------
    left, right : Camera
        The two cameras, extrinsics in a common world frame.
    rms : float or None
        Overall stereo reprojection RMS [pixel] (None for imported calibrations).
    per_view_rms : (n_views, 2) array or None
        Reprojection RMS per accepted view and camera [pixel].
    views_used, views_rejected : int
        Number of calibration views accepted and rejected.
    rejected : tuple of str
        Why each rejected view was rejected.
    view_names : tuple of str
        Name of each accepted view (its image files), in the order of ``per_view_rms``.
    length_unit : str
        Unit of the translations: ``"m"``, or ``"square"`` for a board calibrated without a
        metric square size (such a calibration cannot measure; see :func:`read_calibration`).
    length_scale_u_rel : float or None
        Relative standard uncertainty of lengths measured with this calibration (baseline
        scatter over the views, and the board's square size when its uncertainty was given)
        [1]; None: not assessed.
    status : str
        ``"accepted"``, ``"accepted with --accept-poor: <problems>"`` or
        ``"rejected: <problems>"`` (see :mod:`jointwear.dic._calib_gate`).
    source : str
        Where the calibration came from (``"jointwear calibrate"``, ``"opencv:<file>"``,
        ``"vic3d:<file>"``).
    world_frame : str
        Description of the world frame.
    """

    left: Camera
    right: Camera
    rms: float | None = None
    per_view_rms: np.ndarray | None = None
    views_used: int = 0
    views_rejected: int = 0
    source: str = ""
    world_frame: str = "left camera frame (x right, y down, z along the optical axis)"
    rejected: tuple[str, ...] = ()
    view_names: tuple[str, ...] = ()
    length_unit: str = "m"
    length_scale_u_rel: float | None = None
    status: str = "accepted"

    @property
    def cameras(self) -> dict[str, Camera]:
        return {"left": self.left, "right": self.right}

    @property
    def baseline(self) -> float:
        """Distance between the two projection centres [m]."""
        return float(np.linalg.norm(self.left.centre - self.right.centre))

    @property
    def relative_pose(self) -> tuple[np.ndarray, np.ndarray]:
        """(R, T) taking left-camera coordinates to right-camera coordinates (OpenCV's R, T)."""
        R = self.right.rotation @ self.left.rotation.T
        T = self.right.translation - R @ self.left.translation
        return R, T

    def fundamental_matrix(self) -> np.ndarray:
        """Fundamental matrix of the undistorted pixel coordinates (x_r^T F x_l = 0)."""
        R, T = self.relative_pose
        tx = np.array([[0, -T[2], T[1]], [T[2], 0, -T[0]], [-T[1], T[0], 0]])
        E = tx @ R
        F = np.linalg.inv(self.right.matrix).T @ E @ np.linalg.inv(self.left.matrix)
        return F / np.linalg.norm(F)

    def with_world_frame(self, R_wn: np.ndarray, t_wn: np.ndarray, description: str) -> Any:
        """Express both cameras in a new world frame ``X_old = R_wn X_new + t_wn``."""
        import dataclasses

        return dataclasses.replace(
            self,
            left=self.left.transformed(R_wn, t_wn),
            right=self.right.transformed(R_wn, t_wn),
            world_frame=description,
        )

    # ---- xarray ----------------------------------------------------------------------------
    def to_dataset(self) -> xr.Dataset:
        """The calibration as an :class:`xarray.Dataset` (save it with :func:`jointwear.io.save`)."""
        cams = [self.left, self.right]
        ds = xr.Dataset(
            {
                "camera_matrix": (
                    ("camera", "row", "col"),
                    np.stack([c.matrix for c in cams]),
                    {
                        "units": "pixel",
                        "long_name": "intrinsic matrix [[fx, skew, cx], [0, fy, cy], [0, 0, 1]]",
                    },
                ),
                "distortion": (
                    ("camera", "coefficient"),
                    np.stack([c.distortion for c in cams]),
                    {
                        "units": "1",
                        "long_name": "Brown-Conrady distortion coefficients (OpenCV order)",
                    },
                ),
                "rotation": (
                    ("camera", "row", "col"),
                    np.stack([c.rotation for c in cams]),
                    {"units": "1", "long_name": "world-to-camera rotation R (Xc = R X + t)"},
                ),
                "translation": (
                    ("camera", "axis"),
                    np.stack([c.translation for c in cams]),
                    {
                        "units": self.length_unit,
                        "long_name": "world-to-camera translation t (Xc = R X + t)",
                    },
                ),
                "image_size": (
                    ("camera", "extent"),
                    np.array([c.image_size for c in cams], dtype=np.int64),
                    {"units": "pixel", "long_name": "image width and height"},
                ),
            },
            coords={
                "camera": ("camera", ["left", "right"], {"long_name": "stereo camera"}),
                "row": ("row", [0, 1, 2], {"long_name": "matrix row"}),
                "col": ("col", [0, 1, 2], {"long_name": "matrix column"}),
                "coefficient": (
                    "coefficient",
                    list(DISTORTION_NAMES),
                    {"long_name": "distortion coefficient"},
                ),
                "axis": ("axis", ["x", "y", "z"], {"long_name": "vector component"}),
                "extent": ("extent", ["width", "height"], {"long_name": "image extent"}),
            },
        )
        if self.per_view_rms is not None and len(self.per_view_rms):
            ds["view_rms"] = (
                ("view", "camera"),
                np.asarray(self.per_view_rms, dtype=float),
                {"units": "pixel", "long_name": "reprojection RMS per accepted calibration view"},
            )
            if len(self.view_names) == len(self.per_view_rms):
                ds = ds.assign_coords(
                    view=("view", list(self.view_names), {"long_name": "calibration view files"})
                )
        ds.attrs.update(
            {
                "title": "jointwear stereo calibration",
                "baseline_m": self.baseline,
                "reprojection_rms_px": float(self.rms) if self.rms is not None else -1.0,
                "views_used": int(self.views_used),
                "views_rejected": int(self.views_rejected),
                "calibration_source": self.source,
                "world_frame": self.world_frame,
                "rejected_views": json.dumps(list(self.rejected)),
                "length_unit": self.length_unit,
                "calibration_status": self.status,
                "length_scale_u_rel": (
                    float(self.length_scale_u_rel)
                    if self.length_scale_u_rel is not None
                    else "not assessed"
                ),
            }
        )
        return ds

    @classmethod
    def from_dataset(cls, ds: xr.Dataset, *, what: str = "calibration") -> StereoCalibration:
        """Inverse of :meth:`to_dataset`."""
        missing = [
            v
            for v in ("camera_matrix", "distortion", "rotation", "translation", "image_size")
            if v not in ds
        ]
        if missing:
            raise BadInputError(
                f"{what} is not a jointwear stereo calibration (missing {', '.join(missing)}); "
                "create one with `jointwear dic calibrate` or import one with "
                "`jointwear dic import-calibration`"
            )
        cams = []
        for name in ("left", "right"):
            sel = ds.sel(camera=name)
            cams.append(
                Camera(
                    sel["camera_matrix"].values,
                    sel["distortion"].values,
                    sel["rotation"].values,
                    sel["translation"].values,
                    tuple(int(v) for v in sel["image_size"].values),
                )
            )
        rms = float(ds.attrs.get("reprojection_rms_px", -1.0))
        return cls(
            cams[0],
            cams[1],
            rms=None if rms < 0 else rms,
            per_view_rms=ds["view_rms"].values if "view_rms" in ds else None,
            views_used=int(ds.attrs.get("views_used", 0)),
            views_rejected=int(ds.attrs.get("views_rejected", 0)),
            source=str(ds.attrs.get("calibration_source", "")),
            world_frame=str(ds.attrs.get("world_frame", "")),
            rejected=tuple(_json_list(ds.attrs.get("rejected_views", "[]"))),
            view_names=(
                tuple(str(v) for v in ds["view"].values)
                if "view_rms" in ds and "view" in ds.coords and ds["view"].dtype.kind in "UO"
                else ()
            ),
            length_unit=str(ds.attrs.get("length_unit", "m")),
            status=str(ds.attrs.get("calibration_status", "accepted")),
            length_scale_u_rel=_float_or_none(ds.attrs.get("length_scale_u_rel")),
        )

    def save(self, path: str | Path, *, inputs=(), parameters: Any = None) -> Path:
        """Write the calibration as a jointwear netCDF file with provenance."""
        from jointwear import io

        return io.save(
            self.to_dataset(),
            path,
            inputs=inputs,
            parameters=parameters,
            source="jointwear (dic.calibrate)",
        )


def _float_or_none(value: Any) -> float | None:
    try:
        out = float(value)
    except (TypeError, ValueError):
        return None
    return out if np.isfinite(out) else None


def _json_list(value: Any) -> list[str]:
    if isinstance(value, (list, tuple)):
        return [str(v) for v in value]
    try:
        out = json.loads(value)
    except (TypeError, ValueError):
        return []
    return [str(v) for v in out] if isinstance(out, list) else []


# ---- rotations ------------------------------------------------------------------------------
def cardan_to_matrix(alpha_deg: float, beta_deg: float, gamma_deg: float) -> np.ndarray:
    """Rotation matrix ``Rz(gamma) @ Ry(beta) @ Rx(alpha)`` from Cardan angles [degree].

    This is the convention of the ``<orientation>`` of VIC-3D's ``cal.xml``/project files: the
    matrix takes world coordinates to camera coordinates (``Xc = R X + t``). Sandia's DICe
    builds the same matrix from a VIC-3D file (``eulers_to_rotation_matrix``), SDynPy's VIC-3D
    reader its transpose as the camera-to-world matrix; real VIC-3D stereo matches fit it to
    0.05 px (see :func:`read_vic3d_calibration`).
    """
    a, b, g = np.deg2rad([alpha_deg, beta_deg, gamma_deg])
    ca, sa, cb, sb, cg, sg = np.cos(a), np.sin(a), np.cos(b), np.sin(b), np.cos(g), np.sin(g)
    Rx = np.array([[1, 0, 0], [0, ca, -sa], [0, sa, ca]])
    Ry = np.array([[cb, 0, sb], [0, 1, 0], [-sb, 0, cb]])
    Rz = np.array([[cg, -sg, 0], [sg, cg, 0], [0, 0, 1]])
    return Rz @ Ry @ Rx


def matrix_to_cardan(R: np.ndarray) -> tuple[float, float, float]:
    """Inverse of :func:`cardan_to_matrix` (alpha, beta, gamma) [degree]."""
    beta = np.arcsin(-np.clip(R[2, 0], -1, 1))
    alpha = np.arctan2(R[2, 1], R[2, 2])
    gamma = np.arctan2(R[1, 0], R[0, 0])
    return tuple(float(v) for v in np.rad2deg([alpha, beta, gamma]))


# ---- importers ------------------------------------------------------------------------------
def _length_scale(length_unit: str | float) -> float:
    """Metres per unit of ``length_unit`` (a unit name, or a number of metres per unit)."""
    if isinstance(length_unit, str) and length_unit.strip() in _LENGTH_UNITS:
        return _LENGTH_UNITS[length_unit.strip()]
    try:
        scale = float(length_unit)
    except (TypeError, ValueError):
        scale = float("nan")
    if not (np.isfinite(scale) and scale > 0):
        raise BadInputError(
            f"length_unit {length_unit!r} is not known; use one of {', '.join(_LENGTH_UNITS)} "
            "(the unit the calibration board's square size was given in), or the number of "
            "metres per unit of T (e.g. 0.025 when T is in squares of a 25 mm board)"
        )
    return scale


def _check_rotation(R: Any, where: str) -> np.ndarray:
    """A proper rotation matrix from a 3x3 matrix or a Rodrigues vector, or a clear error."""
    import cv2

    arr = np.asarray(R, dtype=float)
    if arr.size == 3:
        if not np.all(np.isfinite(arr)):
            raise BadInputError(
                f"{where}: the Rodrigues rotation vector {arr.ravel()} is not finite"
            )
        arr = cv2.Rodrigues(arr.reshape(3, 1))[0]
    if arr.shape != (3, 3) or not np.all(np.isfinite(arr)):
        raise BadInputError(
            f"{where}: expected a finite 3x3 rotation matrix or a 3-element Rodrigues vector, "
            f"got shape {arr.shape}"
        )
    err = float(np.max(np.abs(arr @ arr.T - np.eye(3))))
    det = float(np.linalg.det(arr))
    if err <= 1e-5 and det > 0:  # rounded when written: the nearest rotation
        U, _, Vt = np.linalg.svd(arr)
        return U @ Vt
    if err > 1e-6 or abs(det - 1) > 1e-6:
        kind = (
            "a reflection (det = -1)" if det < 0 else f"not orthonormal (|R R^T - I| = {err:.2g})"
        )
        raise BadInputError(
            f"{where} is not a rotation matrix: {kind}, det = {det:.6g}; check that the key holds "
            "stereoCalibrate's R (left-to-right rotation), not R1/R2/P1/P2 or a transposed copy"
        )
    return arr


#: Distortion vector lengths OpenCV writes (k1 k2 p1 p2 [k3 [k4 k5 k6 [s1..s4 [tauX tauY]]]]).
_OPENCV_DIST_SIZES = (4, 5, 8, 12, 14)


def _opencv_distortion(d: Any, where: str) -> np.ndarray:
    arr = np.asarray(d, dtype=float).ravel()
    if arr.size not in _OPENCV_DIST_SIZES:
        raise BadInputError(
            f"{where}: a distortion vector of {arr.size} coefficients; OpenCV writes 4, 5, 8, 12 "
            "or 14 (k1 k2 p1 p2 [k3 [k4 k5 k6 [s1 s2 s3 s4 [tauX tauY]]]])"
        )
    if not np.all(np.isfinite(arr)):
        raise BadInputError(f"{where}: the distortion coefficients {arr.tolist()} are not finite")
    if arr.size > 8 and np.any(arr[8:] != 0):
        raise BadInputError(
            f"{where}: non-zero thin-prism/tilt coefficients (s1..s4, tauX, tauY = "
            f"{arr[8:].tolist()}); jointwear's camera model has k1, k2, p1, p2, k3, k4, k5, k6 "
            "only - recalibrate without CALIB_THIN_PRISM_MODEL/CALIB_TILTED_MODEL"
        )
    return arr[:8]


def _check_lens(cam: Camera, where: str) -> None:
    """Refuse a lens model whose radial mapping folds back within the image (undistortion would
    be ambiguous there): r_d = r * radial(r) must increase up to the farthest image corner."""
    w, h = cam.image_size
    K = cam.matrix
    corners = np.array([[0, 0], [w, 0], [0, h], [w, h]], dtype=float) - K[:2, 2]
    r_max = float(np.max(np.hypot(corners[:, 0] / K[0, 0], corners[:, 1] / K[1, 1])))
    r = np.linspace(0.0, r_max, 2001)
    k1, k2, _, _, k3, k4, k5, k6 = cam.distortion
    r2 = r * r
    rd = r * (1 + r2 * (k1 + r2 * (k2 + r2 * k3))) / (1 + r2 * (k4 + r2 * (k5 + r2 * k6)))
    bad = np.flatnonzero(np.diff(rd) <= 0)
    if bad.size:
        r_fold = float(r[bad[0]])
        raise BadInputError(
            f"{where}: the lens distortion folds back at {r_fold:.3f} (normalised radius), inside "
            f"the {w}x{h} px image (corner at {r_max:.3f}); the coefficients "
            f"{cam.distortion.tolist()} cannot be those of this camera - check the file and the "
            "image size"
        )


_OPENCV_KEYS = {
    "K1": ("K1", "M1", "cameraMatrix1", "camera_matrix_left", "left_camera_matrix"),
    "D1": ("D1", "dist1", "distCoeffs1", "distortion_left", "left_distortion"),
    "K2": ("K2", "M2", "cameraMatrix2", "camera_matrix_right", "right_camera_matrix"),
    "D2": ("D2", "dist2", "distCoeffs2", "distortion_right", "right_distortion"),
    "R": ("R", "rotation", "R_lr"),
    "T": ("T", "translation", "T_lr"),
}


def _fs_array(node: Any) -> np.ndarray | None:
    """A cv::FileNode as an array: an ``opencv-matrix``, a sequence of numbers or a number."""
    if node.isSeq():
        items = [node.at(i) for i in range(node.size())]
        if items and all(item.isSeq() for item in items):  # nested lists: rows of a matrix
            rows = [_fs_array(item) for item in items]
            if any(r is None for r in rows) or len({r.size for r in rows}) != 1:
                return None
            return np.stack([r.ravel() for r in rows])
        if not all(item.isReal() or item.isInt() for item in items):
            return None
        return np.asarray([item.real() for item in items], dtype=float)
    if node.isReal() or node.isInt():
        return np.asarray([node.real()], dtype=float)
    mat = node.mat()
    return None if mat is None else np.asarray(mat, dtype=float)


def _read_opencv_file(path: Path) -> tuple[dict[str, tuple[np.ndarray, str]], Any]:
    """Keys of :data:`_OPENCV_KEYS` found in one FileStorage file, and its image size (or None)."""
    import cv2

    if not path.exists():
        raise BadInputError(f"OpenCV calibration file '{path}' does not exist")
    try:
        fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_READ)
        ok = fs.isOpened()
    except (cv2.error, SystemError):  # OpenCV 5 raises SystemError on truncated/empty files
        ok = False
    if not ok:
        raise BadInputError(
            f"'{path}' could not be read as an OpenCV FileStorage YAML/XML file; check that it "
            "starts with '%YAML:1.0' or '<?xml' and was written by cv::FileStorage"
        )
    found: dict[str, tuple[np.ndarray, str]] = {}
    size = None
    try:
        for key, names in _OPENCV_KEYS.items():
            for name in names:
                node = fs.getNode(name)
                if not node.empty():
                    arr = _fs_array(node)
                    if arr is not None:
                        found[key] = (arr, name)
                        break
        w, h = fs.getNode("image_width"), fs.getNode("image_height")
        if not w.empty() and not h.empty():
            size = (int(w.real()), int(h.real()))
        for name in ("image_size", "imageSize"):
            node = fs.getNode(name)
            if size is None and not node.empty():
                arr = _fs_array(node)
                if arr is not None and arr.size >= 2:
                    size = (int(arr.ravel()[0]), int(arr.ravel()[1]))
    except BadInputError:
        raise
    except (cv2.error, SystemError, ValueError, TypeError, OverflowError) as exc:
        raise BadInputError(
            f"'{path}': an entry of the OpenCV FileStorage file cannot be read ({exc}); the "
            "file is corrupt or truncated - write it again with cv::FileStorage"
        ) from None
    finally:
        fs.release()
    return found, size


def read_opencv_calibration(
    path: str | Path | list[str | Path] | tuple[str | Path, ...],
    *,
    length_unit: str | float,
    image_size: tuple[int, int] | None = None,
    extrinsics: str | Path | None = None,
) -> StereoCalibration:
    """Import a stereo calibration saved by OpenCV (``cv::FileStorage`` YAML or XML).

    The file(s) hold the two intrinsic matrices and distortion vectors and ``stereoCalibrate``'s
    ``R``, ``T`` (left-camera to right-camera: ``X_right = R X_left + T``). They may be split over
    two files as OpenCV's ``stereo_calib`` sample writes them: ``intrinsics.yml`` (``M1 D1 M2
    D2``) and ``extrinsics.yml`` (``R T R1 R2 P1 P2 Q``; the rectification entries are not used).
    Accepted names: ``K1/M1/cameraMatrix1``, ``D1/dist1/distCoeffs1``, ``K2/M2/cameraMatrix2``,
    ``D2/dist2/distCoeffs2``, ``R`` (3x3 matrix or Rodrigues vector), ``T``, and
    ``image_width``/``image_height`` or ``image_size``/``imageSize``. Distortion vectors of 4, 5,
    8, 12 or 14 coefficients are accepted; thin-prism and tilt terms must be zero.

    Parameters
    ----------
    path : path, or list/tuple of paths
        The ``.yml``/``.yaml``/``.xml``/``.json`` file, or several files whose keys are merged
        (a key found in two files must have the same value in both).
    length_unit : {"m", "mm", "cm", "um", "in"} or float
        Unit of ``T``: OpenCV uses whatever unit the board square size was given in; the file
        does not say, so it must be stated. A number is taken as metres per unit (e.g. ``0.025``
        when ``stereo_calib`` ran with its default square size 1 on a 25 mm board).
    image_size : (width, height), optional
        Image size [pixel] when the files do not hold it (``stereo_calib`` does not write it).
    extrinsics : path, optional
        A further file to merge (the ``extrinsics.yml`` of ``stereo_calib``).

    Returns
    -------
    StereoCalibration
        World frame = left camera frame; translations in metres.
    """
    paths = [Path(p) for p in (path if isinstance(path, (list, tuple)) else [path])]
    if extrinsics is not None:
        paths.append(Path(extrinsics))
    if not paths:
        raise BadInputError("read_opencv_calibration: no file given")
    scale = _length_scale(length_unit)
    found: dict[str, tuple[np.ndarray, str, Path]] = {}
    holds: dict[Path, list[str]] = {}
    size = image_size
    for p in paths:
        keys, file_size = _read_opencv_file(p)
        holds[p] = [name for _, name in keys.values()]
        for key, (arr, name) in keys.items():
            if key in found:
                prev, prev_name, prev_path = found[key]
                if prev.shape != arr.shape or not np.allclose(prev, arr, rtol=1e-9, atol=0):
                    raise BadInputError(
                        f"OpenCV calibration: {key} differs between '{prev_path}' ({prev_name}) "
                        f"and '{p}' ({name}); pass files from one calibration only"
                    )
                continue
            found[key] = (arr, name, p)
        if size is None and file_size is not None:
            size = file_size
    names = " + ".join(f"'{p}'" for p in paths)
    missing = [k for k in _OPENCV_KEYS if k not in found]
    if missing:
        held = "; ".join(
            f"'{p.name}' holds {', '.join(h) if h else 'none of them'}" for p, h in holds.items()
        )
        raise BadInputError(
            f"OpenCV calibration {names} lacks {', '.join(missing)} (looked for "
            + "; ".join(f"{k}: {'/'.join(_OPENCV_KEYS[k])}" for k in missing)
            + f"; {held}); it must hold both cameras' matrices and distortion and "
            "stereoCalibrate's R and T - OpenCV's stereo_calib sample writes them to two files, "
            "intrinsics.yml (M1 D1 M2 D2) and extrinsics.yml (R T): pass both"
        )
    if size is None:
        raise BadInputError(
            f"OpenCV calibration {names} does not state the image size; pass image_size="
            "(width, height) (CLI: --image-size W H)"
        )
    size = _check_image_size(size, f"OpenCV calibration {names}")

    def where(key: str) -> str:
        return f"OpenCV calibration '{found[key][2]}', {found[key][1]}"

    mats = {}
    for key in ("K1", "K2"):
        K = found[key][0]
        if K.shape != (3, 3) or not np.all(np.isfinite(K)):
            raise BadInputError(
                f"{where(key)}: expected a finite 3x3 camera matrix, got shape {K.shape}"
            )
        mats[key] = K
    D1 = _opencv_distortion(found["D1"][0], where("D1"))
    D2 = _opencv_distortion(found["D2"][0], where("D2"))
    R = _check_rotation(found["R"][0], where("R"))
    T = found["T"][0].ravel()
    if T.size != 3 or not np.all(np.isfinite(T)):
        raise BadInputError(f"{where('T')}: expected 3 finite values, got {T.tolist()}")
    try:
        left = Camera(mats["K1"], D1, np.eye(3), np.zeros(3), size)
        right = Camera(mats["K2"], D2, R, T * scale, size)
    except BadInputError as exc:
        raise BadInputError(f"OpenCV calibration {names}: {exc}") from None
    _check_lens(left, f"OpenCV calibration {names}, left camera")
    _check_lens(right, f"OpenCV calibration {names}, right camera")
    return StereoCalibration(left, right, source="opencv:" + "+".join(p.name for p in paths))


def _check_image_size(size: Any, what: str) -> tuple[int, int]:
    try:
        w, h = (float(v) for v in size)
    except (TypeError, ValueError):
        raise BadInputError(f"{what}: image size {size!r} is not (width, height)") from None
    if not (
        np.isfinite(w) and np.isfinite(h) and w >= 1 and h >= 1 and w == int(w) and h == int(h)
    ):
        raise BadInputError(
            f"{what}: image size {size!r} is not a positive whole (width, height) in pixels"
        )
    return int(w), int(h)


def _vic3d_numbers(text: str | None, where: str) -> list[float]:
    out = []
    for tok in (text or "").replace(",", " ").split():
        try:
            out.append(float(tok))
        except ValueError:
            raise BadInputError(f"{where}: {tok!r} is not a number") from None
    return out


def _vic3d_root(path: Path) -> ET.Element:
    """The XML of a VIC-3D cal.xml, project XML or ``.z3d`` project (zip holding project.xml),
    with tag and attribute names lower-cased."""
    import zipfile

    if not path.exists():
        raise BadInputError(f"VIC-3D calibration file '{path}' does not exist")
    if zipfile.is_zipfile(path):
        with zipfile.ZipFile(path) as zf:
            xmls = [n for n in zf.namelist() if n.lower().endswith(".xml")]
            xmls.sort(key=lambda n: (Path(n).name.lower() != "project.xml", len(n)))
            if not xmls:
                raise BadInputError(
                    f"VIC-3D project '{path}' is a zip archive without an XML file (expected "
                    "project.xml inside a .z3d); export the calibration as cal.xml from VIC-3D"
                )
            data = zf.read(xmls[0])
            label = f"'{path}' ({xmls[0]})"
    else:
        data = path.read_bytes()
        label = f"'{path}'"
    data = re.sub(rb"<!DOCTYPE[^>\[]*(\[[^\]]*\])?\s*>", b"", data, count=1)
    try:
        root = ET.fromstring(data)
    except ET.ParseError as exc:
        raise BadInputError(
            f"{label} is not well-formed XML ({exc}); is it a VIC-3D cal.xml or project file?"
        ) from None
    for el in root.iter():
        if isinstance(el.tag, str):
            el.tag = el.tag.rsplit("}", 1)[-1].lower()
        el.attrib = {k.lower(): v for k, v in el.attrib.items()}
    return root


def read_vic3d_calibration(
    path: str | Path, *, image_size: tuple[int, int] | None = None
) -> StereoCalibration:
    """Import the calibration of a VIC-3D project or calibration file (``cal.xml``, project XML
    or ``.z3d``).

    VIC-3D stores, per ``<camera id=...>``, ``cx cy fx fy fs k1 k2 k3`` [pixel, pixel, pixel,
    pixel, pixel, 1, 1, 1] followed by ``<orientation>alpha beta gamma tx ty tz</orientation>``
    [degree, mm]. Newer ``.z3d`` projects split them into ``<intrinsics>cx cy fx fy fs
    </intrinsics>``, ``<distortion>`` and ``<orientation>`` (the element names SDynPy's VIC-3D
    reader uses); ``<distortion>`` is taken to hold ``k1 [k2 [k3]]`` and more values are refused.
    They are read as:

    * world-to-camera extrinsics ``Xc = R X + t`` with ``R = Rz(gamma) Ry(beta) Rx(alpha)``
      (:func:`cardan_to_matrix`) and ``t = (tx, ty, tz)`` in millimetres (converted to metres);
    * ``fs`` is the skew entry ``K[0, 1]`` of the intrinsic matrix [pixel] (``u = fx x_d + fs
      y_d + cx``), not an angle;
    * ``k1, k2, k3`` distort normalised coordinates radially,
      ``x_d = x (1 + k1 r^2 + k2 r^4 + k3 r^6)`` with ``r^2 = x^2 + y^2`` - exactly OpenCV's
      ``(k1, k2, 0, 0, k3)``, so the camera model is represented without fitting.

    Evidence: with this reading, real image matches made by VIC-3D and by DICe with real VIC-3D
    files triangulate to 0.02-0.06 px RMS (DICe's ``stereo_d_spec`` regression data: 0.054 px
    over 27 points; VIC-3D's own start-point matches in DICe's ``stereo_list`` project: 0.024 px),
    whereas another rotation order, the transposed rotation or a camera-to-world reading gives
    5-10 px. DICe imports these coefficients as odd powers of the radius (``K1R1_K2R2_K3R3``, a
    radial displacement ``k1 r + k2 r^2 + k3 r^3``), which leaves 82 px on the ``stereo_d_spec``
    matches and makes ``k1`` indistinguishable from a focal-length change: that reading is not
    used. In the plane-fit frame stored in that VIC-3D project the flat specimen comes out within
    0.11 mm of Z = 0 (VIC-3D's own points: -0.014..0.020 mm); ``fs`` read as an angle in degrees
    would spread it over 1.8 mm. Whether k1..k3 distort or undistort is not decided by these
    data (< 0.02 px either way, the distorting form fitting slightly better); it follows the
    usual camera model.

    The image size is read from ``<polygonmask width= height=>`` when present. Camera ``0``
    becomes the ``left`` camera and camera ``1`` the ``right`` one, whatever their physical
    placement (in the two real VIC-3D rigs checked, camera 0 sits on the right, at +x).

    Parameters
    ----------
    path : path
        VIC-3D ``cal.xml``, project XML, ``.z3d`` project, or a file holding just the
        ``<calibration>`` element. Tag case does not matter.
    image_size : (width, height), optional
        Image size [pixel], needed when the file has no ``<polygonmask>``.

    Returns
    -------
    StereoCalibration
        Cameras in VIC-3D's world frame (converted to metres).
    """
    path = Path(path)
    root = _vic3d_root(path)
    cal = next((el for el in root.iter("calibration") if el.find(".//camera") is not None), root)
    nodes = list(cal.iter("camera"))
    cams: dict[str, tuple] = {}
    for node in nodes:
        ident = node.attrib.get("id")
        where = f"VIC-3D calibration '{path}', camera {ident}"
        orient = node.find("orientation")
        intr_el, dist_el = node.find("intrinsics"), node.find("distortion")
        intr = _vic3d_numbers(intr_el.text if intr_el is not None else node.text, where)
        if ident is None or orient is None or len(intr) not in (5, 8):
            raise BadInputError(
                f"VIC-3D calibration '{path}': a <camera> element must hold an id, the eight "
                "intrinsic values 'cx cy fx fy fs k1 k2 k3' (or <intrinsics>cx cy fx fy fs"
                "</intrinsics> and <distortion>k1 k2 k3</distortion>) and an <orientation> with "
                f"'alpha beta gamma tx ty tz'; found id={ident!r}, {len(intr)} intrinsic values"
                f"{'' if orient is not None else ', no <orientation>'}"
            )
        kappa = intr[5:8] if len(intr) == 8 else [0.0, 0.0, 0.0]
        if dist_el is not None:
            dist = _vic3d_numbers(dist_el.text, where + " <distortion>")
            if len(dist) > 3:
                raise BadInputError(
                    f"{where}: <distortion> holds {len(dist)} values; jointwear knows VIC-3D's "
                    "radial k1 k2 k3 (r^2, r^4, r^6) only - export the calibration as cal.xml "
                    "(camera values 'cx cy fx fy fs k1 k2 k3'), or recalibrate without the "
                    "extra distortion terms"
                )
            dist = dist + [0.0] * (3 - len(dist))
            if len(intr) == 8 and not np.allclose(dist, kappa):
                raise BadInputError(
                    f"{where}: the distortion {dist} in <distortion> differs from the k1 k2 k3 "
                    f"{kappa} after the intrinsics; the file is inconsistent"
                )
            kappa = dist
        ext = _vic3d_numbers(orient.text, where + " <orientation>")
        if len(ext) != 6:
            raise BadInputError(
                f"{where}: <orientation> must hold 6 values (alpha beta gamma [deg], tx ty tz "
                f"[mm]); found {len(ext)}"
            )
        names = ("cx", "cy", "fx", "fy", "fs", "k1", "k2", "k3", "alpha", "beta", "gamma", "tx",
                 "ty", "tz")  # fmt: skip
        values = [*intr[:5], *kappa, *ext]
        bad = [n for n, v in zip(names, values, strict=True) if not np.isfinite(v)]
        if bad:
            raise BadInputError(
                f"{where}: {', '.join(bad)} not finite (NaN/inf); the calibration in the file is "
                "incomplete - recalibrate or export the calibration again from VIC-3D"
            )
        cx, cy, fx, fy, fs = intr[:5]
        if fx <= 0 or fy <= 0:
            raise BadInputError(f"{where}: focal lengths fx={fx}, fy={fy} must be positive [pixel]")
        if ident in cams:
            raise BadInputError(f"VIC-3D calibration '{path}': camera id {ident!r} appears twice")
        K = np.array([[fx, fs, cx], [0, fy, cy], [0, 0, 1.0]])
        dist = np.array([kappa[0], kappa[1], 0.0, 0.0, kappa[2]])
        cams[ident] = (K, dist, cardan_to_matrix(*ext[:3]), np.array(ext[3:]) * 1e-3)
    if len(cams) != 2:
        raise BadInputError(
            f"VIC-3D calibration '{path}': expected 2 <camera> elements, found {len(cams)}"
            + (f" (ids {', '.join(cams)})" if cams else "")
            + "; export the stereo system's calibration (cal.xml) from VIC-3D"
        )
    size = image_size
    if size is None:
        for node in root.iter("polygonmask"):
            if "width" in node.attrib and "height" in node.attrib:
                size = (node.attrib["width"], node.attrib["height"])
                break
    if size is None:
        raise BadInputError(
            f"VIC-3D calibration '{path}' does not state the image size (no <polygonmask "
            "width= height=>); pass image_size=(width, height) (CLI: --image-size W H)"
        )
    size = _check_image_size(size, f"VIC-3D calibration '{path}'")
    ids = sorted(cams, key=lambda s: (0, int(s)) if s.strip().lstrip("-").isdigit() else (1, s))
    out = []
    for ident, name in zip(ids, ("left", "right"), strict=True):
        K = cams[ident][0]
        where = f"VIC-3D calibration '{path}', camera {ident} ({name})"
        if not (0 <= K[0, 2] <= size[0] and 0 <= K[1, 2] <= size[1]):
            raise BadInputError(
                f"{where}: principal point ({K[0, 2]:.1f}, {K[1, 2]:.1f}) px lies outside the "
                f"{size[0]}x{size[1]} px image; the image size is wrong (pass the size of the "
                "images VIC-3D calibrated with: --image-size W H)"
            )
        cam = Camera(*cams[ident], size)
        _check_lens(cam, where)
        out.append(cam)
    return StereoCalibration(
        out[0],
        out[1],
        source=f"vic3d:{path.name}",
        world_frame="VIC-3D world frame (file in millimetres, here metres)",
    )


def read_calibration(
    path: str | Path, *, allow_rejected: bool = False, allow_unitless: bool = False
) -> StereoCalibration:
    """Load a jointwear calibration file (``.nc``, written by ``jointwear dic calibrate``).

    A calibration that failed its sanity checks (``<out>.rejected.nc``) and one whose lengths
    are in board squares (``--unit square``) cannot measure and are refused unless
    ``allow_rejected`` / ``allow_unitless``.
    """
    from jointwear import io

    path = Path(path)
    if path.suffix.lower() in (".yml", ".yaml") or (
        path.suffix.lower() == ".xml"
        and path.exists()
        and "opencv_storage" in path.read_text(errors="replace")[:400]
    ):
        raise BadInputError(
            f"'{path}' looks like an OpenCV calibration; import it first with "
            "`jointwear dic import-calibration --format opencv --length-unit mm` "
            "(or read_opencv_calibration)"
        )
    if path.suffix.lower() in (".xml", ".z3d"):
        raise BadInputError(
            f"'{path}' looks like a VIC-3D calibration; import it first with "
            "`jointwear dic import-calibration --format vic3d` (or read_vic3d_calibration)"
        )
    ds = io.load(path)
    status = str(ds.attrs.get("calibration_status", "accepted"))
    if status.startswith("rejected") and not allow_rejected:
        raise BadInputError(
            f"'{path}' is a calibration that failed its sanity checks ({status}); it was kept "
            "for inspection only - recalibrate (or, if it is right after all, calibrate again "
            "with --accept-poor)"
        )
    cal = StereoCalibration.from_dataset(ds, what=f"'{path}'")
    if cal.length_unit != "m" and not allow_unitless:
        raise BadInputError(
            f"'{path}' has its lengths in board {cal.length_unit}s (calibrated with --unit "
            f"{cal.length_unit}); measuring needs a metric scale - calibrate with the board's "
            "square size, e.g. --square 25 --unit mm"
        )
    return cal


def _check_enough_views(n_ok: int, n_total: int, minimum: int, reasons: list[str]) -> None:
    if n_ok < minimum:
        detail = "; ".join(reasons[:5]) + (" ..." if len(reasons) > 5 else "")
        raise CalibrationError(
            f"only {n_ok} of {n_total} calibration view(s) are usable, at least {minimum} are "
            f"needed ({detail}); record more views with the whole board visible to both "
            "cameras, tilted by 20-45 degrees in different directions and filling the field of view"
        )


def _undistort_impl(target, dist, iterations, out):
    """Invert the distortion model for each row of ``target`` (distorted normalised x, y)."""
    k1, k2, p1, p2, k3, k4, k5, k6 = (
        dist[0],
        dist[1],
        dist[2],
        dist[3],
        dist[4],
        dist[5],
        dist[6],
        dist[7],
    )
    for i in range(target.shape[0]):
        tx = target[i, 0]
        ty = target[i, 1]
        if not (np.isfinite(tx) and np.isfinite(ty)):
            out[i, 0] = np.nan
            out[i, 1] = np.nan
            continue
        x = tx
        y = ty
        for _ in range(iterations):  # fixed point: x = (target - tangential) / radial
            r2 = x * x + y * y
            radial = (1 + r2 * (k1 + r2 * (k2 + r2 * k3))) / (1 + r2 * (k4 + r2 * (k5 + r2 * k6)))
            dx = 2 * p1 * x * y + p2 * (r2 + 2 * x * x)
            dy = p1 * (r2 + 2 * y * y) + 2 * p2 * x * y
            x = (tx - dx) / radial
            y = (ty - dy) / radial
        for _ in range(6):  # Newton polish with the exact Jacobian
            r2 = x * x + y * y
            num = 1 + r2 * (k1 + r2 * (k2 + r2 * k3))
            den = 1 + r2 * (k4 + r2 * (k5 + r2 * k6))
            radial = num / den
            dnum = k1 + r2 * (2 * k2 + 3 * k3 * r2)
            dden = k4 + r2 * (2 * k5 + 3 * k6 * r2)
            drad = (dnum * den - num * dden) / (den * den)  # d radial / d r2
            fx = x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x) - tx
            fy = y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y - ty
            a = radial + 2 * x * x * drad + 2 * p1 * y + 6 * p2 * x
            b = 2 * x * y * drad + 2 * p1 * x + 2 * p2 * y
            c = b
            d = radial + 2 * y * y * drad + 6 * p1 * y + 2 * p2 * x
            det = a * d - b * c
            if abs(det) < 1e-12:
                break
            sx = (d * fx - b * fy) / det
            sy = (-c * fx + a * fy) / det
            x -= sx
            y -= sy
            if abs(sx) + abs(sy) < 1e-16:
                break
        out[i, 0] = x
        out[i, 1] = y


def _undistort(target, dist, iterations, out):
    """Compiled on first use (numba), so importing the calibration module stays light."""
    global _undistort
    from numba import njit

    _undistort = njit(cache=True, nogil=True)(_undistort_impl)
    _undistort(target, dist, iterations, out)
