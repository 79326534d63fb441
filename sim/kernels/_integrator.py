"""Adaptive Dormand-Prince 5(4) integration (DOPRI5) of the equations of motion, with
output at given times and the per-step wear-work accumulation.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from jointwear.sim.kernels._contact import _latch_impacts
from jointwear.sim.kernels._context import make_context
from jointwear.sim.kernels._equations import _eval
from jointwear.sim.kernels._jit import inline_kernel
from jointwear.sim.kernels._layout import (
    C_INFO,
    C_SON,
    C_SRATE,
    ERR_ABSOLUTE,
    ERR_VECTOR,
    I_BAD,
    I_CONTACT,
    I_PEN,
    IDEAL,
    LATCH,
    ND_DIAG,
    NL,
    VFLOOR,
)

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


@inline_kernel
def _combine(Ks, coef, s, i):
    """sum_j coef[j] Ks[j, i] over the stages j < s with a non-zero coefficient, in order."""
    a = 0.0
    for j in range(s):
        if coef[j] != 0.0:
            a += coef[j] * Ks[j, i]
    return a


@njit(cache=True)
def integrate(t, y, hstep, t_end, record, i_out, inputs, solver):
    """Advance ``y`` from ``t`` to ``t_end`` with adaptive DOPRI5; record diagnostics.

    ``record`` = (t_out, diag_out): output times, diagnostics rows written from row ``i_out``;
    ``inputs`` = (P, IP, H, HMIN, ZL, WL, AREA, vimp, WW, acc_out) of :func:`.make_context`;
    ``solver`` = (ANG, rtol, atol, hmax, hmin, onset, pen_limit); ``ANG[i]`` says what the
    local error of component i is measured against (``_layout.ERR_*``): atol + rtol |y_i|,
    atol alone (angles), or atol + rtol |v| with v the vector of the components flagged
    ``ERR_VECTOR`` (the rotating body's angular velocity: a component that vibrates about zero
    is then held to rtol of the whole rotation rate, not of its own amplitude). Returns
    (status, t, hstep, i_out, n_accepted, n_rejected); status 0 done, 1 step-size collapse, 2 penetration beyond
    ``pen_limit``, 3 non-finite state, 4 journal axis flipped. Adds to ``acc_out`` the normal,
    axial normal work and normal impulse; keeps there the largest end-of-step penetration.
    """
    t_out, diag_out = record
    P, IP, H, HMIN, ZL, WL, AREA, vimp, WW, acc_out = inputs
    ANG, rtol, atol, hmax, hmin, onset, pen_limit = solver
    n = y.shape[0]
    Nl = IP[NL]
    ctx = make_context(P, IP, H, HMIN, ZL, WL, AREA, vimp, WW, acc_out)
    srate, son, info = ctx[C_SRATE], ctx[C_SON], ctx[C_INFO]
    Ks = np.empty((7, n))  # the seven stage derivatives (the seventh is the next first: FSAL)
    yt = np.empty(n)
    y1 = np.empty(n)
    yi = np.empty(n)
    nodiag = np.empty(0)
    ndg = np.empty(ND_DIAG)
    # whether _eval accumulates wear work, as run-time values: a literal True/False would
    # compile the whole clearance-joint chain once per value (numba types each literal)
    accumulate = np.ones(1, np.bool_)[0]
    look = not accumulate
    _eval(t, y, ctx, Ks[0], look, 0.0, nodiag)
    pen0 = info[I_PEN]
    contact0 = info[I_CONTACT]
    nacc = 0
    nrej = 0
    n_out = t_out.shape[0]
    # record an output point sitting exactly at the start
    while i_out < n_out and t_out[i_out] <= t:
        _eval(t, y, ctx, yi, look, 0.0, ndg)
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
            _eval(t + _C[s] * h, yt, ctx, Ks[s], look, 0.0, nodiag)
        for i in range(n):
            y1[i] = y[i] + h * _combine(Ks, _B, 6, i)
        _eval(t + h, y1, ctx, Ks[6], look, 0.0, nodiag)
        err = 0.0
        finite = True
        va = 0.0
        vb = 0.0
        for i in range(n):
            if ANG[i] == ERR_VECTOR:
                va += y[i] * y[i]
                vb += y1[i] * y1[i]
        vsc = atol + rtol * math.sqrt(va if va > vb else vb)
        for i in range(n):
            ei = h * _combine(Ks, _E, 7, i)
            if ANG[i] == ERR_ABSOLUTE:
                sc = atol
            elif ANG[i] == ERR_VECTOR:
                sc = vsc
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
            _eval(t_out[i_out], yi, ctx, yt, look, 0.0, ndg)
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
            _eval(t, y, ctx, Ks[0], accumulate, h, nodiag)
        else:
            for i in range(n):
                Ks[0, i] = Ks[6, i]
            for k in range(Nl + 2):
                son[k] = 0
        pen0 = pen1
        contact0 = contact1
        if pen0 > acc_out[3]:
            acc_out[3] = pen0
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
