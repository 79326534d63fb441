"""The clearance joint's side of the mechanism interface.

A mechanism's equations of motion give :func:`clearance_joint` the two bodies' poses and
velocities at the joint (bearing frame and centre, journal centre and axis, relative velocity
and angular velocity) and get back the contact wrench on the bearing; the contact search,
forces, friction and wear work behind it (:mod:`._contact`) know nothing of the mechanism.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from jointwear.sim.kernels._contact import _contact
from jointwear.sim.kernels._layout import CTILT, I_BAD, KTILT
from jointwear.sim.kernels._tilt import _tilt_spring

__all__ = ["clearance_joint"]


@njit(cache=True)
def clearance_joint(Rb, Og, Cj, ug, V0g, Wg, ctx, acc, hstep, FM, J0, u):
    """The clearance joint's side of the mechanism interface: contact wrench from the two poses.

    A mechanism gives the bearing frame ``Rb`` (columns: the bearing's axes, global), the bearing
    centre ``Og``, the journal centre ``Cj`` and axis ``ug`` (global), and the journal body's
    velocity at ``Og`` and angular velocity relative to the bearing body, ``V0g`` and ``Wg``
    (global); ``ctx`` as in :func:`_contact`. Fills ``FM`` with the wrench on the bearing (force,
    moment about ``Og``; global), ``J0`` and ``u`` with the journal centre and axis in the
    bearing frame, and returns (elastic energy, normal force sum, max radial penetration, max
    axial penetration, mode, stiffness at the deepest slice, contacting slices, axial force,
    wrench in the bearing frame).
    """
    info = ctx[10]
    V0 = np.empty(3)
    W = np.empty(3)
    for i in range(3):
        J0[i] = Rb[0, i] * (Cj[0] - Og[0]) + Rb[1, i] * (Cj[1] - Og[1]) + Rb[2, i] * (Cj[2] - Og[2])
        u[i] = Rb[0, i] * ug[0] + Rb[1, i] * ug[1] + Rb[2, i] * ug[2]
        V0[i] = Rb[0, i] * V0g[0] + Rb[1, i] * V0g[1] + Rb[2, i] * V0g[2]
        W[i] = Rb[0, i] * Wg[0] + Rb[1, i] * Wg[1] + Rb[2, i] * Wg[2]
    wrench = np.zeros(12)
    info[I_BAD] = 0.0
    if u[2] < 0.5:
        info[I_BAD] = 1.0
        u[2] = 0.5
    energy, fnsum, pen_rad, pen_ax, mode, kdeep, nslice, fax = _contact(
        J0, u, V0, W, ctx, wrench, acc, hstep
    )
    P = ctx[0]
    if P[KTILT] != 0.0 or P[CTILT] != 0.0:
        energy += _tilt_spring(u, W, P[KTILT], P[CTILT], wrench)
    FM[0] = Rb[0, 0] * wrench[0] + Rb[0, 1] * wrench[1] + Rb[0, 2] * wrench[2]
    FM[1] = Rb[1, 0] * wrench[0] + Rb[1, 1] * wrench[1] + Rb[1, 2] * wrench[2]
    FM[2] = Rb[2, 0] * wrench[0] + Rb[2, 1] * wrench[1] + Rb[2, 2] * wrench[2]
    FM[3] = Rb[0, 0] * wrench[3] + Rb[0, 1] * wrench[4] + Rb[0, 2] * wrench[5]
    FM[4] = Rb[1, 0] * wrench[3] + Rb[1, 1] * wrench[4] + Rb[1, 2] * wrench[5]
    FM[5] = Rb[2, 0] * wrench[3] + Rb[2, 1] * wrench[4] + Rb[2, 2] * wrench[5]
    return energy, fnsum, pen_rad, pen_ax, mode, kdeep, nslice, fax, wrench
