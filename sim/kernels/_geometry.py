"""Geometry of joint C in the kernels: follower rotation, bore and journal nodes, the
contact search along a layer's segment and the layer axes.
"""

from __future__ import annotations

import math

from jointwear.sim.kernels._jit import inline_kernel, kernel
from jointwear.sim.kernels._layout import DPHI, LJ, RB, RJ


@kernel
def _quat_matrix(q0, q1, q2, q3, R):
    n = math.sqrt(q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3)
    w, x, y, z = q0 / n, q1 / n, q2 / n, q3 / n
    R[0, 0] = 1 - 2 * (y * y + z * z)
    R[0, 1] = 2 * (x * y - w * z)
    R[0, 2] = 2 * (x * z + w * y)
    R[1, 0] = 2 * (x * y + w * z)
    R[1, 1] = 1 - 2 * (x * x + z * z)
    R[1, 2] = 2 * (y * z - w * x)
    R[2, 0] = 2 * (x * z - w * y)
    R[2, 1] = 2 * (y * z + w * x)
    R[2, 2] = 1 - 2 * (x * x + y * y)


@inline_kernel
def body_rotation(y, R):
    """Fill ``R`` from the quaternion y[4:8]; return the body's angular velocity y[8:11] in its
    own axes and in global axes (the rotating body of the clearance-model states)."""
    _quat_matrix(y[4], y[5], y[6], y[7], R)
    ob0, ob1, ob2 = y[8], y[9], y[10]
    wgx = R[0, 0] * ob0 + R[0, 1] * ob1 + R[0, 2] * ob2
    wgy = R[1, 0] * ob0 + R[1, 1] * ob1 + R[1, 2] * ob2
    wgz = R[2, 0] * ob0 + R[2, 1] * ob1 + R[2, 2] * ob2
    return ob0, ob1, ob2, wgx, wgy, wgz


@kernel
def _node(n, m, J0, u, P, H, ZL, Nd, TRIG):
    """Signed penetration of bearing point (n, m) by the journal and its geometry (bearing frame).

    ``TRIG`` (Nd, 2): cos and sin of the points' angles (:func:`._context.make_context`).
    Returns delta, Dx, Dy, Dz (the point), nx, ny, nz (unit normal from the journal axis towards
    the point), s (axial position of the foot on the journal axis, from the journal centre).
    """
    m = m % Nd
    R = P[RB] + H[n, m]
    Dx = -R * TRIG[m, 0]
    Dy = R * TRIG[m, 1]
    Dz = ZL[n]
    wx, wy, wz = Dx - J0[0], Dy - J0[1], Dz - J0[2]
    s = wx * u[0] + wy * u[1] + wz * u[2]
    dx, dy, dz = wx - s * u[0], wy - s * u[1], wz - s * u[2]
    dist = math.sqrt(dx * dx + dy * dy + dz * dz)
    if dist < 1e-300:
        dist = 1e-300
    return P[RJ] - dist, Dx, Dy, Dz, dx / dist, dy / dist, dz / dist, s


@kernel
def _dl(t, P):
    """Penetration of a node tuple from :func:`_node`, -1 beyond the journal's ends."""
    if abs(t[7]) > 0.5 * P[LJ]:
        return -1.0
    return t[0]


@kernel
def _node_delta(n, m, J0, u, P, H, ZL, Nd, TRIG):
    """Penetration of bearing point (n, m), -1 beyond the journal's ends."""
    return _dl(_node(n, m, J0, u, P, H, ZL, Nd, TRIG), P)


@kernel
def _cross_acc(ax, ay, az, bx, by, bz, out, k, s):
    out[k] += s * (ay * bz - az * by)
    out[k + 1] += s * (az * bx - ax * bz)
    out[k + 2] += s * (ax * by - ay * bx)


#: Slots of a contact wrench (12 values): resultant force 0-2, its moment 3-5, then the sums of
#: the normal forces (6-8) and of the friction forces (9-11).
W_NORMAL, W_FRICTION = 6, 9


@inline_kernel
def _add_force(wrench, px, py, pz, dx, dy, dz, s, part):
    """Add the force s (dx, dy, dz) acting at (px, py, pz) to a contact wrench: to the resultant,
    to its ``part`` (:data:`W_NORMAL` or :data:`W_FRICTION`) and its moment to the moment slots."""
    wrench[0] += s * dx
    wrench[1] += s * dy
    wrench[2] += s * dz
    wrench[part] += s * dx
    wrench[part + 1] += s * dy
    wrench[part + 2] += s * dz
    _cross_acc(px, py, pz, dx, dy, dz, wrench, 3, s)


_GL_T = (0.5 - 0.5 * math.sqrt(0.6), 0.5, 0.5 + 0.5 * math.sqrt(0.6))


_GL_W = (5.0 / 18.0, 8.0 / 18.0, 5.0 / 18.0)


@kernel
def _seg(a, b, nexp):
    """Integrals over an axial interval where the penetration runs linearly from a to b.

    With p = max(delta, 0) and t in [0, 1]: returns J0 = int (1-t) p^n, J1 = int t p^n,
    G = int p^(n+1)/(n+1) and the fraction of the interval in contact. J0, J1 are the exact
    derivatives of G with respect to a and b, so forces built from them are conservative.
    """
    if a <= 0.0 and b <= 0.0:
        return 0.0, 0.0, 0.0, 0.0
    d = b - a
    big = a if a > b else b
    if abs(d) <= 1e-3 * big:  # both positive and nearly equal: Gauss-Legendre, no cancellation
        j0 = 0.0
        j1 = 0.0
        g = 0.0
        for k in range(3):
            t = _GL_T[k]
            uu = a + d * t
            f = uu**nexp
            j0 += _GL_W[k] * (1.0 - t) * f
            j1 += _GL_W[k] * t * f
            g += _GL_W[k] * uu * f / (nexp + 1.0)
        return j0, j1, g, 1.0
    swap = d < 0.0
    if swap:
        a, b = b, a
        d = -d
    lo = a if a > 0.0 else 0.0
    hi = b
    n1 = nexp + 1.0
    n2 = nexp + 2.0
    ph1, pl1 = hi**n1, lo**n1
    ph2, pl2 = hi**n2, lo**n2
    j0 = (b * (ph1 - pl1) / n1 - (ph2 - pl2) / n2) / (d * d)
    j1 = ((ph2 - pl2) / n2 - a * (ph1 - pl1) / n1) / (d * d)
    g = (ph2 - pl2) / (n1 * n2 * d)
    frac = (hi - lo) / d
    if swap:
        return j1, j0, g, frac
    return j0, j1, g, frac


@kernel
def _search(n, m0, J0, u, P, H, ZL, Nd, TRIG):
    """Deepest node of layer n near node m0: (ms, delta at ms-1, ms, ms+1, their node tuples)."""
    # climb from the node facing the eccentricity to the nearest local maximum of the
    # penetration on each side; keep the deeper one (on a worn profile the journal can
    # bridge a narrow groove and touch both flanks: the deeper flank carries the slice)
    t0 = _node(n, m0, J0, u, P, H, ZL, Nd, TRIG)
    tp = _node(n, m0 + 1, J0, u, P, H, ZL, Nd, TRIG)
    tm = _node(n, m0 - 1, J0, u, P, H, ZL, Nd, TRIG)
    c0, cp, cm = _dl(t0, P), _dl(tp, P), _dl(tm, P)
    ms, dm, d0, dp = m0, cm, c0, cp
    nm, n0, npp = tm, t0, tp
    found = False
    if cp > c0:
        r, b0, b1 = m0 + 1, t0, tp
        b2 = _node(n, m0 + 2, J0, u, P, H, ZL, Nd, TRIG)
        a0, a1, a2 = c0, cp, _dl(b2, P)
        for _ in range(Nd // 2):
            if a2 <= a1:
                break
            r += 1
            a0, a1, b0, b1 = a1, a2, b1, b2
            b2 = _node(n, r + 1, J0, u, P, H, ZL, Nd, TRIG)
            a2 = _dl(b2, P)
        ms, dm, d0, dp = r, a0, a1, a2
        nm, n0, npp = b0, b1, b2
        found = True
    if cm > c0:
        r, b0, b1 = m0 - 1, t0, tm
        b2 = _node(n, m0 - 2, J0, u, P, H, ZL, Nd, TRIG)
        a0, a1, a2 = c0, cm, _dl(b2, P)
        for _ in range(Nd // 2):
            if a2 <= a1:
                break
            r -= 1
            a0, a1, b0, b1 = a1, a2, b1, b2
            b2 = _node(n, r - 1, J0, u, P, H, ZL, Nd, TRIG)
            a2 = _dl(b2, P)
        if not found or a1 > d0:
            ms, dm, d0, dp = r, a2, a1, a0
            nm, n0, npp = b2, b1, b0
    return ms, dm, d0, dp, nm, n0, npp


@kernel
def _layer_axis(n, J0, u, P, HMIN, ZL):
    """Journal axis point in layer n's plane and a bound of the layer's penetration.

    Returns (reach, ax, ay, dest): reach False when layer n lies beyond the journal's ends;
    (ax, ay) the axis point in the layer plane; dest an upper bound of the penetration of any
    point of the layer (from its least worn point), exact for an aligned journal.
    """
    s0 = (ZL[n] - J0[2]) / u[2]
    if abs(s0) > 0.5 * P[LJ]:
        return False, 0.0, 0.0, -1.0
    ax = J0[0] + s0 * u[0]
    ay = J0[1] + s0 * u[1]
    dest = u[2] * math.sqrt(ax * ax + ay * ay) + P[RJ] - u[2] * (P[RB] + HMIN[n])
    return True, ax, ay, dest


@kernel
def _facing_node(ax, ay, P, Nd):
    """Index of the bore node facing the journal axis point (ax, ay) (eq. 2 angles)."""
    phi0 = math.atan2(ay, -ax)
    if phi0 < 0.0:
        phi0 += 2.0 * math.pi
    return int(round(phi0 / P[DPHI])) % Nd


@inline_kernel
def _rel_velocity(V0, W, px, py, pz):
    """Velocity of the journal relative to the bearing at the point (px, py, pz)."""
    return (
        V0[0] + W[1] * pz - W[2] * py,
        V0[1] + W[2] * px - W[0] * pz,
        V0[2] + W[0] * py - W[1] * px,
    )
