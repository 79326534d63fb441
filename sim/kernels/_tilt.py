"""Lumped tilt spring-damper of joint C: the rig's out-of-plane compliance (docs/sim.md)."""

from __future__ import annotations

import math

from jointwear.sim.kernels._jit import inline_kernel


@inline_kernel
def _tilt_spring(u, W, k, c, wrench):
    """Rotational spring-damper resisting the journal's tilt, in the bearing frame.

    The tilt is the rotation vector theta n, n = ez x u / |ez x u|, theta = acos(u_z), that turns
    the bearing axis into the journal axis ``u``; the journal feels the moment -k theta n and
    the damping moment -c W_perp (``W`` the journal's angular velocity relative to the bearing,
    W_perp its part normal to the journal axis: the joint's own rotation is not damped).
    Adds the reaction, a pure moment on the bearing, to ``wrench[3:6]`` and returns the elastic
    energy k theta^2 / 2 [J].
    """
    s = math.sqrt(u[0] * u[0] + u[1] * u[1])
    th = math.atan2(s, u[2])
    ratio = th / s if s > 1e-12 else 1.0  # theta / sin(theta)
    spin = W[0] * u[0] + W[1] * u[1] + W[2] * u[2]
    wrench[3] += k * ratio * (-u[1]) + c * (W[0] - spin * u[0])
    wrench[4] += k * ratio * u[0] + c * (W[1] - spin * u[1])
    wrench[5] += c * (W[2] - spin * u[2])
    return 0.5 * k * th * th
