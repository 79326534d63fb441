"""Array layout of the kernels: indices into the float (P) and integer (IP) parameter
vectors, the diagnostics row, the per-evaluation info and the contact modes.
"""

from __future__ import annotations

# ---- float parameters (P) ---------------------------------------------------------------------
L1, L2, L3, L4 = 0, 1, 2, 3


M1, M2, M3 = 4, 5, 6


I1, I2, I3X, I3Y, I3Z = 7, 8, 9, 10, 11


GRAV, OMEGA, JOFF = 12, 13, 14


RJ, LJ, RB, WB, CA, RHO = 15, 16, 17, 18, 19, 20


KFAC, K0, NEXP, CE, VFLOOR, KAX = 21, 22, 23, 24, 25, 26


MUS, MUD, VS, VD, MUON = 27, 28, 29, 30, 31


BAUM, DPHI = 32, 33


KTILT, CTILT = 34, 35  # lumped tilt spring [N m/rad] and damper [N m s/rad] of joint C


NP = 36


# ---- integer parameters (IP) ------------------------------------------------------------------
DRIVER, ON_COUPLER, IDEAL, PER_POINT, KVARY, KDEN_WORN, NL, ND = 0, 1, 2, 3, 4, 5, 6, 7


WPROJ = 8  # wear projection of the slice formulation: 0 local, 1 lumped, 2 local_conserving


LATCH = 9  # impact velocity latched 0 once per impact and contact region, 1 per layer


GRADED = 10  # 0: layers equally spaced (eq. 2), 1: spacing from ZL (joint.axial_grading)


MECH = 11  # the mechanism: MECH_FOUR_BAR or MECH_SLIDER_CRANK (its own slots follow, _slider_crank)
NIP = 15
MECH_FOUR_BAR, MECH_SLIDER_CRANK = 0, 1


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


# ---- evaluation context (ctx), made by _context.make_context --------------------------------
# the inputs and memory every evaluation reads or adds to (_context.make_context):
C_P, C_IP = 0, 1  # packed float and integer parameters
C_H, C_HMIN = 2, 3  # (Nl, Nd) wear depth; (Nl,) its least value per layer
C_ZL, C_WL, C_AREA = 4, 5, 6  # layer positions, their width shares, (Nl, Nd) point areas
C_VIMP, C_SRATE, C_SON = 7, 8, 9  # (Nl + 2) latched impact velocity, approach rate, contact flag
C_INFO = 10  # (NINFO,) per-evaluation info, slots I_*
C_WW, C_ACC = 11, 12  # (2, Nl, Nd) wear work and sliding distance; accumulated totals
# then the scratch arrays of the evaluation kernels, which allocate nothing
C_VEC = 13  # (N_VEC, 12) vectors of the joint, rows V_*
C_MAT = 14  # (2, 3, 3): the rotating body's rotation (body -> global) and the bearing frame
C_LAYER = 15  # (Nl, 8) per-layer results of the slice contact
C_GEO = 16  # (Nl, 3, 6) the three nodes around each layer's deepest: point, normal
C_NODE = 17  # (Nl,) int: each layer's deepest node
C_WSC = 18  # (Nl, 3) per-layer work of the conserving wear projection
C_BUF = 19  # (Nd + 1,) penetrations of a layer's penetrating run of nodes
C_TRIG = 20  # (Nd, 2) cos and sin of each bore point's angle phi_m = m DPHI


# rows of ctx[C_VEC]: bearing centre, journal centre, journal axis (global); wrench on the
# bearing (global: force, moment); journal centre and axis, relative velocity and angular
# velocity (bearing frame); the contact wrench (12, bearing frame)
V_OG, V_CJ, V_UG, V_FM, V_J0, V_U, V_V0, V_W, V_WRENCH = 0, 1, 2, 3, 4, 5, 6, 7, 8


N_VEC = 9


# ---- state components and their error flags (the integrator's ``ANG``) ------------------------
Y_OMEGA = 8  # the clearance state's y[8:11]: the rotating body's angular velocity (body axes)


# local error per component: 0 against atol + rtol |y_i|, 1 against atol (angles), 2 against
# atol + rtol |v| with v the vector of all components flagged 2 (the angular velocity)
ERR_RELATIVE, ERR_ABSOLUTE, ERR_VECTOR = 0, 1, 2


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
