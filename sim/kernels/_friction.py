"""Smoothed Coulomb friction in the kernels (eq. 12): the coefficient and the tangential
force it adds to the contact wrench.
"""

from __future__ import annotations

import math

from jointwear.sim.kernels._geometry import W_FRICTION, _add_force
from jointwear.sim.kernels._jit import inline_kernel, kernel
from jointwear.sim.kernels._layout import MUD, MUS, VD, VS


@kernel
def friction_coefficient(v, mus, mud, vs, vd):
    """Eq. 12: smoothed Coulomb friction coefficient at sliding speed v >= 0 [m/s]."""
    if v < vs:
        return mus * math.sin(0.5 * math.pi * v / vs)
    if v <= vd:
        return mud + (mus - mud) * 0.5 * (1.0 + math.cos(math.pi * (v - vs) / (vd - vs)))
    return mud


@inline_kernel
def _apply_friction(wrench, px, py, pz, tx, ty, tz, fn, muon, P):
    """Add the friction of eq. 12 at a contact to ``wrench``; return the sliding speed |v_t|.

    (tx, ty, tz) is the relative tangential velocity at the contact point (px, py, pz), fn the
    normal force [N]; the force mu(|v_t|) fn along v_t goes into both force slots and its
    moment into the moment slot, exactly as the contact branches did inline.
    """
    vt = math.sqrt(tx * tx + ty * ty + tz * tz)
    if muon > 0.0 and vt > 0.0:
        mu = friction_coefficient(vt, P[MUS], P[MUD], P[VS], P[VD])
        s = mu * fn / vt
        _add_force(wrench, px, py, pz, tx, ty, tz, s, W_FRICTION)
    return vt
