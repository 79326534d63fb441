"""Motion of the virtual rig: the rig's configuration and the four-bar's analytic pose.

:class:`RigConfig` (cameras, patches, motion, rendering options), the prescribed
out-of-plane motion of joint C (:class:`PrescribedMotion`), and :func:`fourbar_pose`, the
analytic planar kinematics with that motion, from which the ground truth and its time
derivatives come. Rendering and files are in :mod:`jointwear.datasets.rig`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import xarray as xr

from jointwear.errors import BadInputError
from jointwear.params import check_fields, positive

L1, L2, L3, L4 = 0.10, 0.40, 0.30, 0.30

#: Video codecs the bundled OpenCV/FFmpeg can write here: name -> (fourcc, extension, lossless).
#: Decoding one 1280 x 1024 grey frame here: grey (raw) 4 ms, mp4v 5 ms, mjpg 7 ms, png 21 ms,
#: ffv1 38 ms; mjpg and mp4v as written by OpenCV are lossy (errors of 30+ grey levels on speckle).
CODECS: dict[str, tuple[str, str, bool]] = {
    "ffv1": ("FFV1", ".avi", True),
    "mjpg": ("MJPG", ".avi", False),
    "mp4v": ("mp4v", ".mp4", False),
    "png": ("png ", ".avi", True),
    "grey": ("GREY", ".avi", True),
}


@dataclass(frozen=True)
class RigConfig:
    """Parameters of the virtual rig (SI units; pixel quantities say so).

    The defaults describe a rig like the study's: two 1280 x 1024 cameras 1.0 m from the
    mechanism plane, 0.30 m apart (toe-in towards ``look_at``), a 0.42 m x 0.34 m field of view
    (0.33 mm per pixel) covering the follower and joint C, 50 frames/s.
    """

    width: int = 1280
    height: int = 1024
    fov_width: float = 0.42
    distance: float = 1.0
    baseline: float = 0.30
    look_at: tuple[float, float, float] = (0.29, 0.16, 0.0)
    distortion: tuple[float, float, float, float, float] = (-0.08, 0.10, 2e-4, -1e-4, 0.0)
    principal_offset_px: tuple[float, float] = (6.0, -4.0)
    fps: float = positive(50.0)
    duration: float = positive(1.0)
    crank_speed_rpm: float = 120.0
    crank_angle0_deg: float = 30.0
    z_amplitude: float = 2.5e-3
    z_phase_deg: float = 0.0
    journal_size: float = 0.04
    journal_z: float = 0.02
    crank_z: float = 0.03
    follower_width: float = 0.03
    speckle_size: float | None = None
    noise_sigma: float = 1.0
    blur_sigma_px: float = 0.6
    exposure: float = 1.0
    exposure_time: float = 2e-4
    motion_blur_samples: int = 1
    background: float = 40.0
    seed: int = 0
    drop_frames: tuple[int, ...] = ()
    duplicate_frames: tuple[int, ...] = ()
    board_squares: tuple[int, int] = (10, 8)
    board_square_size: float = 0.025
    board_views: int = 12
    board_kind: str = "chessboard"
    board_marker_size: float = 0.01875
    board_dictionary: str = "DICT_5X5_100"
    board_legacy: bool = False

    def __post_init__(self) -> None:
        if self.width < 64 or self.height < 64:
            raise BadInputError(f"rig image size {self.width}x{self.height} is too small")
        check_fields(self, "rig")
        if self.motion_blur_samples < 1:
            raise BadInputError("motion_blur_samples must be >= 1")
        if self.board_kind not in ("chessboard", "charuco"):
            raise BadInputError(
                f"board_kind {self.board_kind!r}: expected 'chessboard' or 'charuco'"
            )

    @property
    def focal_px(self) -> float:
        """Focal length [pixel] giving ``fov_width`` at ``distance``."""
        return self.width * self.distance / self.fov_width

    @property
    def n_frames(self) -> int:
        return int(round(self.duration * self.fps))

    @property
    def omega(self) -> float:
        """Crank angular speed [rad/s]."""
        return self.crank_speed_rpm * 2 * np.pi / 60.0


# ---------------------------------------------------------------------------------------------
# kinematics
def _rz(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _ry(b: float) -> np.ndarray:
    c, s = np.cos(b), np.sin(b)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


@dataclass(frozen=True, eq=False)
class PrescribedMotion:
    """Motion taken from data (e.g. a simulator output) instead of the analytic default.

    ``crank_angle(t)`` [rad] and ``z_c(t)`` [m] (out-of-plane position of joint C) are
    callables; None keeps the analytic one (constant crank speed, sinusoidal z).
    """

    crank_angle: Any = None
    z_c: Any = None

    @classmethod
    def from_dataset(cls, ds: xr.Dataset) -> PrescribedMotion:
        """Cubic-spline interpolants of a Dataset's ``crank_angle`` [rad] and of the
        out-of-plane motion of joint C, from ``journal_position``/``journal_displacement``
        (z) or, for a follower hanging on its spherical joint, twice ``follower_position`` z."""
        from scipy.interpolate import CubicSpline

        if "time" not in ds.coords or ds.sizes.get("time", 0) < 4:
            raise BadInputError("motion dataset needs a 'time' coordinate with at least 4 samples")
        t = np.asarray(ds["time"].values, dtype=float)
        theta = z = None
        if "crank_angle" in ds:
            theta = CubicSpline(t, np.unwrap(np.asarray(ds["crank_angle"].values, dtype=float)))
        for name, factor in (
            ("journal_position", 1.0),
            ("journal_displacement", 1.0),
            ("follower_position", 2.0),
        ):
            if name in ds and "axis" in ds[name].dims:
                z = CubicSpline(t, factor * np.asarray(ds[name].sel(axis="z").values, dtype=float))
                break
        if theta is None and z is None:
            raise BadInputError(
                "motion dataset has neither 'crank_angle' nor an out-of-plane motion "
                "('journal_position', 'journal_displacement' or 'follower_position' with axis z)"
            )
        return cls(theta, z)


def fourbar_pose(
    t: float, cfg: RigConfig, motion: PrescribedMotion | None = None
) -> dict[str, Any]:
    """Poses of the rig's bodies at time ``t`` [s] (mechanism frame).

    Returns a dict with ``crank_angle`` [rad], ``B``, ``C`` (joint positions [m]), and per body
    ``(R, p)``: rotation and origin of the body frame (``X = R x_body + p``).
    """
    if motion is not None and motion.crank_angle is not None:
        th1 = float(motion.crank_angle(t))
    else:
        th1 = np.deg2rad(cfg.crank_angle0_deg) + cfg.omega * t
    B = np.array([L1 * np.cos(th1), L1 * np.sin(th1)])
    D = np.array([L4, 0.0])
    d = np.linalg.norm(D - B)
    a = (L2**2 - L3**2 + d**2) / (2 * d)
    h = np.sqrt(max(L2**2 - a**2, 0.0))
    e = (D - B) / d
    C = B + a * e + h * np.array([-e[1], e[0]])
    phi3 = np.arctan2(C[1] - D[1], C[0] - D[0])
    phi2 = np.arctan2(C[1] - B[1], C[0] - B[0])
    if motion is not None and motion.z_c is not None:
        zc = float(motion.z_c(t))
    else:
        zc = cfg.z_amplitude * np.sin(cfg.omega * t + np.deg2rad(cfg.z_phase_deg))
    psi = np.arcsin(np.clip(zc / L3, -1, 1))
    R_f = _rz(phi3) @ _ry(-psi)
    C3 = np.array([D[0], D[1], 0.0]) + L3 * R_f[:, 0]
    return {
        "crank_angle": th1,
        "B": np.array([B[0], B[1], 0.0]),
        "C": C3,
        "follower": (R_f, np.array([D[0], D[1], 0.0])),
        "journal": (_rz(phi2), C3 + np.array([0.0, 0.0, cfg.journal_z])),
        "crank": (_rz(th1), np.array([0.0, 0.0, cfg.crank_z])),
        "follower_centroid": np.array([D[0], D[1], 0.0]) + 0.5 * L3 * R_f[:, 0],
    }


def _truth_state(t: float, cfg: RigConfig, motion=None) -> dict[str, np.ndarray]:
    p = fourbar_pose(t, cfg, motion)
    return {
        "follower_position": p["follower_centroid"],
        "journal_position": p["journal"][1],
        "crank_angle": np.array([p["crank_angle"]]),
    }


def _truth_derivative(
    t: float, cfg: RigConfig, key: str, motion=None, h: float = 1e-5
) -> np.ndarray:
    """4th-order central difference of an analytic quantity (truncation error ~1e-12 m/s)."""
    f = [_truth_state(t + k * h, cfg, motion)[key] for k in (-2, -1, 1, 2)]
    return (f[0] - 8 * f[1] + 8 * f[2] - f[3]) / (12 * h)
