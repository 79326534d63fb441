"""numba kernels of the four-bar simulator: contact search, forces, equations of motion, DOPRI5.

Everything here works on plain float arrays; :mod:`jointwear.sim.dynamics` packs the parameters
(index constants below) and unpacks the results. Units are SI throughout.

State vector, clearance model (11): theta1, theta2, theta1_dot, theta2_dot, q_w, q_x, q_y, q_z
(follower orientation, body -> global), omega_x, omega_y, omega_z (follower angular velocity in
its body frame). Ideal model (6): theta1, theta2, theta3, and their rates.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

# ---- float parameters (P) ---------------------------------------------------------------------
L1, L2, L3, L4 = 0, 1, 2, 3
M1, M2, M3 = 4, 5, 6
I1, I2, I3X, I3Y, I3Z = 7, 8, 9, 10, 11
GRAV, OMEGA, JOFF = 12, 13, 14
RJ, LJ, RB, WB, CA, RHO = 15, 16, 17, 18, 19, 20
KFAC, K0, NEXP, CE, VFLOOR, KAX = 21, 22, 23, 24, 25, 26
MUS, MUD, VS, VD, MUON = 27, 28, 29, 30, 31
BAUM, DPHI = 32, 33
NP = 34
# ---- integer parameters (IP) ------------------------------------------------------------------
DRIVER, ON_COUPLER, IDEAL, PER_POINT, KVARY, KDEN_WORN, NL, ND = 0, 1, 2, 3, 4, 5, 6, 7
WPROJ = 8  # wear projection of the slice formulation: 0 local, 1 lumped, 2 local_conserving
LATCH = 9  # impact velocity latched 0 once per impact and contact region, 1 per layer
GRADED = 10  # 0: layers equally spaced (eq. 2), 1: spacing from ZL (joint.axial_grading)
NIP = 11
WPROJ_LOCAL, WPROJ_LUMPED, WPROJ_CONSERVING = 0, 1, 2
# ---- diagnostics row (recorded at output times) ----------------------------------------------
D_TH1 = 0
D_CRANK_POS, D_CRANK_VEL = 1, 4
D_COUP_POS, D_COUP_VEL = 7, 10
D_FOLL_POS, D_FOLL_VEL = 13, 16
D_FOLL_OMEGA = 19
D_TH2, D_TH3 = 22, 23
D_OFFSET, D_AXIS, D_TILT = 24, 27, 30
D_FORCE = 31
D_FN, D_FT, D_FMAG = 34, 35, 36
D_MODE, D_PEN, D_PENAX, D_K, D_ENERGY, D_NSLICE, D_TH2DOT = 37, 38, 39, 40, 41, 42, 43
D_QUAT = 44
D_FAX = 48
D_BEAR_POS, D_JOUR_POS = 49, 52
ND_DIAG = 55
# ---- info (per evaluation) -------------------------------------------------------------------
I_PEN, I_CONTACT, I_BAD = 0, 1, 2
NINFO = 4
# contact modes
MODE_FREE, MODE_POINT, MODE_LINE, MODE_TWO, MODE_AXIAL, MODE_AXIAL_RADIAL, MODE_IDEAL = (
    0,
    1,
    2,
    3,
    4,
    5,
    6,
)


@njit(cache=True)
def friction_coefficient(v, mus, mud, vs, vd):
    """Eq. 12: smoothed Coulomb friction coefficient at sliding speed v >= 0 [m/s]."""
    if v < vs:
        return mus * math.sin(0.5 * math.pi * v / vs)
    if v <= vd:
        return mud + (mus - mud) * 0.5 * (1.0 + math.cos(math.pi * (v - vs) / (vd - vs)))
    return mud


@njit(cache=True)
def ln_factor(rate, vimp, ce):
    """Lankarani-Nikravesh damping factor 1 + 3(1-ce^2) rate / (4 vimp), clamped at 0."""
    f = 1.0 + 3.0 * (1.0 - ce * ce) * rate / (4.0 * vimp)
    return f if f > 0.0 else 0.0


@njit(cache=True)
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


@njit(cache=True)
def _node(n, m, J0, u, P, H, ZL, Nd):
    """Signed penetration of bearing point (n, m) by the journal and its geometry (bearing frame).

    Returns delta, Dx, Dy, Dz (the point), nx, ny, nz (unit normal from the journal axis towards
    the point), s (axial position of the foot on the journal axis, from the journal centre).
    """
    m = m % Nd
    phi = m * P[DPHI]
    R = P[RB] + H[n, m]
    Dx = -R * math.cos(phi)
    Dy = R * math.sin(phi)
    Dz = ZL[n]
    wx, wy, wz = Dx - J0[0], Dy - J0[1], Dz - J0[2]
    s = wx * u[0] + wy * u[1] + wz * u[2]
    dx, dy, dz = wx - s * u[0], wy - s * u[1], wz - s * u[2]
    dist = math.sqrt(dx * dx + dy * dy + dz * dz)
    if dist < 1e-300:
        dist = 1e-300
    return P[RJ] - dist, Dx, Dy, Dz, dx / dist, dy / dist, dz / dist, s


@njit(cache=True)
def _dl(t, P):
    """Penetration of a node tuple from :func:`_node`, -1 beyond the journal's ends."""
    if abs(t[7]) > 0.5 * P[LJ]:
        return -1.0
    return t[0]


@njit(cache=True)
def _node_delta(n, m, J0, u, P, H, ZL, Nd):
    """Penetration of bearing point (n, m), -1 beyond the journal's ends."""
    return _dl(_node(n, m, J0, u, P, H, ZL, Nd), P)


@njit(cache=True)
def _stiffness(P, IP, h):
    if IP[KVARY] == 0:
        return P[K0]
    rbt = P[RB] + h
    if IP[KDEN_WORN] == 1:
        den = rbt - P[RJ]
    else:
        den = P[RB] - P[RJ]
    return P[KFAC] * math.sqrt(P[RJ] * rbt / den)


@njit(cache=True)
def _cross_acc(ax, ay, az, bx, by, bz, out, k, s):
    out[k] += s * (ay * bz - az * by)
    out[k + 1] += s * (az * bx - ax * bz)
    out[k + 2] += s * (ax * by - ay * bx)


_GL_T = (0.5 - 0.5 * math.sqrt(0.6), 0.5, 0.5 + 0.5 * math.sqrt(0.6))
_GL_W = (5.0 / 18.0, 8.0 / 18.0, 5.0 / 18.0)


@njit(cache=True, inline="always")
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
        wrench[0] += s * tx
        wrench[1] += s * ty
        wrench[2] += s * tz
        wrench[9] += s * tx
        wrench[10] += s * ty
        wrench[11] += s * tz
        _cross_acc(px, py, pz, tx, ty, tz, wrench, 3, s)
    return vt


@njit(cache=True)
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


@njit(cache=True)
def _search(n, m0, J0, u, P, H, ZL, Nd):
    """Deepest node of layer n near node m0: (ms, delta at ms-1, ms, ms+1, their node tuples)."""
    # climb from the node facing the eccentricity to the nearest local maximum of the
    # penetration on each side; keep the deeper one (on a worn profile the journal can
    # bridge a narrow groove and touch both flanks: the deeper flank carries the slice)
    t0 = _node(n, m0, J0, u, P, H, ZL, Nd)
    tp = _node(n, m0 + 1, J0, u, P, H, ZL, Nd)
    tm = _node(n, m0 - 1, J0, u, P, H, ZL, Nd)
    c0, cp, cm = _dl(t0, P), _dl(tp, P), _dl(tm, P)
    ms, dm, d0, dp = m0, cm, c0, cp
    nm, n0, npp = tm, t0, tp
    found = False
    if cp > c0:
        r, b0, b1 = m0 + 1, t0, tp
        b2 = _node(n, m0 + 2, J0, u, P, H, ZL, Nd)
        a0, a1, a2 = c0, cp, _dl(b2, P)
        for _ in range(Nd // 2):
            if a2 <= a1:
                break
            r += 1
            a0, a1, b0, b1 = a1, a2, b1, b2
            b2 = _node(n, r + 1, J0, u, P, H, ZL, Nd)
            a2 = _dl(b2, P)
        ms, dm, d0, dp = r, a0, a1, a2
        nm, n0, npp = b0, b1, b2
        found = True
    if cm > c0:
        r, b0, b1 = m0 - 1, t0, tm
        b2 = _node(n, m0 - 2, J0, u, P, H, ZL, Nd)
        a0, a1, a2 = c0, cm, _dl(b2, P)
        for _ in range(Nd // 2):
            if a2 <= a1:
                break
            r -= 1
            a0, a1, b0, b1 = a1, a2, b1, b2
            b2 = _node(n, r - 1, J0, u, P, H, ZL, Nd)
            a2 = _dl(b2, P)
        if not found or a1 > d0:
            ms, dm, d0, dp = r, a2, a1, a0
            nm, n0, npp = b2, b1, b0
    return ms, dm, d0, dp, nm, n0, npp


@njit(cache=True)
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


@njit(cache=True)
def _facing_node(ax, ay, P, Nd):
    """Index of the bore node facing the journal axis point (ax, ay) (eq. 2 angles)."""
    phi0 = math.atan2(ay, -ax)
    if phi0 < 0.0:
        phi0 += 2.0 * math.pi
    return int(round(phi0 / P[DPHI])) % Nd


@njit(cache=True, inline="always")
def _add_normal(wrench, px, py, pz, nx, ny, nz, s):
    """Add the normal force s (nx, ny, nz) at (px, py, pz) to the force, moment and normal slots."""
    wrench[0] += s * nx
    wrench[1] += s * ny
    wrench[2] += s * nz
    wrench[6] += s * nx
    wrench[7] += s * ny
    wrench[8] += s * nz
    _cross_acc(px, py, pz, nx, ny, nz, wrench, 3, s)


@njit(cache=True, inline="always")
def _damped(fel, rate, vm, vfloor, ce):
    """Eq. 6: elastic force fel times the L-N factor; vm <= 0 (no impact remembered) uses the
    current approach rate, at least vfloor, as impact velocity."""
    if vm <= 0.0:
        vm = rate if rate > vfloor else vfloor
    return fel * ln_factor(rate, vm, ce)


@njit(cache=True, inline="always")
def _rel_velocity(V0, W, px, py, pz):
    """Velocity of the journal relative to the bearing at the point (px, py, pz)."""
    return (
        V0[0] + W[1] * pz - W[2] * py,
        V0[1] + W[2] * px - W[0] * pz,
        V0[2] + W[0] * py - W[1] * px,
    )


@njit(cache=True)
def _slices(J0, u, V0, W, ctx, wrench, acc, hstep):
    """Grid-independent radial contact: axial slices with the penetration linear in between.

    Each layer gives its deepest penetration (parabola through three nodes); between adjacent
    layers the penetration is taken linear in z, so the joint-level law K delta^n is integrated
    exactly over the contact length (an edge contact shorter than a layer spacing gets its true
    length). The elastic force on each layer is the derivative of that integral (conservative),
    applied along the layer's deepest normal; L-N damping and friction act per layer.
    Returns (energy, normal force sum, max penetration, K at the deepest layer, contacting
    layers, opposite-sides flag, contact length fraction).
    """
    P, IP, H, HMIN, ZL, WL, AREA = ctx[0], ctx[1], ctx[2], ctx[3], ctx[4], ctx[5], ctx[6]
    vimp, srate, son, WW, acc_out = ctx[7], ctx[8], ctx[9], ctx[11], ctx[12]
    Nl = IP[NL]
    Nd = IP[ND]
    nexp = P[NEXP]
    # one scratch block per call: bound, in-plane axis point, reach, results per layer
    scr = np.empty((Nl, 8))
    dest = scr[:, 0]
    axs = scr[:, 1]
    ays = scr[:, 2]
    sd = scr[:, 3]  # signed deepest penetration of each layer
    sx = scr[:, 4]  # parabola vertex offset (node units)
    kk = scr[:, 5]
    fel = scr[:, 6]
    reach = scr[:, 7]  # 1 = the journal spans this layer, 2 = and it was searched
    geo = np.empty((Nl, 3, 6))  # the three nodes around the deepest: point (3), normal (3)
    sm = np.empty(Nl, dtype=np.int64)
    for n in range(Nl):
        fel[n] = 0.0
        ok, axs[n], ays[n], dest[n] = _layer_axis(n, J0, u, P, HMIN, ZL)
        reach[n] = 1.0 if ok else 0.0
    pen = -1.0
    for n in range(Nl):
        act = dest[n] > 0.0 or (n > 0 and dest[n - 1] > 0.0) or (n < Nl - 1 and dest[n + 1] > 0.0)
        if not (act and reach[n] > 0.0):
            sd[n] = dest[n] if dest[n] < 0.0 else -1e-12
            if sd[n] > pen:
                pen = sd[n]
            continue
        m0 = _facing_node(axs[n], ays[n], P, Nd)
        ms, dm, d0, dp, nm, n0, npp = _search(n, m0, J0, u, P, H, ZL, Nd)
        b = 0.5 * (dp - dm)
        dd = 2.0 * d0 - dp - dm
        x = 0.0
        if dd > 1e-300:
            x = b / dd
            if x > 1.0:
                x = 1.0
            elif x < -1.0:
                x = -1.0
        sd[n] = d0 + b * x - 0.5 * dd * x * x
        if sd[n] > pen:
            pen = sd[n]
        sx[n] = x
        sm[n] = ms
        for q in range(6):
            geo[n, 0, q] = nm[1 + q]
            geo[n, 1, q] = n0[1 + q]
            geo[n, 2, q] = npp[1 + q]
        lm = 0.5 * x * (x - 1.0)
        l0 = 1.0 - x * x
        lp = 0.5 * x * (x + 1.0)
        hc = lm * H[n, (ms - 1) % Nd] + l0 * H[n, ms % Nd] + lp * H[n, (ms + 1) % Nd]
        kk[n] = _stiffness(P, IP, hc)
        reach[n] = 2.0
    # elastic force per layer from the exact integral over each interval
    energy = 0.0
    clen = 0.0
    for n in range(Nl - 1):
        a = sd[n]
        bb = sd[n + 1]
        if a <= 0.0 and bb <= 0.0:
            continue
        j0, j1, g, frac = _seg(a, bb, nexp)
        # the interval's share of the bearing width (written as 1/(Nl-1) for equal spacing)
        lam = (ZL[n] - ZL[n + 1]) / P[WB] if IP[GRADED] else 1.0 / (Nl - 1)
        fel[n] += lam * kk[n] * j0
        fel[n + 1] += lam * kk[n + 1] * j1
        energy += lam * 0.5 * (kk[n] + kk[n + 1]) * g
        clen += lam * frac
    fnsum = 0.0
    kdeep = 0.0
    dmax = -1.0
    nslice = 0
    two = False
    have0 = False
    f0x, f0y, f0z = 0.0, 0.0, 0.0
    proj = IP[WPROJ]
    wsc = np.empty((Nl if (acc and proj == WPROJ_CONSERVING) else 0, 3))
    for n in range(Nl):
        if fel[n] <= 0.0 or reach[n] != 2.0:
            son[n] = 0
            continue
        x = sx[n]
        lw0 = 0.5 * x * (x - 1.0)
        lw1 = 1.0 - x * x
        lw2 = 0.5 * x * (x + 1.0)
        cx = lw0 * geo[n, 0, 0] + lw1 * geo[n, 1, 0] + lw2 * geo[n, 2, 0]
        cy = lw0 * geo[n, 0, 1] + lw1 * geo[n, 1, 1] + lw2 * geo[n, 2, 1]
        cz = lw0 * geo[n, 0, 2] + lw1 * geo[n, 1, 2] + lw2 * geo[n, 2, 2]
        nx = lw0 * geo[n, 0, 3] + lw1 * geo[n, 1, 3] + lw2 * geo[n, 2, 3]
        ny = lw0 * geo[n, 0, 4] + lw1 * geo[n, 1, 4] + lw2 * geo[n, 2, 4]
        nz = lw0 * geo[n, 0, 5] + lw1 * geo[n, 1, 5] + lw2 * geo[n, 2, 5]
        nn = math.sqrt(nx * nx + ny * ny + nz * nz)
        hx, hy, hz = nx / nn, ny / nn, nz / nn
        vx, vy, vz = _rel_velocity(V0, W, cx, cy, cz)
        rate = vx * hx + vy * hy + vz * hz
        fn = _damped(fel[n], rate, vimp[n], P[VFLOOR], P[CE])
        for k in range(3):
            lk = lw0 if k == 0 else (lw1 if k == 1 else lw2)
            g = geo[n, k]
            _add_normal(wrench, g[0], g[1], g[2], g[3], g[4], g[5], fn * lk)
        fnsum += fn
        tx = vx - rate * hx
        ty = vy - rate * hy
        tz = vz - rate * hz
        vt = _apply_friction(wrench, cx, cy, cz, tx, ty, tz, fn, P[MUON], P)
        srate[n] = rate
        son[n] = 1
        if acc:
            fw = _wear_force(n, fn, sd, kk, fel, WL, proj, P)
            if proj == WPROJ_CONSERVING:  # spread below, once each region's work is known
                wsc[n, 0] = fn * vt
                wsc[n, 1] = fw * vt
                wsc[n, 2] = vt
            elif fw > 0.0:
                _spread(n, sm[n], fw, vt, hstep, J0, u, P, H, ZL, Nd, AREA, WW)
            acc_out[0] += fn * vt * hstep
            acc_out[2] += fn * hstep
        nslice += 1
        if sd[n] > dmax:
            dmax = sd[n]
            kdeep = kk[n]
        if not have0:
            f0x, f0y, f0z = hx, hy, hz
            have0 = True
        elif f0x * hx + f0y * hy + f0z * hz < 0.0:
            two = True
    if acc and proj == WPROJ_CONSERVING:
        _spread_regions(wsc, sm, son, hstep, J0, u, P, H, ZL, Nd, AREA, WW)
    return energy, fnsum, pen, kdeep, nslice, two, clen


@njit(cache=True)
def _wear_force(n, fn, sd, kk, fel, WL, proj, P):
    """Force of layer n whose pressure, spread over the layer's slice area, gives its wear work.

    ``fn`` is the layer's (damped) share of the contact force, the derivative of the
    integrated law: hat-weighted over the two neighbouring intervals. Spreading it over the
    slice area (``lumped``) averages the pressure over the slice, so a contact shorter than
    the slice (at the bearing's edges) is diluted by the grid. ``local`` takes the pressure
    from the penetration at the layer itself, the line load K delta_n^n / wb (same L-N factor),
    so the wear work is a point value that does not depend on the slice width;
    ``local_conserving`` scales those per contact region to conserve its work
    (:func:`_spread_regions`).
    """
    if proj == WPROJ_LUMPED:
        return fn
    if sd[n] <= 0.0:  # the law at the layer itself
        return 0.0
    return fn * kk[n] * sd[n] ** P[NEXP] * WL[n] / fel[n]


@njit(cache=True)
def _spread_regions(wsc, sm, son, hstep, J0, u, P, H, ZL, Nd, AREA, WW):
    """Spread the local wear forces, scaled per contact region to its normal work.

    ``wsc[n]`` = (F_n |v_t|, local wear force x |v_t|, |v_t|) of contacting layer n. In each
    run of adjacent contacting layers the local forces keep their shape and are scaled so that
    their work equals the region's F_n |v_t| (the worn volume stays kw times the normal work).
    """
    Nl = son.shape[0] - 2
    n = 0
    while n < Nl:
        if son[n] != 1:
            n += 1
            continue
        end = n
        work = 0.0
        wloc = 0.0
        while end < Nl and son[end] == 1:
            work += wsc[end, 0]
            wloc += wsc[end, 1]
            end += 1
        for k in range(n, end):
            if wloc > 0.0:
                fw = wsc[k, 1] / wsc[k, 2] * (work / wloc) if wsc[k, 2] > 0.0 else 0.0
            else:  # no layer of the region penetrates at its node: lumped
                fw = wsc[k, 0] / wsc[k, 2] if wsc[k, 2] > 0.0 else 0.0
            if fw > 0.0:
                _spread(k, sm[k], fw, wsc[k, 2], hstep, J0, u, P, H, ZL, Nd, AREA, WW)
        n = end


@njit(cache=True)
def _penetrating_run(n, ms, J0, u, P, H, ZL, Nd, buf):
    """Contiguous run of penetrating nodes of layer n around node ms.

    Returns (lo, hi) and the penetrations in ``buf[m - ms + Nd // 2]`` for m in [lo, hi]
    (``buf[Nd // 2]`` = that of ms, possibly <= 0); every node is evaluated once.
    """
    half = Nd // 2
    d0 = _node_delta(n, ms, J0, u, P, H, ZL, Nd)
    lo = ms
    hi = ms
    if d0 > 0.0:
        while lo - ms > -half:
            dk = _node_delta(n, lo - 1, J0, u, P, H, ZL, Nd)
            if dk <= 0.0:
                break
            lo -= 1
            buf[lo - ms + half] = dk
        while hi - ms < half:
            dk = _node_delta(n, hi + 1, J0, u, P, H, ZL, Nd)
            if dk <= 0.0:
                break
            hi += 1
            buf[hi - ms + half] = dk
    buf[half] = d0
    return lo, hi


@njit(cache=True)
def _spread(n, ms, fn, vt, hstep, J0, u, P, H, ZL, Nd, AREA, WW):
    """Spread a layer's normal force over its contiguous penetrating nodes, weights sqrt(delta),
    adding p |v_t| dt to WW[0] and |v_t| dt to WW[1]; every node is evaluated once."""
    half = Nd // 2
    buf = np.empty(2 * half + 1)
    lo, hi = _penetrating_run(n, ms, J0, u, P, H, ZL, Nd, buf)
    wsum = 0.0
    for mm in range(lo, hi + 1):
        dk = buf[mm - ms + half]
        if dk > 0.0:
            wsum += math.sqrt(dk) * AREA[n, mm % Nd]
    if wsum > 0.0:
        for mm in range(lo, hi + 1):
            dk = buf[mm - ms + half]
            if dk > 0.0:
                WW[0, n, mm % Nd] += fn * math.sqrt(dk) / wsum * vt * hstep
                WW[1, n, mm % Nd] += vt * hstep
    else:  # in contact between nodes or only through the neighbouring interval
        WW[0, n, ms % Nd] += fn / AREA[n, ms % Nd] * vt * hstep
        WW[1, n, ms % Nd] += vt * hstep


@njit(cache=True)
def _per_point(J0, u, V0, W, ctx, wrench, acc, hstep):
    """The study's literal form: a full L-N force at every penetrating node (grid-dependent).

    Returns the same tuple as :func:`_slices`.
    """
    P, IP, H, HMIN, ZL, WL, AREA = ctx[0], ctx[1], ctx[2], ctx[3], ctx[4], ctx[5], ctx[6]
    vimp, srate, son, WW, acc_out = ctx[7], ctx[8], ctx[9], ctx[11], ctx[12]
    Nl = IP[NL]
    Nd = IP[ND]
    nexp = P[NEXP]
    energy = 0.0
    fnsum = 0.0
    pen_rad = -1.0
    kdeep = 0.0
    dmaxslice = -1.0
    nslice = 0
    wcontact = 0.0
    two = False
    fn0x, fn0y, fn0z = 0.0, 0.0, 0.0
    have0 = False
    buf = np.empty(2 * (Nd // 2) + 1)
    for n in range(Nl):
        son[n] = 0
        ok, ax, ay, dest = _layer_axis(n, J0, u, P, HMIN, ZL)
        if not ok:
            continue
        if dest <= 0.0:
            if dest > pen_rad:
                pen_rad = dest
            continue
        m0 = _facing_node(ax, ay, P, Nd)
        ms, _dm, d0, _dp, _nm, _n0, _np = _search(n, m0, J0, u, P, H, ZL, Nd)
        if d0 > pen_rad:
            pen_rad = d0
        if d0 <= 0.0:
            continue
        lo, hi = _penetrating_run(n, ms, J0, u, P, H, ZL, Nd, buf)
        hx, hy, hz = 0.0, 0.0, 0.0
        rate0 = 0.0
        kdk = 0.0
        for mm in range(lo, hi + 1):
            nd = _node(n, mm, J0, u, P, H, ZL, Nd)
            dk = nd[0]
            if dk <= 0.0:
                continue
            K = _stiffness(P, IP, H[n, mm % Nd])
            vx, vy, vz = _rel_velocity(V0, W, nd[1], nd[2], nd[3])
            rate = vx * nd[4] + vy * nd[5] + vz * nd[6]
            if mm == ms:
                rate0 = rate
                hx, hy, hz = nd[4], nd[5], nd[6]
                kdk = K
            fn = _damped(K * dk**nexp, rate, vimp[n], P[VFLOOR], P[CE])
            energy += K * dk ** (nexp + 1.0) / (nexp + 1.0)
            _add_normal(wrench, nd[1], nd[2], nd[3], nd[4], nd[5], nd[6], fn)
            fnsum += fn
            tx = vx - rate * nd[4]
            ty = vy - rate * nd[5]
            tz = vz - rate * nd[6]
            vt = _apply_friction(wrench, nd[1], nd[2], nd[3], tx, ty, tz, fn, P[MUON], P)
            if acc:
                WW[0, n, mm % Nd] += fn / AREA[n, mm % Nd] * vt * hstep
                WW[1, n, mm % Nd] += vt * hstep
                acc_out[0] += fn * vt * hstep
                acc_out[2] += fn * hstep
        srate[n] = rate0
        son[n] = 1
        # contact statistics (modes)
        nslice += 1
        wcontact += WL[n]
        if d0 > dmaxslice:
            dmaxslice = d0
            kdeep = kdk
        if not have0:
            fn0x, fn0y, fn0z = hx, hy, hz
            have0 = True
        elif fn0x * hx + fn0y * hy + fn0z * hz < 0.0:
            two = True
    return energy, fnsum, pen_rad, kdeep, nslice, two, wcontact


@njit(cache=True, inline="always")
def _end_faces(J0, u, V0, W, ctx, wrench, acc, hstep):
    """Axial stops: the journal's shoulders against the bearing end faces.

    Returns (elastic energy, max axial penetration, axial normal force sum).
    """
    P, IP, vimp, srate, son, acc_out = ctx[0], ctx[1], ctx[7], ctx[8], ctx[9], ctx[12]
    Nl = IP[NL]
    nexp = P[NEXP]
    energy = 0.0
    pen_ax = -1.0
    fax = 0.0
    upx, upy = u[0], u[1]
    up = math.sqrt(upx * upx + upy * upy)
    half = 0.5 * (P[WB] + P[CA])
    kax = P[KAX]
    for face in range(2):
        sg = 1.0 if face == 0 else -1.0
        if up > 1e-14:
            rx, ry = sg * upx / up, sg * upy / up
        else:
            rx, ry = 0.0, 0.0
        xx = P[RHO] * rx
        xy = P[RHO] * ry
        xz = sg * 0.5 * P[WB]
        qx = J0[0] + sg * half * u[0]
        qy = J0[1] + sg * half * u[1]
        qz = J0[2] + sg * half * u[2]
        dlt = sg * ((xx - qx) * u[0] + (xy - qy) * u[1] + (xz - qz) * u[2])
        if dlt > pen_ax:
            pen_ax = dlt
        k = Nl + face
        if dlt <= 0.0:
            son[k] = 0
            continue
        vx, vy, vz = _rel_velocity(V0, W, xx, xy, xz)
        vn = vx * u[0] + vy * u[1] + vz * u[2]
        rate = -sg * vn
        fn = _damped(kax * dlt**nexp, rate, vimp[k], P[VFLOOR], P[CE])
        energy += kax * dlt ** (nexp + 1.0) / (nexp + 1.0)
        _add_normal(wrench, xx, xy, xz, u[0], u[1], u[2], -sg * fn)
        tx, ty, tz = vx - vn * u[0], vy - vn * u[1], vz - vn * u[2]
        vt = _apply_friction(wrench, xx, xy, xz, tx, ty, tz, fn, P[MUON], P)
        srate[k] = rate
        son[k] = 1
        fax += fn
        if acc:
            acc_out[1] += fn * vt * hstep
    return energy, pen_ax, fax


@njit(cache=True, inline="always")
def _contact(J0, u, V0, W, ctx, wrench, acc, hstep):
    """Contact of the journal with the bore and the end faces, in the bearing frame.

    ``ctx`` = (P, IP, H, HMIN, ZL, WL, AREA, vimp, srate, son, info, WW, acc_out). With
    ``acc``, adds to ``WW[0]`` the wear work p |v_t| dt and to ``WW[1]`` the sliding distance
    |v_t| dt of every contacting bearing point. Adds to ``wrench`` (12: force on the bearing,
    moment about the bearing centre, normal part of the force, friction part of the force)
    and returns (elastic energy, normal force magnitude sum, max radial penetration, max axial
    penetration, mode, stiffness at the deepest slice, number of contacting slices, axial
    force magnitude).
    """
    IP = ctx[1]
    info = ctx[10]
    if IP[PER_POINT] == 1:
        energy, fnsum, pen_rad, kdeep, nslice, two, wcontact = _per_point(
            J0, u, V0, W, ctx, wrench, acc, hstep
        )
    else:
        energy, fnsum, pen_rad, kdeep, nslice, two, wcontact = _slices(
            J0, u, V0, W, ctx, wrench, acc, hstep
        )
    eax, pen_ax, fax = _end_faces(J0, u, V0, W, ctx, wrench, acc, hstep)
    energy += eax
    if nslice == 0:
        mode = MODE_FREE
    elif two:
        mode = MODE_TWO
    elif wcontact >= 0.5:
        mode = MODE_LINE
    else:
        mode = MODE_POINT
    if fax > 0.0 or pen_ax > 0.0:
        mode = MODE_AXIAL if nslice == 0 else MODE_AXIAL_RADIAL
    info[I_PEN] = max(pen_rad, pen_ax)
    info[I_CONTACT] = 1.0 if (nslice > 0 or pen_ax > 0.0) else 0.0
    return energy, fnsum, pen_rad, pen_ax, mode, kdeep, nslice, fax


@njit(cache=True)
def _eval_clearance(t, y, ctx, dy, acc, hstep, diag):
    """Right-hand side of the clearance model; optionally accumulates wear work / fills diag."""
    P, IP, info = ctx[0], ctx[1], ctx[10]
    th1, th2, w1, w2 = y[0], y[1], y[2], y[3]
    c1, s1 = math.cos(th1), math.sin(th1)
    c2, s2 = math.cos(th2), math.sin(th2)
    l1, l2, l3, l4 = P[L1], P[L2], P[L3], P[L4]
    Bx, By = l1 * c1, l1 * s1
    vBx, vBy = -l1 * w1 * s1, l1 * w1 * c1
    Ccx, Ccy = Bx + l2 * c2, By + l2 * s2
    R = np.empty((3, 3))
    _quat_matrix(y[4], y[5], y[6], y[7], R)
    ob0, ob1, ob2 = y[8], y[9], y[10]
    # follower angular velocity, global
    wgx = R[0, 0] * ob0 + R[0, 1] * ob1 + R[0, 2] * ob2
    wgy = R[1, 0] * ob0 + R[1, 1] * ob1 + R[1, 2] * ob2
    wgz = R[2, 0] * ob0 + R[2, 1] * ob1 + R[2, 2] * ob2
    dz = P[JOFF]
    Cfx = l4 + l3 * R[0, 1] + dz * R[0, 2]
    Cfy = l3 * R[1, 1] + dz * R[1, 2]
    Cfz = l3 * R[2, 1] + dz * R[2, 2]
    Rb = np.empty((3, 3))
    Og = np.empty(3)
    Cj = np.empty(3)
    ug = np.empty(3)
    on_coupler = IP[ON_COUPLER] == 1
    if on_coupler:
        Rb[0, 0], Rb[1, 0], Rb[2, 0] = c2, s2, 0.0
        Rb[0, 1], Rb[1, 1], Rb[2, 1] = -s2, c2, 0.0
        Rb[0, 2], Rb[1, 2], Rb[2, 2] = 0.0, 0.0, 1.0
        Og[0], Og[1], Og[2] = Ccx, Ccy, dz
        Cj[0], Cj[1], Cj[2] = Cfx, Cfy, Cfz
        ug[0], ug[1], ug[2] = R[0, 2], R[1, 2], R[2, 2]
    else:
        for i in range(3):
            for j in range(3):
                Rb[i, j] = R[i, j]
        Og[0], Og[1], Og[2] = Cfx, Cfy, Cfz
        Cj[0], Cj[1], Cj[2] = Ccx, Ccy, dz
        ug[0], ug[1], ug[2] = 0.0, 0.0, 1.0
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
    J0 = np.empty(3)
    u = np.empty(3)
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
    # wrench on the bearing, global: force F, moment M about Og
    Fx = Rb[0, 0] * wrench[0] + Rb[0, 1] * wrench[1] + Rb[0, 2] * wrench[2]
    Fy = Rb[1, 0] * wrench[0] + Rb[1, 1] * wrench[1] + Rb[1, 2] * wrench[2]
    Fz = Rb[2, 0] * wrench[0] + Rb[2, 1] * wrench[1] + Rb[2, 2] * wrench[2]
    Mx = Rb[0, 0] * wrench[3] + Rb[0, 1] * wrench[4] + Rb[0, 2] * wrench[5]
    My = Rb[1, 0] * wrench[3] + Rb[1, 1] * wrench[4] + Rb[1, 2] * wrench[5]
    Mz = Rb[2, 0] * wrench[3] + Rb[2, 1] * wrench[4] + Rb[2, 2] * wrench[5]
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
        for i in range(3):
            diag[D_OFFSET + i] = J0[i]
            diag[D_AXIS + i] = u[i]
        diag[D_TILT] = math.acos(min(1.0, u[2]))
        diag[D_FORCE], diag[D_FORCE + 1], diag[D_FORCE + 2] = Fx, Fy, Fz
        diag[D_FN] = math.sqrt(wrench[6] ** 2 + wrench[7] ** 2 + wrench[8] ** 2)
        diag[D_FMAG] = math.sqrt(Fx * Fx + Fy * Fy + Fz * Fz)
        diag[D_FT] = math.sqrt(wrench[9] ** 2 + wrench[10] ** 2 + wrench[11] ** 2)
        diag[D_MODE] = mode
        diag[D_PEN] = pen_rad
        diag[D_PENAX] = pen_ax
        diag[D_K] = kdeep
        T = 0.5 * (M11 * w1 * w1 + 2 * M12 * w1 * w2 + M22 * w2 * w2)
        T += 0.5 * (Ix * ob0 * ob0 + Iy * ob1 * ob1 + Iz * ob2 * ob2)
        V = g * (0.5 * m1 * l1 * s1 + m2 * (l1 * s1 + hb * s2) + m3 * gy)
        diag[D_ENERGY] = T + V + energy
        diag[D_NSLICE] = nslice
        diag[D_TH2DOT] = w2
        n = math.sqrt(q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3)
        diag[D_QUAT], diag[D_QUAT + 1], diag[D_QUAT + 2], diag[D_QUAT + 3] = (
            q0 / n,
            q1 / n,
            q2 / n,
            q3 / n,
        )
        diag[D_FAX] = fax
        for i in range(3):
            diag[D_BEAR_POS + i] = Og[i]
            diag[D_JOUR_POS + i] = Cj[i]


@njit(cache=True)
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
        diag[D_BEAR_POS], diag[D_BEAR_POS + 1] = l4 + l3 * c3, l3 * s3
        diag[D_JOUR_POS], diag[D_JOUR_POS + 1] = Bx + l2 * c2, By + l2 * s2
        diag[D_BEAR_POS + 2] = P[JOFF]
        diag[D_JOUR_POS + 2] = P[JOFF]
        diag[D_AXIS + 2] = 1.0
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
        diag[D_FORCE], diag[D_FORCE + 1] = Fx, Fy
        diag[D_FN] = math.sqrt(Fx * Fx + Fy * Fy)
        diag[D_FMAG] = diag[D_FN]
        diag[D_MODE] = MODE_IDEAL
        diag[D_PEN] = 0.0
        M11 = P[I1] + m1 * 0.25 * l1 * l1 + m2 * l1 * l1
        M12 = m2 * l1 * hb * math.cos(th2 - th1)
        T = 0.5 * (M11 * w1 * w1 + 2 * M12 * w1 * w2 + IB * w2 * w2) + 0.5 * Ia * w3 * w3
        V = g * (0.5 * m1 * l1 * s1 + m2 * (l1 * s1 + hb * s2) + m3 * 0.5 * l3 * s3)
        diag[D_ENERGY] = T + V
        diag[D_TH2DOT] = w2
        a = 0.5 * (th3 - 0.5 * math.pi)
        diag[D_QUAT], diag[D_QUAT + 3] = math.cos(a), math.sin(a)


@njit(cache=True)
def _latch_impacts(vimp, srate, son, Nl, vfloor, per_layer):
    """Impact velocity of eq. 6, latched once per impact at its onset, per contact region.

    A contact region is a run of adjacent contacting layers (each end face is one of its own).
    A region that holds a remembered velocity continues its impact: all its layers take it
    (the largest, if impacts merged), so a layer that joins a spreading contact does not start
    an impact of its own. A region without one is a new impact: its largest approach rate,
    at least ``vfloor``, is latched. Layers out of contact forget. ``per_layer``: the form
    before issue 16, every layer latches its own rate when it enters contact.
    """
    n = 0
    while n < Nl + 2:
        if son[n] != 1:
            vimp[n] = 0.0
            n += 1
            continue
        end = n + 1
        if n < Nl and per_layer == 0:
            while end < Nl and son[end] == 1:
                end += 1
        v = 0.0
        r = vfloor
        for k in range(n, end):
            if vimp[k] > v:
                v = vimp[k]
            if srate[k] > r:
                r = srate[k]
        if v <= 0.0:
            v = r
        for k in range(n, end):
            vimp[k] = v
        n = end


@njit(cache=True)
def _eval(t, y, ctx, dy, acc, hstep, diag):
    """Right-hand side dy of either model; ``ctx`` as in :func:`_contact`."""
    if ctx[1][IDEAL] == 1:
        _eval_ideal(t, y, ctx[0], ctx[1], dy, diag)
        info = ctx[10]
        info[I_PEN] = -1.0
        info[I_CONTACT] = 0.0
        info[I_BAD] = 0.0
    else:
        _eval_clearance(t, y, ctx, dy, acc, hstep, diag)


# Dormand-Prince 5(4) tableau: nodes, stage coefficients (row s: stage s + 1), 5th-order
# weights and error weights (b - b*); the second stage never enters B and E
_C = np.array([0.0, 1.0 / 5.0, 3.0 / 10.0, 4.0 / 5.0, 8.0 / 9.0, 1.0])
_A = np.array(
    [
        [0.0, 0.0, 0.0, 0.0, 0.0],
        [1.0 / 5.0, 0.0, 0.0, 0.0, 0.0],
        [3.0 / 40.0, 9.0 / 40.0, 0.0, 0.0, 0.0],
        [44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0, 0.0, 0.0],
        [19372.0 / 6561.0, -25360.0 / 2187.0, 64448.0 / 6561.0, -212.0 / 729.0, 0.0],
        [9017.0 / 3168.0, -355.0 / 33.0, 46732.0 / 5247.0, 49.0 / 176.0, -5103.0 / 18656.0],
    ]
)
_B = np.array([35.0 / 384.0, 0.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0])
_E = np.array(
    [
        71.0 / 57600.0,
        0.0,
        -71.0 / 16695.0,
        71.0 / 1920.0,
        -17253.0 / 339200.0,
        22.0 / 525.0,
        -1.0 / 40.0,
    ]
)


@njit(cache=True, inline="always")
def _combine(Ks, coef, s, i):
    """sum_j coef[j] Ks[j, i] over the stages j < s with a non-zero coefficient, in order."""
    a = 0.0
    for j in range(s):
        if coef[j] != 0.0:
            a += coef[j] * Ks[j, i]
    return a


@njit(cache=True)
def integrate(
    t,
    y,
    hstep,
    t_end,
    t_out,
    i_out,
    diag_out,
    P,
    IP,
    H,
    HMIN,
    ZL,
    WL,
    AREA,
    vimp,
    WW,
    acc_out,
    ANG,
    rtol,
    atol,
    hmax,
    hmin,
    onset,
    pen_limit,
):
    """Advance ``y`` from ``t`` to ``t_end`` with adaptive DOPRI5; record diagnostics.

    Returns (status, t, hstep, i_out, n_accepted, n_rejected). status: 0 done, 1 step-size
    collapse, 2 penetration beyond ``pen_limit``, 3 non-finite state, 4 journal axis flipped.
    """
    n = y.shape[0]
    Nl = IP[NL]
    srate = np.zeros(Nl + 2)
    son = np.zeros(Nl + 2, dtype=np.int64)
    info = np.zeros(NINFO)
    ctx = (P, IP, H, HMIN, ZL, WL, AREA, vimp, srate, son, info, WW, acc_out)
    Ks = np.empty((7, n))  # the seven stage derivatives (the seventh is the next first: FSAL)
    yt = np.empty(n)
    y1 = np.empty(n)
    yi = np.empty(n)
    nodiag = np.empty(0)
    ndg = np.empty(ND_DIAG)
    _eval(t, y, ctx, Ks[0], False, 0.0, nodiag)
    pen0 = info[I_PEN]
    contact0 = info[I_CONTACT]
    nacc = 0
    nrej = 0
    n_out = t_out.shape[0]
    # record an output point sitting exactly at the start
    while i_out < n_out and t_out[i_out] <= t:
        _eval(t, y, ctx, yi, False, 0.0, ndg)
        for j in range(ND_DIAG):
            diag_out[i_out, j] = ndg[j]
        i_out += 1
    while t < t_end:
        h = hstep
        if h > hmax:
            h = hmax
        last = False
        if t + h >= t_end:
            h = t_end - t
            last = True
        # ---- one DOPRI5 step: stages 2..6, the 5th-order solution and its derivative ----
        for s in range(1, 6):
            for i in range(n):
                if s == 1:
                    yt[i] = y[i] + h * _A[1, 0] * Ks[0, i]
                else:
                    yt[i] = y[i] + h * _combine(Ks, _A[s], s, i)
            _eval(t + _C[s] * h, yt, ctx, Ks[s], False, 0.0, nodiag)
        for i in range(n):
            y1[i] = y[i] + h * _combine(Ks, _B, 6, i)
        _eval(t + h, y1, ctx, Ks[6], False, 0.0, nodiag)
        err = 0.0
        finite = True
        for i in range(n):
            ei = h * _combine(Ks, _E, 7, i)
            if ANG[i] == 1:
                sc = atol
            else:
                a = abs(y[i])
                b = abs(y1[i])
                sc = atol + rtol * (a if a > b else b)
            r = ei / sc
            err += r * r
            if not math.isfinite(y1[i]):
                finite = False
        err = math.sqrt(err / n)
        if not finite or not math.isfinite(err):
            if h <= hmin:
                return 3, t, h, i_out, nacc, nrej
            hstep = 0.25 * h
            nrej += 1
            continue
        pen1 = info[I_PEN]
        contact1 = info[I_CONTACT]
        bad1 = info[I_BAD]
        if err > 1.0:
            fac = 0.9 * err**-0.2
            if fac < 0.2:
                fac = 0.2
            hstep = h * fac
            nrej += 1
            if hstep < hmin:
                return 1, t, hstep, i_out, nacc, nrej
            continue
        # event control: a step from free flight may not end deep in contact
        if contact0 == 0.0 and pen1 > onset and h > hmin * 10.0:
            frac = (0.5 * onset - pen0) / (pen1 - pen0)
            if frac > 0.9:
                frac = 0.9
            if frac < 0.01:
                frac = 0.01
            hstep = h * frac
            nrej += 1
            continue
        if bad1 != 0.0:
            return 4, t, h, i_out, nacc, nrej
        # ---- accepted ----
        # outputs in (t, t + h] by cubic Hermite interpolation
        t1 = t + h
        while i_out < n_out and t_out[i_out] <= t1 + 1e-15:
            th = (t_out[i_out] - t) / h
            if th > 1.0:
                th = 1.0
            h00 = 2 * th**3 - 3 * th**2 + 1
            h10 = th**3 - 2 * th**2 + th
            h01 = -2 * th**3 + 3 * th**2
            h11 = th**3 - th**2
            for i in range(n):
                yi[i] = h00 * y[i] + h10 * h * Ks[0, i] + h01 * y1[i] + h11 * h * Ks[6, i]
            _eval(t_out[i_out], yi, ctx, yt, False, 0.0, ndg)
            for j in range(ND_DIAG):
                diag_out[i_out, j] = ndg[j]
            i_out += 1
        for i in range(n):
            y[i] = y1[i]
        if IP[IDEAL] == 0:
            qn = math.sqrt(y[4] ** 2 + y[5] ** 2 + y[6] ** 2 + y[7] ** 2)
            for i in range(4, 8):
                y[i] /= qn
        t = t1
        if last:
            t = t_end
        nacc += 1
        # wear work and impact-velocity memory at the new state
        if contact1 != 0.0:
            _eval(t, y, ctx, Ks[0], True, h, nodiag)
        else:
            for i in range(n):
                Ks[0, i] = Ks[6, i]
            for k in range(Nl + 2):
                son[k] = 0
        pen0 = pen1
        contact0 = contact1
        _latch_impacts(vimp, srate, son, Nl, P[VFLOOR], IP[LATCH])
        if pen0 > pen_limit:
            return 2, t, h, i_out, nacc, nrej
        # next step size
        if err < 1e-10:
            fac = 5.0
        else:
            fac = 0.9 * err**-0.2
            if fac > 5.0:
                fac = 5.0
        hstep = h * fac
    return 0, t, hstep, i_out, nacc, nrej
