"""Equations of motion in the kernels: right-hand sides of the clearance model (11 states)
and of the ideal model (6 states).
"""

from __future__ import annotations

import math

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
from jointwear.sim.kernels._layout import (
    BAUM,
    C_INFO,
    C_IP,
    C_P,
    D_COUP_POS,
    D_COUP_VEL,
    D_CRANK_POS,
    D_CRANK_VEL,
    D_ENERGY,
    D_FOLL_OMEGA,
    D_FOLL_POS,
    D_FOLL_VEL,
    D_TH1,
    D_TH2,
    D_TH2DOT,
    D_TH3,
    DRIVER,
    GRAV,
    I1,
    I2,
    I3X,
    I3Y,
    I3Z,
    IDEAL,
    JOFF,
    L1,
    L2,
    L3,
    L4,
    M1,
    M2,
    M3,
    MECH,
    MECH_SLIDER_CRANK,
    ND_DIAG,
    ON_COUPLER,
)
from jointwear.sim.kernels._slider_crank import eval_slider_crank


@kernel
def _eval_clearance(t, y, ctx, dy, acc, hstep, diag):
    """Right-hand side of the clearance model; optionally accumulates wear work / fills diag."""
    P, IP = ctx[C_P], ctx[C_IP]
    th1, th2, w1, w2 = y[0], y[1], y[2], y[3]
    c1, s1 = math.cos(th1), math.sin(th1)
    c2, s2 = math.cos(th2), math.sin(th2)
    l1, l2, l3, l4 = P[L1], P[L2], P[L3], P[L4]
    Bx, By = l1 * c1, l1 * s1
    vBx, vBy = -l1 * w1 * s1, l1 * w1 * c1
    Ccx, Ccy = Bx + l2 * c2, By + l2 * s2
    R, Rb, Og, Cj, ug, FM, J0, u, wrench = joint_arrays(ctx)
    ob0, ob1, ob2, wgx, wgy, wgz = body_rotation(y, R)  # the follower
    dz = P[JOFF]
    Cfx = l4 + l3 * R[0, 1] + dz * R[0, 2]
    Cfy = l3 * R[1, 1] + dz * R[1, 2]
    Cfz = l3 * R[2, 1] + dz * R[2, 2]
    on_coupler = IP[ON_COUPLER] == 1
    # the follower is the spatial body, the coupler the planar one
    joint_frames(not on_coupler, R, Cfx, Cfy, Cfz, c2, s2, -s2, c2, Ccx, Ccy, dz, Rb, Og, Cj, ug)
    # velocities at Og of the coupler-fixed and follower-fixed points, and angular velocities
    vcx = vBx - w2 * (Og[1] - By)
    vcy = vBy + w2 * (Og[0] - Bx)
    vcz = 0.0
    rx, ry, rz = Og[0] - l4, Og[1], Og[2]
    vfx = wgy * rz - wgz * ry
    vfy = wgz * rx - wgx * rz
    vfz = wgx * ry - wgy * rx
    if on_coupler:  # journal = follower, bearing = coupler
        V0g = (vfx - vcx, vfy - vcy, vfz - vcz)
        Wg = (wgx, wgy, wgz - w2)
    else:
        V0g = (vcx - vfx, vcy - vfy, vcz - vfz)
        Wg = (-wgx, -wgy, w2 - wgz)
    energy, fnsum, pen_rad, pen_ax, mode, kdeep, nslice, fax = clearance_joint(
        Rb, Og, Cj, ug, V0g, Wg, ctx, acc, hstep, FM, J0, u, wrench
    )
    # wrench on the bearing, global: force F, moment M about Og
    Fx, Fy, Fz, Mx, My, Mz = FM[0], FM[1], FM[2], FM[3], FM[4], FM[5]
    sgn_c = 1.0 if on_coupler else -1.0  # sign of the contact wrench acting on the coupler
    # coupler generalised forces
    Q1c = sgn_c * (Fx * (-l1 * s1) + Fy * (l1 * c1))
    MBz = Mz + (Og[0] - Bx) * Fy - (Og[1] - By) * Fx
    Q2c = sgn_c * MBz
    # follower moment about D (global)
    sf = -sgn_c
    MDx = sf * (Mx + ry * Fz - rz * Fy)
    MDy = sf * (My + rz * Fx - rx * Fz)
    MDz = sf * (Mz + rx * Fy - ry * Fx)
    # gravity on the follower: weight at R (0, L3/2, 0)
    g = P[GRAV]
    m3 = P[M3]
    gx, gy, gz = 0.5 * l3 * R[0, 1], 0.5 * l3 * R[1, 1], 0.5 * l3 * R[2, 1]
    MDx += gy * 0.0 - gz * (-m3 * g)
    MDz += gx * (-m3 * g) - gy * 0.0
    # body frame moment
    mb0 = R[0, 0] * MDx + R[1, 0] * MDy + R[2, 0] * MDz
    mb1 = R[0, 1] * MDx + R[1, 1] * MDy + R[2, 1] * MDz
    mb2 = R[0, 2] * MDx + R[1, 2] * MDy + R[2, 2] * MDz
    a = 0.25 * l3 * l3 * m3
    Ix, Iy, Iz = P[I3X] + a, P[I3Y], P[I3Z] + a
    dy[8] = (mb0 - (Iz - Iy) * ob1 * ob2) / Ix
    dy[9] = (mb1 - (Ix - Iz) * ob2 * ob0) / Iy
    dy[10] = (mb2 - (Iy - Ix) * ob0 * ob1) / Iz
    q0, q1, q2, q3 = y[4], y[5], y[6], y[7]
    dy[4] = -0.5 * (q1 * ob0 + q2 * ob1 + q3 * ob2)
    dy[5] = 0.5 * (q0 * ob0 + q2 * ob2 - q3 * ob1)
    dy[6] = 0.5 * (q0 * ob1 + q3 * ob0 - q1 * ob2)
    dy[7] = 0.5 * (q0 * ob2 + q1 * ob1 - q2 * ob0)
    # crank + coupler
    m1, m2 = P[M1], P[M2]
    hb = 0.5 * l2
    M11 = P[I1] + m1 * 0.25 * l1 * l1 + m2 * l1 * l1
    M12 = m2 * l1 * hb * math.cos(th2 - th1)
    M22 = P[I2] + m2 * hb * hb
    sd = math.sin(th2 - th1)
    h1 = -m2 * l1 * hb * sd * w2 * w2
    h2 = m2 * l1 * hb * sd * w1 * w1
    Q1 = -(0.5 * m1 * l1 + m2 * l1) * g * c1 + Q1c
    Q2 = -m2 * g * hb * c2 + Q2c
    dy[0] = w1
    dy[1] = w2
    if IP[DRIVER] == 1:
        dy[2] = 0.0
        dy[3] = (Q2 - h2) / M22
    else:
        r1 = Q1 - h1
        r2 = Q2 - h2
        det = M11 * M22 - M12 * M12
        dy[2] = (M22 * r1 - M12 * r2) / det
        dy[3] = (M11 * r2 - M12 * r1) / det
    if diag.shape[0] > 0:
        diag[D_TH1] = th1
        diag[D_CRANK_POS], diag[D_CRANK_POS + 1], diag[D_CRANK_POS + 2] = 0.5 * Bx, 0.5 * By, 0.0
        diag[D_CRANK_VEL], diag[D_CRANK_VEL + 1], diag[D_CRANK_VEL + 2] = 0.5 * vBx, 0.5 * vBy, 0.0
        diag[D_COUP_POS] = Bx + hb * c2
        diag[D_COUP_POS + 1] = By + hb * s2
        diag[D_COUP_POS + 2] = 0.0
        diag[D_COUP_VEL] = vBx - w2 * hb * s2
        diag[D_COUP_VEL + 1] = vBy + w2 * hb * c2
        diag[D_COUP_VEL + 2] = 0.0
        diag[D_FOLL_POS] = l4 + gx
        diag[D_FOLL_POS + 1] = gy
        diag[D_FOLL_POS + 2] = gz
        diag[D_FOLL_VEL] = wgy * gz - wgz * gy
        diag[D_FOLL_VEL + 1] = wgz * gx - wgx * gz
        diag[D_FOLL_VEL + 2] = wgx * gy - wgy * gx
        diag[D_FOLL_OMEGA], diag[D_FOLL_OMEGA + 1], diag[D_FOLL_OMEGA + 2] = wgx, wgy, wgz
        diag[D_TH2] = th2
        diag[D_TH3] = math.atan2(R[1, 1], R[0, 1])
        record_joint(diag, y, Og, Cj, FM, J0, u, wrench, pen_rad, pen_ax, mode, kdeep, nslice, fax)
        T = 0.5 * (M11 * w1 * w1 + 2 * M12 * w1 * w2 + M22 * w2 * w2)
        T += 0.5 * (Ix * ob0 * ob0 + Iy * ob1 * ob1 + Iz * ob2 * ob2)
        V = g * (0.5 * m1 * l1 * s1 + m2 * (l1 * s1 + hb * s2) + m3 * gy)
        diag[D_ENERGY] = T + V + energy
        diag[D_TH2DOT] = w2


@kernel
def _eval_ideal(t, y, P, IP, dy, diag):
    """Planar four-bar with ideal joint C: loop-closure constraints, Baumgarte-stabilised."""
    th1, th2, th3, w1, w2, w3 = y[0], y[1], y[2], y[3], y[4], y[5]
    l1, l2, l3, l4 = P[L1], P[L2], P[L3], P[L4]
    c1, s1 = math.cos(th1), math.sin(th1)
    c2, s2 = math.cos(th2), math.sin(th2)
    c3, s3 = math.cos(th3), math.sin(th3)
    phx = l1 * c1 + l2 * c2 - l4 - l3 * c3
    phy = l1 * s1 + l2 * s2 - l3 * s3
    dphx = -l1 * w1 * s1 - l2 * w2 * s2 + l3 * w3 * s3
    dphy = l1 * w1 * c1 + l2 * w2 * c2 - l3 * w3 * c3
    al = P[BAUM]
    gx = l1 * w1 * w1 * c1 + l2 * w2 * w2 * c2 - l3 * w3 * w3 * c3 - 2 * al * dphx - al * al * phx
    gy = l1 * w1 * w1 * s1 + l2 * w2 * w2 * s2 - l3 * w3 * w3 * s3 - 2 * al * dphy - al * al * phy
    a11, a12 = -l2 * s2, l3 * s3
    a21, a22 = l2 * c2, -l3 * c3
    det = a11 * a22 - a12 * a21
    dd2 = (gx * a22 - a12 * gy) / det
    dd3 = (a11 * gy - a21 * gx) / det
    dy[0] = w1
    dy[1] = w2
    dy[2] = w3
    dy[3] = 0.0
    dy[4] = dd2
    dy[5] = dd3
    if diag.shape[0] > 0:
        g = P[GRAV]
        m1, m2, m3 = P[M1], P[M2], P[M3]
        hb = 0.5 * l2
        Bx, By = l1 * c1, l1 * s1
        vBx, vBy = -l1 * w1 * s1, l1 * w1 * c1
        for i in range(ND_DIAG):
            diag[i] = 0.0
        diag[D_TH1] = th1
        diag[D_CRANK_POS], diag[D_CRANK_POS + 1] = 0.5 * Bx, 0.5 * By
        diag[D_CRANK_VEL], diag[D_CRANK_VEL + 1] = 0.5 * vBx, 0.5 * vBy
        diag[D_COUP_POS], diag[D_COUP_POS + 1] = Bx + hb * c2, By + hb * s2
        diag[D_COUP_VEL] = vBx - w2 * hb * s2
        diag[D_COUP_VEL + 1] = vBy + w2 * hb * c2
        diag[D_FOLL_POS], diag[D_FOLL_POS + 1] = l4 + 0.5 * l3 * c3, 0.5 * l3 * s3
        diag[D_FOLL_VEL], diag[D_FOLL_VEL + 1] = -0.5 * l3 * w3 * s3, 0.5 * l3 * w3 * c3
        diag[D_FOLL_OMEGA + 2] = w3
        diag[D_TH2] = th2
        diag[D_TH3] = th3
        # joint reaction at C (force on the follower) from the two rotational equations
        Ia = P[I3Z] + 0.25 * m3 * l3 * l3
        rhs_f = Ia * dd3 + m3 * g * 0.5 * l3 * c3  # = ((C-D) x F)_z
        IB = P[I2] + m2 * hb * hb
        aBx, aBy = -l1 * w1 * w1 * c1, -l1 * w1 * w1 * s1
        inert = IB * dd2 + m2 * (hb * c2 * aBy - hb * s2 * aBx)
        rhs_c = -(inert + m2 * g * hb * c2)  # = ((C-B) x F)_z with F on the follower
        rdx, rdy = l3 * c3, l3 * s3
        rbx, rby = l2 * c2, l2 * s2
        det2 = rdx * rby - rdy * rbx
        Fx = (rhs_f * rbx - rdx * rhs_c) / det2
        Fy = (rhs_f * rby - rdy * rhs_c) / det2
        bx, by = l4 + l3 * c3, l3 * s3
        record_ideal_joint(diag, bx, by, Bx + l2 * c2, By + l2 * s2, P[JOFF], Fx, Fy, th3)
        M11 = P[I1] + m1 * 0.25 * l1 * l1 + m2 * l1 * l1
        M12 = m2 * l1 * hb * math.cos(th2 - th1)
        T = 0.5 * (M11 * w1 * w1 + 2 * M12 * w1 * w2 + IB * w2 * w2) + 0.5 * Ia * w3 * w3
        V = g * (0.5 * m1 * l1 * s1 + m2 * (l1 * s1 + hb * s2) + m3 * 0.5 * l3 * s3)
        diag[D_ENERGY] = T + V
        diag[D_TH2DOT] = w2


@kernel
def _eval(t, y, ctx, dy, acc, hstep, diag):
    """Right-hand side dy of the mechanism (``IP[MECH]``) and joint model; ``ctx`` as in
    :func:`~jointwear.sim.kernels._contact._contact`.

    One integrator serves every mechanism through this branch: numba's cache does not keep
    integrators specialised on a function argument or a closure (they compile again in every
    process), so the mechanisms are told apart by an integer.
    """
    if ctx[C_IP][MECH] == MECH_SLIDER_CRANK:
        eval_slider_crank(t, y, ctx, dy, acc, hstep, diag)
    elif ctx[C_IP][IDEAL] == 1:
        _eval_ideal(t, y, ctx[C_P], ctx[C_IP], dy, diag)
        ideal_joint_info(ctx[C_INFO])
    else:
        _eval_clearance(t, y, ctx, dy, acc, hstep, diag)
