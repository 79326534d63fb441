"""Contact forces of joint C in the kernels: Lankarani-Nikravesh force per slice (eqs. 6-10),
the per-point and end-face variants, wear work and the impact-velocity latch.
"""

from __future__ import annotations

import math

from jointwear.sim.kernels._friction import _apply_friction
from jointwear.sim.kernels._geometry import (
    W_NORMAL,
    _add_force,
    _facing_node,
    _layer_axis,
    _node,
    _node_delta,
    _rel_velocity,
    _search,
    _seg,
)
from jointwear.sim.kernels._jit import inline_kernel, kernel
from jointwear.sim.kernels._layout import (
    C_ACC,
    C_AREA,
    C_BUF,
    C_GEO,
    C_H,
    C_HMIN,
    C_INFO,
    C_IP,
    C_LAYER,
    C_NODE,
    C_P,
    C_SON,
    C_SRATE,
    C_TRIG,
    C_VIMP,
    C_WL,
    C_WSC,
    C_WW,
    C_ZL,
    CA,
    CE,
    DPHI,
    GRADED,
    I_CONTACT,
    I_PEN,
    K0,
    KAX,
    KDEN_WORN,
    KFAC,
    KVARY,
    MODE_AXIAL,
    MODE_AXIAL_RADIAL,
    MODE_FREE,
    MODE_LINE,
    MODE_POINT,
    MODE_TWO,
    MUON,
    ND,
    NEXP,
    NL,
    PER_POINT,
    RB,
    RHO,
    RJ,
    VFLOOR,
    WB,
    WPROJ,
    WPROJ_CONSERVING,
    WPROJ_LUMPED,
)


@kernel
def ln_factor(rate, vimp, ce):
    """Lankarani-Nikravesh damping factor 1 + 3(1-ce^2) rate / (4 vimp), clamped at 0."""
    f = 1.0 + 3.0 * (1.0 - ce * ce) * rate / (4.0 * vimp)
    return f if f > 0.0 else 0.0


@kernel
def _stiffness(P, IP, h):
    if IP[KVARY] == 0:
        return P[K0]
    rbt = P[RB] + h
    if IP[KDEN_WORN] == 1:
        den = rbt - P[RJ]
    else:
        den = P[RB] - P[RJ]
    return P[KFAC] * math.sqrt(P[RJ] * rbt / den)


@inline_kernel
def _damped(fel, rate, vm, vfloor, ce):
    """Eq. 6: elastic force fel times the L-N factor; vm <= 0 (no impact remembered) uses the
    current approach rate, at least vfloor, as impact velocity."""
    if vm <= 0.0:
        vm = rate if rate > vfloor else vfloor
    return fel * ln_factor(rate, vm, ce)


@inline_kernel
def _inputs(ctx):
    """The context's inputs and memory by name: (P, IP, H, HMIN, ZL, WL, AREA, vimp, srate,
    son, WW, acc_out) (:func:`._context.make_context`)."""
    return (
        ctx[C_P],
        ctx[C_IP],
        ctx[C_H],
        ctx[C_HMIN],
        ctx[C_ZL],
        ctx[C_WL],
        ctx[C_AREA],
        ctx[C_VIMP],
        ctx[C_SRATE],
        ctx[C_SON],
        ctx[C_WW],
        ctx[C_ACC],
    )


@kernel
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
    P, IP, H, HMIN, ZL, WL, AREA, vimp, srate, son, WW, acc_out = _inputs(ctx)
    TRIG = ctx[C_TRIG]
    Nl = IP[NL]
    Nd = IP[ND]
    nexp = P[NEXP]
    # the context's scratch block: bound, in-plane axis point, reach, results per layer
    scr = ctx[C_LAYER]
    dest = scr[:, 0]
    axs = scr[:, 1]
    ays = scr[:, 2]
    sd = scr[:, 3]  # signed deepest penetration of each layer
    sx = scr[:, 4]  # parabola vertex offset (node units)
    kk = scr[:, 5]
    fel = scr[:, 6]
    reach = scr[:, 7]  # 1 = the journal spans this layer, 2 = and it was searched
    geo = ctx[C_GEO]  # the three nodes around the deepest: point (3), normal (3)
    sm = ctx[C_NODE]
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
        ms, dm, d0, dp, nm, n0, npp = _search(n, m0, J0, u, P, H, ZL, Nd, TRIG)
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
        # a layer beyond the journal's end was not searched: the interval has the other's K
        k0 = kk[n] if reach[n] == 2.0 else kk[n + 1]
        k1 = kk[n + 1] if reach[n + 1] == 2.0 else kk[n]
        fel[n] += lam * k0 * j0
        fel[n + 1] += lam * k1 * j1
        energy += lam * 0.5 * (k0 + k1) * g
        clen += lam * frac
    fnsum = 0.0
    kdeep = 0.0
    dmax = -1.0
    nslice = 0
    two = False
    have0 = False
    f0x, f0y, f0z = 0.0, 0.0, 0.0
    proj = IP[WPROJ]
    wsc = ctx[C_WSC]  # written and read with acc and the conserving projection only
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
            _add_force(wrench, g[0], g[1], g[2], g[3], g[4], g[5], fn * lk, W_NORMAL)
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
                _spread(n, sm[n], fw, vt, hstep, J0, u, P, H, ZL, Nd, TRIG, AREA, WW, ctx[C_BUF])
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
        _spread_regions(wsc, sm, son, hstep, J0, u, P, H, ZL, Nd, TRIG, AREA, WW, ctx[C_BUF])
    return energy, fnsum, pen, kdeep, nslice, two, clen


@kernel
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


@kernel
def _spread_regions(wsc, sm, son, hstep, J0, u, P, H, ZL, Nd, TRIG, AREA, WW, buf):
    """Spread the local wear forces, scaled per contact region to its normal work.

    ``wsc[n]`` = (F_n |v_t|, local wear force x |v_t|, |v_t|) of contacting layer n. In each
    run of adjacent contacting layers the local forces keep their shape and are scaled so that
    their work equals the region's F_n |v_t| (the worn volume stays kw times the normal work).
    ``buf`` is scratch for :func:`_spread`.
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
                _spread(k, sm[k], fw, wsc[k, 2], hstep, J0, u, P, H, ZL, Nd, TRIG, AREA, WW, buf)
        n = end


@kernel
def _penetrating_run(n, ms, J0, u, P, H, ZL, Nd, TRIG, buf):
    """Contiguous run of penetrating nodes of layer n around node ms.

    Returns (lo, hi) and the penetrations in ``buf[m - ms + Nd // 2]`` for m in [lo, hi]
    (``buf[Nd // 2]`` = that of ms, possibly <= 0); every node is evaluated once.
    """
    half = Nd // 2
    d0 = _node_delta(n, ms, J0, u, P, H, ZL, Nd, TRIG)
    lo = ms
    hi = ms
    if d0 > 0.0:
        while lo - ms > -half:
            dk = _node_delta(n, lo - 1, J0, u, P, H, ZL, Nd, TRIG)
            if dk <= 0.0:
                break
            lo -= 1
            buf[lo - ms + half] = dk
        while hi - ms < half:
            dk = _node_delta(n, hi + 1, J0, u, P, H, ZL, Nd, TRIG)
            if dk <= 0.0:
                break
            hi += 1
            buf[hi - ms + half] = dk
    buf[half] = d0
    return lo, hi


@kernel
def _spread(n, ms, fn, vt, hstep, J0, u, P, H, ZL, Nd, TRIG, AREA, WW, buf):
    """Spread a layer's normal force over its contiguous penetrating nodes, weights sqrt(delta),
    adding p |v_t| dt to WW[0] and |v_t| dt to WW[1]; every node is evaluated once. ``buf``
    (at least ``2 (Nd // 2) + 1``) is scratch for :func:`_penetrating_run`. A ``WW`` of four
    planes also gets the contact, unspread, in the direction of the journal's axis point in
    the layer (split linearly between the two nodes around it): F |v_t| dt in WW[2] and
    F^2 |v_t| dt in WW[3] (the conformal wear pressure, ``jointwear.sim.wear._conformal``)."""
    half = Nd // 2
    if WW.shape[0] > 2:
        s0 = (ZL[n] - J0[2]) / u[2]
        f = math.atan2(J0[1] + s0 * u[1], -(J0[0] + s0 * u[0])) / P[DPHI]
        m = int(math.floor(f))
        f -= m
        for k, share in ((m, 1.0 - f), (m + 1, f)):
            WW[2, n, k % Nd] += share * fn * vt * hstep
            WW[3, n, k % Nd] += share * fn * fn * vt * hstep
    lo, hi = _penetrating_run(n, ms, J0, u, P, H, ZL, Nd, TRIG, buf)
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


@kernel
def _per_point(J0, u, V0, W, ctx, wrench, acc, hstep):
    """The study's literal form: a full L-N force at every penetrating node (grid-dependent).

    Returns the same tuple as :func:`_slices`.
    """
    P, IP, H, HMIN, ZL, WL, AREA, vimp, srate, son, WW, acc_out = _inputs(ctx)
    TRIG = ctx[C_TRIG]
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
    buf = ctx[C_BUF]
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
        ms, _dm, d0, _dp, _nm, _n0, _np = _search(n, m0, J0, u, P, H, ZL, Nd, TRIG)
        if d0 > pen_rad:
            pen_rad = d0
        if d0 <= 0.0:
            continue
        lo, hi = _penetrating_run(n, ms, J0, u, P, H, ZL, Nd, TRIG, buf)
        hx, hy, hz = 0.0, 0.0, 0.0
        rate0 = 0.0
        kdk = 0.0
        for mm in range(lo, hi + 1):
            nd = _node(n, mm, J0, u, P, H, ZL, Nd, TRIG)
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
            _add_force(wrench, nd[1], nd[2], nd[3], nd[4], nd[5], nd[6], fn, W_NORMAL)
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


@inline_kernel
def _end_faces(J0, u, V0, W, ctx, wrench, acc, hstep):
    """Axial stops: the journal's shoulders against the bearing end faces.

    Returns (elastic energy, max axial penetration, axial normal force sum).
    """
    P, IP, vimp, srate, son, acc_out = (
        ctx[C_P],
        ctx[C_IP],
        ctx[C_VIMP],
        ctx[C_SRATE],
        ctx[C_SON],
        ctx[C_ACC],
    )
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
        _add_force(wrench, xx, xy, xz, u[0], u[1], u[2], -sg * fn, W_NORMAL)
        tx, ty, tz = vx - vn * u[0], vy - vn * u[1], vz - vn * u[2]
        vt = _apply_friction(wrench, xx, xy, xz, tx, ty, tz, fn, P[MUON], P)
        srate[k] = rate
        son[k] = 1
        fax += fn
        if acc:
            acc_out[1] += fn * vt * hstep
    return energy, pen_ax, fax


@inline_kernel
def _contact(J0, u, V0, W, ctx, wrench, acc, hstep):
    """Contact of the journal with the bore and the end faces, in the bearing frame.

    ``ctx`` = (P, IP, H, HMIN, ZL, WL, AREA, vimp, srate, son, info, WW, acc_out, then the
    scratch arrays of :func:`._context.make_context`). With
    ``acc``, adds to ``WW[0]`` the wear work p |v_t| dt and to ``WW[1]`` the sliding distance
    |v_t| dt of every contacting bearing point. Adds to ``wrench`` (12: force on the bearing,
    moment about the bearing centre, normal part of the force, friction part of the force)
    and returns (elastic energy, normal force magnitude sum, max radial penetration, max axial
    penetration, mode, stiffness at the deepest slice, number of contacting slices, axial
    force magnitude).
    """
    IP = ctx[C_IP]
    info = ctx[C_INFO]
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


@kernel
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
