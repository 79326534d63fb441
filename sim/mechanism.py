"""Kinematics of the four-bar linkage: loop closure of the ideal (planar) mechanism.

Ground pivot A at the origin, D at (L4, 0, 0); crank angle theta1, coupler angle theta2 and
follower angle theta3 are measured from +x, counter-clockwise (rad). The assembly branch is the
one with joint C above the ground line (y > 0), as on the rig.
"""

from __future__ import annotations

import numpy as np

from jointwear.errors import ParameterError
from jointwear.sim.parameters import MechanismParameters

__all__ = ["loop_closure", "quaternion_to_matrix", "rotation_xzy_angles"]


def loop_closure(
    theta1: np.ndarray | float, mech: MechanismParameters, theta1_dot: float | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Coupler and follower angles (and rates) of the ideal four-bar for given crank angles.

    Parameters
    ----------
    theta1 : array_like
        Crank angle(s) [rad] from +x, counter-clockwise.
    mech : MechanismParameters
        Link lengths [m].
    theta1_dot : float, optional
        Crank rate [rad/s]; defaults to the nominal crank speed.

    Returns
    -------
    theta2, theta3, theta2_dot, theta3_dot : ndarray
        Coupler and follower angles [rad] and angular velocities [rad/s].
    """
    L1, L2, L3, L4 = (
        mech.crank_length,
        mech.coupler_length,
        mech.follower_length,
        mech.ground_length,
    )
    w1 = mech.crank_speed if theta1_dot is None else theta1_dot
    t1 = np.asarray(theta1, dtype=float)
    bx, by = L1 * np.cos(t1), L1 * np.sin(t1)
    # C is at distance L2 from B and L3 from D: intersection of two circles
    dx, dy = L4 - bx, -by
    d = np.hypot(dx, dy)
    a = (L2**2 - L3**2 + d**2) / (2 * d)
    h2 = L2**2 - a**2
    if np.any(h2 < 0):
        raise ParameterError(
            "mechanism: the links cannot be assembled at some crank angle; check the lengths"
        )
    h = np.sqrt(h2)
    mx, my = bx + a * dx / d, by + a * dy / d
    # the two intersections; take the one with C above the ground line
    c1x, c1y = mx - h * dy / d, my + h * dx / d
    c2x, c2y = mx + h * dy / d, my - h * dx / d
    up = c1y >= c2y
    cx, cy = np.where(up, c1x, c2x), np.where(up, c1y, c2y)
    th2 = np.arctan2(cy - by, cx - bx)
    th3 = np.arctan2(cy, cx - L4)
    # velocities: L1 w1 e1p + L2 w2 e2p = L3 w3 e3p
    s12 = np.sin(th3 - th2)
    w2 = L1 * w1 * np.sin(t1 - th3) / (L2 * s12)
    w3 = L1 * w1 * np.sin(t1 - th2) / (L3 * s12)
    return th2, th3, w2, w3


def quaternion_to_matrix(q: np.ndarray) -> np.ndarray:
    """Rotation matrices (..., 3, 3) of unit quaternions (..., 4) ordered (w, x, y, z)."""
    q = np.asarray(q, dtype=float)
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    w, x, y, z = np.moveaxis(q, -1, 0)
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
            np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
            np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
        ],
        -2,
    )


def rotation_xzy_angles(R: np.ndarray) -> np.ndarray:
    """Angles (about x, about y, about z) [rad] such that R = Rx(ax) Rz(az) Ry(ay) (eq. 4 order)."""
    R = np.asarray(R, dtype=float)
    az = np.arcsin(np.clip(-R[..., 0, 1], -1.0, 1.0))
    ax = np.arctan2(R[..., 2, 1], R[..., 1, 1])
    ay = np.arctan2(R[..., 0, 2], R[..., 0, 0])
    return np.stack([ax, ay, az], -1)
