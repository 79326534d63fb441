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

from jointwear.datasets._rig_config import CODECS, RigConfig  # noqa: F401 (re-exported)
from jointwear.errors import BadInputError

L1, L2, L3, L4 = 0.10, 0.40, 0.30, 0.30


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
