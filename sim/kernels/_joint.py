"""The clearance joint's side of the mechanism interface.

A mechanism's equations of motion give :func:`clearance_joint` the two bodies' poses and
velocities at the joint (bearing frame and centre, journal centre and axis, relative velocity
and angular velocity) and get back the contact wrench on the bearing; the contact search,
forces, friction and wear work behind it (:mod:`._contact`) know nothing of the mechanism.
:func:`joint_frames` builds those poses for a joint between a spatial and a planar body (both
mechanisms have one); :func:`record_joint`, :func:`record_ideal_joint` and
:func:`ideal_joint_info` write the joint's part of the diagnostics and info, the same for every
mechanism.
"""

from __future__ import annotations

import math

from jointwear.sim.kernels._contact import _contact
from jointwear.sim.kernels._jit import inline_kernel, kernel
from jointwear.sim.kernels._layout import (
    C_INFO,
    C_P,
    C_VEC,
    CTILT,
    D_AXIS,
    D_BEAR_POS,
    D_FAX,
    D_FMAG,
    D_FN,
    D_FORCE,
    D_FT,
    D_JOUR_POS,
    D_K,
    D_MODE,
    D_NSLICE,
    D_OFFSET,
    D_PEN,
    D_PENAX,
    D_QUAT,
    D_TILT,
    I_BAD,
    I_CONTACT,
    I_PEN,
    KTILT,
    MODE_IDEAL,
    V_V0,
    V_W,
)
from jointwear.sim.kernels._tilt import _tilt_spring

__all__ = [
    "joint_frames",
    "clearance_joint",
    "record_joint",
    "ideal_joint_info",
    "record_ideal_joint",
]


@inline_kernel
def joint_frames(on_spatial, R, sx, sy, sz, xx, xy, yx, yy, qx, qy, qz, Rb, Og, Cj, ug):
    """Fill the bearing frame ``Rb``, bearing centre ``Og``, journal centre ``Cj`` and journal
    axis ``ug`` (global) of a joint between a spatial body and a planar one.

    The spatial body is turned by ``R`` (body -> global; its z axis is its joint axis) and has
    its joint centre at (``sx``, ``sy``, ``sz``); the planar body turns about +z, its x and y
    axes are (``xx``, ``xy``, 0) and (``yx``, ``yy``, 0), its joint centre is at (``qx``,
    ``qy``, ``qz``).
    The bearing is on the spatial body if ``on_spatial``, else on the planar body.
    """
    if on_spatial:
        for i in range(3):
            for j in range(3):
                Rb[i, j] = R[i, j]
        Og[0], Og[1], Og[2] = sx, sy, sz
        Cj[0], Cj[1], Cj[2] = qx, qy, qz
        ug[0], ug[1], ug[2] = 0.0, 0.0, 1.0
    else:
        Rb[0, 0], Rb[1, 0], Rb[2, 0] = xx, xy, 0.0
        Rb[0, 1], Rb[1, 1], Rb[2, 1] = yx, yy, 0.0
        Rb[0, 2], Rb[1, 2], Rb[2, 2] = 0.0, 0.0, 1.0
        Og[0], Og[1], Og[2] = qx, qy, qz
        Cj[0], Cj[1], Cj[2] = sx, sy, sz
        ug[0], ug[1], ug[2] = R[0, 2], R[1, 2], R[2, 2]


@kernel
def clearance_joint(Rb, Og, Cj, ug, V0g, Wg, ctx, acc, hstep, FM, J0, u, wrench):
    """The clearance joint's side of the mechanism interface: contact wrench from the two poses.

    A mechanism gives the bearing frame ``Rb`` (columns: the bearing's axes, global), the bearing
    centre ``Og``, the journal centre ``Cj`` and axis ``ug`` (global), and the journal body's
    velocity at ``Og`` and angular velocity relative to the bearing body, ``V0g`` and ``Wg``
    (global); ``ctx`` as in :func:`_contact`. Fills ``FM`` with the wrench on the bearing (force,
    moment about ``Og``; global), ``J0`` and ``u`` with the journal centre and axis in the
    bearing frame, and ``wrench`` with the contact wrench in the bearing frame (12, as
    :func:`_contact` adds to it); returns (elastic energy, normal force sum, max radial
    penetration, max axial penetration, mode, stiffness at the deepest slice, contacting slices,
    axial force). The out arrays are the context's scratch arrays
    (:func:`._context.joint_arrays`); the relative velocity and angular velocity in the bearing
    frame, which only the contact reads, are the context's too.
    """
    info = ctx[C_INFO]
    V0, W = ctx[C_VEC][V_V0], ctx[C_VEC][V_W]
    for i in range(3):
        J0[i] = Rb[0, i] * (Cj[0] - Og[0]) + Rb[1, i] * (Cj[1] - Og[1]) + Rb[2, i] * (Cj[2] - Og[2])
        u[i] = Rb[0, i] * ug[0] + Rb[1, i] * ug[1] + Rb[2, i] * ug[2]
        V0[i] = Rb[0, i] * V0g[0] + Rb[1, i] * V0g[1] + Rb[2, i] * V0g[2]
        W[i] = Rb[0, i] * Wg[0] + Rb[1, i] * Wg[1] + Rb[2, i] * Wg[2]
    wrench[:] = 0.0
    info[I_BAD] = 0.0
    if u[2] < 0.5:
        info[I_BAD] = 1.0
        u[2] = 0.5
    energy, fnsum, pen_rad, pen_ax, mode, kdeep, nslice, fax = _contact(
        J0, u, V0, W, ctx, wrench, acc, hstep
    )
    P = ctx[C_P]
    if P[KTILT] != 0.0 or P[CTILT] != 0.0:
        energy += _tilt_spring(u, W, P[KTILT], P[CTILT], wrench)
    FM[0] = Rb[0, 0] * wrench[0] + Rb[0, 1] * wrench[1] + Rb[0, 2] * wrench[2]
    FM[1] = Rb[1, 0] * wrench[0] + Rb[1, 1] * wrench[1] + Rb[1, 2] * wrench[2]
    FM[2] = Rb[2, 0] * wrench[0] + Rb[2, 1] * wrench[1] + Rb[2, 2] * wrench[2]
    FM[3] = Rb[0, 0] * wrench[3] + Rb[0, 1] * wrench[4] + Rb[0, 2] * wrench[5]
    FM[4] = Rb[1, 0] * wrench[3] + Rb[1, 1] * wrench[4] + Rb[1, 2] * wrench[5]
    FM[5] = Rb[2, 0] * wrench[3] + Rb[2, 1] * wrench[4] + Rb[2, 2] * wrench[5]
    return energy, fnsum, pen_rad, pen_ax, mode, kdeep, nslice, fax


@kernel
def record_joint(diag, y, Og, Cj, FM, J0, u, wrench, pen_rad, pen_ax, mode, kdeep, nslice, fax):
    """Write the clearance joint's slots of the diagnostics row, the same for every mechanism.

    ``Og``, ``Cj``, ``FM``, ``J0``, ``u`` and the scalars as given to and returned by
    :func:`clearance_joint`; ``y`` the clearance state, whose components 4-7 are the orientation
    quaternion of the journal's body (recorded normalised).
    """
    for i in range(3):
        diag[D_OFFSET + i] = J0[i]
        diag[D_AXIS + i] = u[i]
        diag[D_BEAR_POS + i] = Og[i]
        diag[D_JOUR_POS + i] = Cj[i]
        diag[D_FORCE + i] = FM[i]
    diag[D_TILT] = math.acos(min(1.0, u[2]))
    diag[D_FN] = math.sqrt(wrench[6] * wrench[6] + wrench[7] * wrench[7] + wrench[8] * wrench[8])
    diag[D_FMAG] = math.sqrt(FM[0] * FM[0] + FM[1] * FM[1] + FM[2] * FM[2])
    diag[D_FT] = math.sqrt(
        wrench[9] * wrench[9] + wrench[10] * wrench[10] + wrench[11] * wrench[11]
    )
    diag[D_MODE] = mode
    diag[D_PEN] = pen_rad
    diag[D_PENAX] = pen_ax
    diag[D_K] = kdeep
    diag[D_NSLICE] = nslice
    diag[D_FAX] = fax
    n = math.sqrt(y[4] * y[4] + y[5] * y[5] + y[6] * y[6] + y[7] * y[7])
    for i in range(4):
        diag[D_QUAT + i] = y[4 + i] / n


@kernel
def record_ideal_joint(diag, bx, by, jx, jy, joff, Fx, Fy, angle):
    """Write the joint's slots of the diagnostics row for the ideal (planar) joint.

    Bearing centre (``bx``, ``by``, ``joff``), journal centre (``jx``, ``jy``, ``joff``), axis
    +z, reaction force (``Fx``, ``Fy``, 0) on the bearing, mode ideal, no penetration; the
    journal's body turned by ``angle`` about z (its y axis from +x) as its quaternion.
    """
    diag[D_BEAR_POS], diag[D_BEAR_POS + 1], diag[D_BEAR_POS + 2] = bx, by, joff
    diag[D_JOUR_POS], diag[D_JOUR_POS + 1], diag[D_JOUR_POS + 2] = jx, jy, joff
    diag[D_AXIS + 2] = 1.0
    diag[D_FORCE], diag[D_FORCE + 1] = Fx, Fy
    diag[D_FN] = math.sqrt(Fx * Fx + Fy * Fy)
    diag[D_FMAG] = diag[D_FN]
    diag[D_MODE] = MODE_IDEAL
    diag[D_PEN] = 0.0
    a = 0.5 * (angle - 0.5 * math.pi)
    diag[D_QUAT], diag[D_QUAT + 3] = math.cos(a), math.sin(a)


@kernel
def ideal_joint_info(info):
    """Set the per-evaluation ``info`` of the ideal joint: no contact, no penetration, valid."""
    info[I_PEN] = -1.0
    info[I_CONTACT] = 0.0
    info[I_BAD] = 0.0
