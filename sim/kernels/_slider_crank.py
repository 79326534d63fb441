"""numba kernels of the slider-crank: the mechanism's side of the clearance-joint interface.

The clearance joint (:func:`clearance_joint`) only needs the two bodies' poses and velocities at
the joint: the bearing frame, the journal's centre and axis, their relative velocity; it returns
the contact wrench on the bearing. This module supplies those from the slider-crank's state and
turns the wrench into the bodies' accelerations.

State (11), the same layout as the four-bar's clearance state (positions, rates, rod
orientation, rod angular velocity): theta1, x (slider), theta1_dot, x_dot, q_w, q_x, q_y, q_z
(rod orientation, body -> global), omega_x, omega_y, omega_z (rod angular velocity, body frame).
Rod body axes: y along the rod from its pivot P to the clearance-joint end J, z the joint axis,
x = y cross z; reference orientation (q = 1): rod along +y.

* clearance at rod-slider (C): the rod hangs on the crank pin B (spherical joint; revolute with
  ``planar``), its end J at the slider; the slider is a mass on the x axis pushed by the joint.
* clearance at crank-rod (B): the rod hangs on the slider at C (spherical; revolute with
  ``planar``), its end J at the crank pin; rod and slider move together (coupled equations).

With the pivot P accelerating by a_P = a_P0 + kappa xdd e_x (kappa = 1 when P is on the slider),
Euler's equations about P in body axes read D alpha = M_P - omega x D omega - m rho x R^T a_P
(D = diag(Ix + m c^2, Iy, Iz + m c^2), rho = (0, c, 0), c = L2/2); the slider's x equation closes
the system. Ideal model (2 states: theta1, theta1_dot): closed-form kinematics and the joint
reactions and driver torque from Newton-Euler.
"""

from __future__ import annotations

import math

from jointwear.sim.kernels import _layout as kn
from jointwear.sim.kernels._context import joint_arrays
from jointwear.sim.kernels._geometry import body_rotation
from jointwear.sim.kernels._jit import kernel
from jointwear.sim.kernels._joint import (
    clearance_joint,
    ideal_joint_info,
    joint_frames,
    record_ideal_joint,
    record_joint,
)
from jointwear.sim.kernels._slider_kinematics import closed_form

# ---- integer parameters of the slider-crank (IP slots after the four-bar's) -------------------
SC_CASE = 12  # 0: clearance at rod-slider (C), 1: at crank-rod (B)
SC_BEARING_ROD = 13  # 1: the bearing is on the rod, 0: on the slider (C) or crank (B)
SC_PLANAR = 14  # 1: the rod turns about z only
# ---- diagnostics row of the slider-crank (joint slots shared with the four-bar) ---------------
D_SLIDER_POS, D_SLIDER_VEL, D_SLIDER_ACC = 1, 4, 7
D_CRANK_PIN = 10
D_ROD_POS, D_ROD_VEL = 13, 16
D_ROD_OMEGA = 19
D_ROD_ANGLE, D_DRIVER_TORQUE = 22, 23


@kernel
def _cross(a0, a1, a2, b0, b1, b2):
    return a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0


@kernel
def _eval_slider_clearance(t, y, ctx, dy, acc, hstep, diag):
    """Right-hand side of the slider-crank with the clearance joint; fills ``diag`` if sized."""
    P, IP = ctx[kn.C_P], ctx[kn.C_IP]
    th1, xs, w1, vs = y[0], y[1], y[2], y[3]
    l1, l2, joff = P[kn.L1], P[kn.L2], P[kn.JOFF]
    m1, mr, ms, g = P[kn.M1], P[kn.M2], P[kn.M3], P[kn.GRAV]
    case_b = IP[SC_CASE] == 1
    on_rod = IP[SC_BEARING_ROD] == 1
    c1, s1 = math.cos(th1), math.sin(th1)
    Bx, By = l1 * c1, l1 * s1
    vBx, vBy = -l1 * w1 * s1, l1 * w1 * c1
    R, Rb, Og, Cj, ug, FM, J0, u, wrench = joint_arrays(ctx)
    ob0, ob1, ob2, wgx, wgy, wgz = body_rotation(y, R)  # the rod
    # rod pivot P (position, velocity, acceleration without the slider's unknown xdd)
    if case_b:
        Px, Py, vPx, vPy, aP0x, aP0y = xs, 0.0, vs, 0.0, 0.0, 0.0
    else:
        Px, Py, vPx, vPy = Bx, By, vBx, vBy
        aP0x, aP0y = -l1 * w1 * w1 * c1, -l1 * w1 * w1 * s1
    # rod end J (journal or bearing centre on the rod) and the other body's joint centre
    Jx = Px + l2 * R[0, 1] + joff * R[0, 2]
    Jy = Py + l2 * R[1, 1] + joff * R[1, 2]
    Jz = l2 * R[2, 1] + joff * R[2, 2]
    if case_b:
        Ox, Oy = Bx, By  # crank pin
    else:
        Ox, Oy = xs, 0.0  # slider pin
    # the rod is the spatial body; the other is the crank (x along A -> B) or the slider
    xx, xy, yx, yy = (c1, s1, -s1, c1) if case_b else (1.0, 0.0, 0.0, 1.0)
    joint_frames(on_rod, R, Jx, Jy, Jz, xx, xy, yx, yy, Ox, Oy, joff, Rb, Og, Cj, ug)
    # velocities at Og of the rod-fixed point and of the other body's point
    rx, ry, rz = Og[0] - Px, Og[1] - Py, Og[2]
    vrx = vPx + wgy * rz - wgz * ry
    vry = vPy + wgz * rx - wgx * rz
    vrz = wgx * ry - wgy * rx
    if case_b:  # crank turning about A (the origin)
        vox, voy, woz = -w1 * Og[1], w1 * Og[0], w1
    else:  # slider
        vox, voy, woz = vs, 0.0, 0.0
    if on_rod:  # journal on the other body
        V0g = (vox - vrx, voy - vry, -vrz)
        Wg = (-wgx, -wgy, woz - wgz)
    else:
        V0g = (vrx - vox, vry - voy, vrz)
        Wg = (wgx, wgy, wgz - woz)
    energy, fnsum, pen_rad, pen_ax, mode, kdeep, nslice, fax = clearance_joint(
        Rb, Og, Cj, ug, V0g, Wg, ctx, acc, hstep, FM, J0, u, wrench
    )
    sr = 1.0 if on_rod else -1.0  # sign of the bearing wrench acting on the rod
    Frx, Fry, Frz = sr * FM[0], sr * FM[1], sr * FM[2]
    mx, my, mz = _cross(rx, ry, rz, Frx, Fry, Frz)
    MPx = sr * FM[3] + mx
    MPy = sr * FM[4] + my
    MPz = sr * FM[5] + mz
    # gravity on the rod at rho = c R[:, 1]
    c = 0.5 * l2
    gx, gy, gz = c * R[0, 1], c * R[1, 1], c * R[2, 1]
    MPx += gz * mr * g
    MPz -= gx * mr * g
    # body frame: moment, rho x R^T e_x and rho x R^T a_P0 (rho = (0, c, 0))
    mb0 = R[0, 0] * MPx + R[1, 0] * MPy + R[2, 0] * MPz
    mb1 = R[0, 1] * MPx + R[1, 1] * MPy + R[2, 1] * MPz
    mb2 = R[0, 2] * MPx + R[1, 2] * MPy + R[2, 2] * MPz
    ex0, ex2 = R[0, 0], R[0, 2]  # R^T e_x (its y component does not enter rho x .)
    a0 = R[0, 0] * aP0x + R[1, 0] * aP0y
    a2 = R[0, 2] * aP0x + R[1, 2] * aP0y
    Dx = P[kn.I3X] + mr * c * c
    Dy = P[kn.I3Y]
    Dz = P[kn.I3Z] + mr * c * c
    # rho x v = (c v2, 0, -c v0)
    gb0 = (mb0 - (Dz - Dy) * ob1 * ob2 - mr * c * a2) / Dx
    gb1 = (mb1 - (Dx - Dz) * ob2 * ob0) / Dy
    gb2 = (mb2 - (Dy - Dx) * ob0 * ob1 + mr * c * a0) / Dz
    kb0, kb2 = c * ex2, -c * ex0  # k = rho x R^T e_x
    hb0, hb2 = mr * kb0 / Dx, mr * kb2 / Dz
    if IP[SC_PLANAR] == 1:
        gb0, gb1, hb0 = 0.0, 0.0, 0.0
    # omega x (omega x rho), global x component
    wrx, wry, wrz = _cross(wgx, wgy, wgz, gx, gy, gz)
    cx_, _, _ = _cross(wgx, wgy, wgz, wrx, wry, wrz)
    Fsx = -Frx  # the joint force on the other body (slider or crank), x component
    if case_b:
        den = ms + mr - mr * (hb0 * kb0 + hb2 * kb2)
        xdd = (Frx - mr * (gb0 * kb0 + gb2 * kb2) - mr * cx_) / den
        al0, al1, al2 = gb0 - hb0 * xdd, gb1, gb2 - hb2 * xdd
    else:
        xdd = Fsx / ms
        al0, al1, al2 = gb0, gb1, gb2
    dy[0] = w1
    dy[1] = vs
    dy[2] = 0.0
    dy[3] = xdd
    q0, q1, q2, q3 = y[4], y[5], y[6], y[7]
    dy[4] = -0.5 * (q1 * ob0 + q2 * ob1 + q3 * ob2)
    dy[5] = 0.5 * (q0 * ob0 + q2 * ob2 - q3 * ob1)
    dy[6] = 0.5 * (q0 * ob1 + q3 * ob0 - q1 * ob2)
    dy[7] = 0.5 * (q0 * ob2 + q1 * ob1 - q2 * ob0)
    dy[8] = al0
    dy[9] = al1
    dy[10] = al2
    if diag.shape[0] == 0:
        return
    for i in range(kn.ND_DIAG):
        diag[i] = 0.0
    # rod centre of mass: velocity and acceleration
    vgx = vPx + wgy * gz - wgz * gy
    vgy = vPy + wgz * gx - wgx * gz
    vgz = wgx * gy - wgy * gx
    agl0 = R[0, 0] * al0 + R[0, 1] * al1 + R[0, 2] * al2
    agl1 = R[1, 0] * al0 + R[1, 1] * al1 + R[1, 2] * al2
    agl2 = R[2, 0] * al0 + R[2, 1] * al1 + R[2, 2] * al2
    ax_, ay_, _ = _cross(agl0, agl1, agl2, gx, gy, gz)
    _, cy_, _ = _cross(wgx, wgy, wgz, wrx, wry, wrz)
    aPx = aP0x + (xdd if case_b else 0.0)
    acx, acy = aPx + ax_ + cx_, aP0y + ay_ + cy_
    # driver torque: the crank's moment balance about A (constant speed)
    if case_b:  # the joint acts on the crank directly
        Fcx, Fcy = -Frx, -Fry
        Mcz = -sr * FM[5] + Og[0] * Fcy - Og[1] * Fcx
    else:  # the rod's pivot force on the crank: -(m a_G - F_contact - weight)
        Fcx = -(mr * acx - Frx)
        Fcy = -(mr * acy - Fry + mr * g)
        Mcz = Bx * Fcy - By * Fcx
    tau = -(Mcz - m1 * g * 0.5 * l1 * c1)
    diag[kn.D_TH1] = th1
    diag[D_SLIDER_POS] = xs
    diag[D_SLIDER_VEL] = vs
    diag[D_SLIDER_ACC] = xdd
    diag[D_CRANK_PIN], diag[D_CRANK_PIN + 1] = Bx, By
    diag[D_ROD_POS], diag[D_ROD_POS + 1], diag[D_ROD_POS + 2] = Px + gx, Py + gy, gz
    diag[D_ROD_VEL], diag[D_ROD_VEL + 1], diag[D_ROD_VEL + 2] = vgx, vgy, vgz
    diag[D_ROD_OMEGA], diag[D_ROD_OMEGA + 1], diag[D_ROD_OMEGA + 2] = wgx, wgy, wgz
    diag[D_ROD_ANGLE] = math.atan2(R[1, 1], R[0, 1])
    diag[D_DRIVER_TORQUE] = tau
    record_joint(diag, y, Og, Cj, FM, J0, u, wrench, pen_rad, pen_ax, mode, kdeep, nslice, fax)
    T = 0.5 * (P[kn.I1] + 0.25 * m1 * l1 * l1) * w1 * w1 + 0.5 * ms * vs * vs
    T += 0.5 * mr * (vgx * vgx + vgy * vgy + vgz * vgz)
    T += 0.5 * (P[kn.I3X] * ob0 * ob0 + P[kn.I3Y] * ob1 * ob1 + P[kn.I3Z] * ob2 * ob2)
    V = g * (0.5 * m1 * By + mr * (Py + gy))
    diag[kn.D_ENERGY] = T + V + energy


@kernel
def _eval_slider_ideal(t, y, ctx, dy, diag):
    """Ideal joints: the crank at constant speed; joint reactions and driver torque (Newton-Euler).

    Unknowns: F_B and F_C, the forces on the rod from the crank and the slider, and the driver
    torque. Rod: m a_G = F_B + F_C + m g and I phi_dd = (B - G) x F_B + (C - G) x F_C; slider x:
    m_s x_dd = -F_Cx; crank about A: 0 = tau - (B x F_B)_z - m1 g (L1/2) cos theta.
    """
    P, IP = ctx[kn.C_P], ctx[kn.C_IP]
    th1, w1 = y[0], y[1]
    dy[0] = w1
    dy[1] = 0.0
    ideal_joint_info(ctx[kn.C_INFO])
    if diag.shape[0] == 0:
        return
    l1, l2, joff = P[kn.L1], P[kn.L2], P[kn.JOFF]
    m1, mr, ms, g = P[kn.M1], P[kn.M2], P[kn.M3], P[kn.GRAV]
    s1, c1 = math.sin(th1), math.cos(th1)
    x, dx, ddx, phi, dphi, ddphi = closed_form(th1, l1, l2)
    cp, sp = math.cos(phi), math.sin(phi)
    h = 0.5 * l2
    wphi = dphi * w1
    aphi = ddphi * w1 * w1
    # rod centre G = B + h e_phi
    aGx = -l1 * w1 * w1 * c1 - h * (aphi * sp + wphi * wphi * cp)
    aGy = -l1 * w1 * w1 * s1 + h * (aphi * cp - wphi * wphi * sp)
    Qx, Qy = mr * aGx, mr * (aGy + g)
    FCx = -ms * ddx * w1 * w1
    FBx = Qx - FCx
    dCx, dCy = h * cp, h * sp  # C - G = -(B - G)
    FCy = (P[kn.I3Z] * aphi + dCx * Qy - dCy * FBx + dCy * FCx) / (2.0 * dCx)
    FBy = Qy - FCy
    Bxf, Byf = l1 * c1, l1 * s1
    tau = Bxf * FBy - Byf * FBx + m1 * g * 0.5 * l1 * c1
    for i in range(kn.ND_DIAG):
        diag[i] = 0.0
    # force on the bearing at the clearance-joint location
    on_rod = IP[SC_BEARING_ROD] == 1
    if IP[SC_CASE] == 1:  # joint B: on the rod F_B, on the crank -F_B
        Fx, Fy = (FBx, FBy) if on_rod else (-FBx, -FBy)
        bx, by = Bxf, Byf
    else:  # joint C: on the rod F_C, on the slider -F_C
        Fx, Fy = (FCx, FCy) if on_rod else (-FCx, -FCy)
        bx, by = x, 0.0
    diag[kn.D_TH1] = th1
    diag[D_SLIDER_POS] = x
    diag[D_SLIDER_VEL] = dx * w1
    diag[D_SLIDER_ACC] = ddx * w1 * w1
    diag[D_CRANK_PIN], diag[D_CRANK_PIN + 1] = Bxf, Byf
    diag[D_ROD_POS], diag[D_ROD_POS + 1] = Bxf + h * cp, Byf + h * sp
    diag[D_ROD_VEL] = -l1 * w1 * s1 - h * wphi * sp
    diag[D_ROD_VEL + 1] = l1 * w1 * c1 + h * wphi * cp
    diag[D_ROD_OMEGA + 2] = wphi
    diag[D_ROD_ANGLE] = phi
    diag[D_DRIVER_TORQUE] = tau
    record_ideal_joint(diag, bx, by, bx, by, joff, Fx, Fy, phi)
    vGx, vGy = diag[D_ROD_VEL], diag[D_ROD_VEL + 1]
    T = 0.5 * (P[kn.I1] + 0.25 * m1 * l1 * l1) * w1 * w1 + 0.5 * ms * (dx * w1) ** 2
    T += 0.5 * mr * (vGx * vGx + vGy * vGy) + 0.5 * P[kn.I3Z] * wphi * wphi
    diag[kn.D_ENERGY] = T + g * (0.5 * m1 * Byf + mr * (Byf + h * sp))


@kernel
def eval_slider_crank(t, y, ctx, dy, acc, hstep, diag):
    """Right-hand side of the slider-crank (clearance or ideal model, ``IP[IDEAL]``)."""
    if ctx[kn.C_IP][kn.IDEAL] == 1:
        _eval_slider_ideal(t, y, ctx, dy, diag)
    else:
        _eval_slider_clearance(t, y, ctx, dy, acc, hstep, diag)
