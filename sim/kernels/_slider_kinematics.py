"""Closed-form kinematics of the in-line slider-crank, compiled by numba.

One source for :func:`jointwear.sim.slider_crank.slider_crank_kinematics` (arrays) and the
ideal-joint kernel in :mod:`jointwear.sim.kernels._slider_crank` (scalars); kept apart from the
kernels so that the kinematics load without them.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["closed_form"]


@njit(cache=True)
def closed_form(theta, l1, l2):
    """Closed-form kinematics of the in-line slider-crank (scalars or arrays of theta).

    Returns the slider position x [m], dx/dtheta, d2x/dtheta2, the rod angle phi (B -> C, from
    +x) and dphi/dtheta, d2phi/dtheta2, from x = L1 cos theta + S, S = sqrt(L2^2 - L1^2
    sin^2 theta), sin phi = -L1 sin theta / L2.
    """
    s = np.sin(theta)
    c = np.cos(theta)
    S = np.sqrt(l2 * l2 - l1 * l1 * s * s)
    x = l1 * c + S
    dx = -l1 * s - l1 * l1 * s * c / S
    ddx = -l1 * c - l1 * l1 * (c * c - s * s) / S - l1**4 * s * s * c * c / S**3
    phi = np.arctan2(-l1 * s, S)
    dphi = -l1 * c / S
    ddphi = l1 * s / S - l1**3 * s * c * c / S**3
    return x, dx, ddx, phi, dphi, ddphi
