"""The evaluation context of the kernels: what every right-hand side reads and writes, and the
scratch arrays that let the evaluation kernels allocate nothing (:mod:`._jit`).

``ctx`` is a tuple of arrays: the packed parameters, the bore profile and layer geometry, the
impact and wear-work memory, then the scratch arrays; every slot is read by its name ``C_*`` of
:mod:`._layout` (``ctx[C_IP]``, never a bare number). It is made once per integration; the
scratch arrays hold nothing from one evaluation to the next.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from jointwear.sim.kernels._jit import inline_kernel
from jointwear.sim.kernels._layout import (
    C_MAT,
    C_VEC,
    DPHI,
    N_VEC,
    ND,
    NINFO,
    NL,
    V_CJ,
    V_FM,
    V_J0,
    V_OG,
    V_U,
    V_UG,
    V_WRENCH,
)

__all__ = ["joint_arrays", "make_context"]


@njit(cache=True)
def make_context(P, IP, H, HMIN, ZL, WL, AREA, vimp, WW, acc_out):
    """The evaluation context of one integration (allocates; keeps numba's runtime).

    ``P``, ``IP`` the packed parameters, ``H`` (Nl, Nd) the wear depth, ``HMIN`` its least value
    per layer, ``ZL``, ``WL`` the layers' positions and width shares, ``AREA`` the points' areas,
    ``vimp`` (Nl + 2) the latched impact velocities, ``WW`` (2, Nl, Nd) the wear work and sliding
    distance, ``acc_out`` (>= 3) the accumulated normal work, axial normal work and normal
    impulse: each is read or added to in place. The approach rates, contact flags and the
    per-evaluation info start at zero.
    """
    Nl, Nd = IP[NL], IP[ND]
    inputs = (P, IP, H, HMIN, ZL, WL, AREA, vimp)
    rates_and_info = (np.zeros(Nl + 2), np.zeros(Nl + 2, dtype=np.int64), np.zeros(NINFO))
    joint = (np.empty((N_VEC, 12)), np.empty((2, 3, 3)))
    layers = (np.empty((Nl, 8)), np.empty((Nl, 3, 6)), np.empty(Nl, dtype=np.int64))
    wear = (np.empty((Nl, 3)), np.empty(Nd + 1))
    # the bore points' angles never change within an integration: their cos and sin once here
    # (the same libm values the contact search computed at every node visit before)
    trig = np.empty((Nd, 2))
    for m in range(Nd):
        phi = m * P[DPHI]
        trig[m, 0] = math.cos(phi)
        trig[m, 1] = math.sin(phi)
    return inputs + rates_and_info + (WW, acc_out) + joint + layers + wear + (trig,)


@inline_kernel
def joint_arrays(ctx):
    """The scratch arrays of a mechanism's right-hand side and its clearance joint: the rotating
    body's rotation ``R``, the bearing frame ``Rb``, ``Og``, ``Cj``, ``ug``, ``FM``, ``J0``,
    ``u`` and the contact ``wrench`` (as :func:`._joint.clearance_joint` names them). Their
    contents are undefined until written."""
    vec, mat = ctx[C_VEC], ctx[C_MAT]
    return (
        mat[0],
        mat[1],
        vec[V_OG],
        vec[V_CJ],
        vec[V_UG],
        vec[V_FM],
        vec[V_J0],
        vec[V_U],
        vec[V_WRENCH],
    )
