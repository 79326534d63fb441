"""Camera models and stereo calibration: projection, undistortion, (de)serialisation.

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
    "DISTORTION_NAMES",
]

#: OpenCV's order of the distortion coefficients jointwear supports.
DISTORTION_NAMES = ("k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6")


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
        ``"rejected: <problems>"`` (see :mod:`jointwear.dic.calibration._gate`).
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
