"""Conformal-contact wear pressure: the pressure of an elastic (Winkler) foundation over the
worn bore's local geometry, the option ``contact.wear_pressure = "conformal"``.

By default (``"hertz"``) the kernel spreads each slice's force, at each step, over the points the
rigid journal overlaps at its simulated position, with weights sqrt(delta) (docs/sim.md). The
overlap comes from the Lankarani-Nikravesh law, a point-contact law: on the reference rig it is
about eight times Hertz's line-contact width, and it does not know how well the worn bore fits
the journal. The elastic-foundation (Winkler) model is the usual description of conformal
contact in revolute joints with wear (S. Mukras, N.H. Kim, N.A. Mauntler, T.L. Schmitz,
W.G. Sawyer, "Analysis of planar multibody systems with revolute joint wear", Wear 268 (2010)
643-652; K.L. Johnson, *Contact Mechanics*, 1985, sections 5.9 and 9.2): a rigid journal
seated in the worn bore along the load's direction and pressed into a foundation with the load,
``p = kf max(d0 cos(phi - psi) - gap(phi), 0)``, ``d0`` such that the pressure's resultant
equals the load. A groove of the journal's radius then carries the load over its whole arc at
a lower peak; on the unworn bore the contact is Hertz's.

The foundation modulus is not a material constant (for a thin elastic layer of thickness t on a
rigid base it is ``(1 - nu) E / ((1 + nu)(1 - 2 nu) t)``, :func:`foundation_modulus`, and the
bush's wall is not known here); it is matched per load so that on the *unworn* bore the
foundation gives Hertz's contact width for a cylinder in a cylinder
(:func:`hertz_matched_modulus`).

The kernel records, for every slice and step, the contact's centre (its deepest node: the
direction of its force) with the work ``F |v_t| dt`` and ``F^2 |v_t| dt`` there
(:func:`jointwear.sim.run_cycles` with the option). :func:`conformal_wear_work` spreads each
node's work by the Winkler pressure of the journal seated in the worn bore in that node's
direction under the work-weighted mean force. An earlier attempt spread the kernel's *already
spread* map point by point, re-seating the journal in each point's own direction: on a groove's
flank that direction is not the load's, the journal touched the rim first and the work moved
outwards (max depth 28.5 against 20.6 um on an 8 x 120 rig). Recording the contact's centre in
the kernel removes both errors.

Normalisation: the pressure's *resultant* is the slice's force, so on a wide arc the pressure
integrates to more than the force (by 1 / mean cos over the arc) and, by Archard's local law, so
does the wear: the worn volume is kw times the integral of p |ds|, which exceeds kw times the
normal work by that factor where the contact conforms (on the unworn bore they agree).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq

from jointwear.errors import ParameterError

__all__ = [
    "conformal_wear_work",
    "foundation_modulus",
    "hertz_matched_modulus",
    "seated_gap",
    "winkler_line_pressure",
]


def foundation_modulus(modulus: float, poisson: float, thickness: float) -> float:
    """Winkler modulus of an elastic layer of ``thickness`` on a rigid base [Pa/m]:
    ``(1 - nu) E / ((1 + nu)(1 - 2 nu) t)`` (Mukras et al. 2010; Johnson 1985, 5.9)."""
    if not (modulus > 0 and 0 <= poisson < 0.5 and thickness > 0):
        raise ParameterError(
            f"foundation modulus needs E > 0, 0 <= nu < 0.5 and a thickness > 0; got "
            f"E = {modulus!r}, nu = {poisson!r}, thickness = {thickness!r}"
        )
    return (1 - poisson) * modulus / ((1 + poisson) * (1 - 2 * poisson) * thickness)


def hertz_matched_modulus(
    line_load: float | np.ndarray,
    journal_radius: float,
    bearing_radius: float,
    reduced_modulus: float,
) -> float | np.ndarray:
    """Winkler modulus [Pa/m] that gives Hertz's contact width on the unworn bore.

    Hertz, cylinder in a cylindrical bore under ``line_load`` F' [N/m] (a number or an array):
    half-width ``b = sqrt(4 F' R' / (pi E*))``, ``R' = Rj Rb / (Rb - Rj)``. The foundation
    under a journal seated in the unworn bore (gap ``c' (1 - cos phi)``, ``c' = Rb c / Rj``)
    touches ``|phi| < a`` with ``cos a = c' / (d0 + c')`` and carries
    ``F' = kf Rb ((d0 + c')(a + sin a cos a) - 2 c' sin a)``; with ``a = b / Rb`` this gives kf.
    """
    rj, rb = journal_radius, bearing_radius
    clearance = rb - rj
    r_eff = rj * rb / clearance
    load = np.asarray(line_load, dtype=float)
    b = np.sqrt(4 * load * r_eff / (math.pi * reduced_modulus))
    a = np.minimum(b / rb, 0.5 * math.pi - 1e-6)
    cp = rb * clearance / rj
    # (d0 + c')(a + sin a cos a) - 2 c' sin a with d0 + c' = c' / cos a: f(a) c'; below
    # a = 0.05 its series (relative error below 1e-12), which avoids cancelling 2a
    closed = (a + np.sin(a) * np.cos(a)) / np.cos(a) - 2 * np.sin(a)
    series = a**3 * (2 / 3 + a**2 * (1 / 5 + a**2 * (107 / 1260 + a**2 * 779 / 22680)))
    carried = rb * cp * np.where(a < 0.05, series, closed)
    out = load / carried
    return float(out) if out.ndim == 0 else out


def seated_gap(
    bore_radius: np.ndarray, journal_radius: float, phi: np.ndarray, direction: float
) -> np.ndarray:
    """Gap [m] between a rigid journal seated in the bore in ``direction`` and the bore.

    The bore point at angle ``phi`` [rad] lies at ``bore_radius`` (the worn radius Rb + h) from
    the bore's centre; the journal of radius ``journal_radius`` has its centre moved along
    ``direction`` [rad] by the largest ``e`` at which it does not overlap the bore anywhere
    (exact geometry: a conforming groove is resolved to far below the foundation's
    deflection). The gap at ``phi`` is the bore point's distance from the journal centre
    minus ``journal_radius``; NaN on the far half (no contact possible there).
    """
    bx, by = bore_radius * np.cos(phi), bore_radius * np.sin(phi)
    ux, uy = math.cos(direction), math.sin(direction)
    near = (bx * ux + by * uy) > 0

    def least(e: float) -> float:
        return float(np.min(np.hypot(bx[near] - e * ux, by[near] - e * uy))) - journal_radius

    lo, hi = 0.0, float(np.min(bore_radius))
    if least(lo) < -1e-12 * journal_radius:
        raise ParameterError("the journal does not fit in the bore (worn radius below it)")
    if least(lo) <= 0:
        e = 0.0
    else:
        e = brentq(least, lo, hi, xtol=1e-15, rtol=1e-14, maxiter=200) if least(hi) < 0 else hi
    gap = np.hypot(bx - e * ux, by - e * uy) - journal_radius
    return np.where(near, np.maximum(gap, 0.0), np.nan)


def winkler_line_pressure(
    gap: np.ndarray,
    phi: np.ndarray,
    direction: float,
    radius: float,
    line_load: float,
    kf: float,
) -> tuple[np.ndarray, float]:
    """Winkler pressure [Pa] of a journal pressed into the bore with ``line_load`` [N/m].

    The journal advances by ``d0`` along ``direction`` from its seated position; the
    foundation is compressed by ``d0 cos(phi - direction) - gap`` where positive, so
    ``p = kf max(d0 cos - gap, 0)``, and ``d0`` balances the load,
    ``sum p cos(phi - direction) radius dphi = line_load`` (points at equal spacing ``dphi``).

    Returns
    -------
    (p, d0)
        Pressure per point [Pa] and the journal's advance [m].
    """
    c = np.cos(phi - direction)
    g = np.where(np.isfinite(gap), gap, np.inf)
    dphi = 2 * math.pi / phi.size

    def carried(d0: float) -> float:
        p = kf * np.maximum(d0 * c - g, 0.0)
        return float(np.sum(p * np.maximum(c, 0.0))) * radius * dphi - line_load

    if line_load <= 0:
        return np.zeros_like(phi), 0.0
    hi = line_load / (kf * radius * dphi) + float(np.min(g)) + 1e-15
    while carried(hi) < 0:
        hi *= 2
    d0 = brentq(carried, 0.0, hi, xtol=1e-18, rtol=1e-12, maxiter=200)
    return kf * np.maximum(d0 * c - g, 0.0), d0


def _seated_gaps(rho: np.ndarray, journal_radius: float, phi: np.ndarray, src: np.ndarray):
    """:func:`seated_gap` for every source direction ``phi[src]`` at once: (gap, cos) arrays
    (sources, points), gap = inf on the far half."""
    d = phi[None, :] - phi[src][:, None]
    cos, sin = np.cos(d), np.sin(d)
    near = cos > 1e-9
    root = journal_radius**2 - (rho[None, :] * sin) ** 2
    ok = near & (root >= 0)
    # the journal centre along the source direction touching bore point k: the smaller root
    touch = np.where(ok, rho[None, :] * cos - np.sqrt(np.where(ok, root, 0.0)), np.inf)
    e = np.maximum(touch.min(axis=1), 0.0)
    gap = np.hypot(rho[None, :] * cos - e[:, None], rho[None, :] * sin) - journal_radius
    return np.where(near, np.maximum(gap, 0.0), np.inf), cos


def _advance(gap: np.ndarray, cos: np.ndarray, rho: np.ndarray, need: np.ndarray) -> np.ndarray:
    """The journal's advance ``d0`` [m] per row at which ``sum rho cos max(d0 cos - gap, 0)``
    reaches ``need`` [m²] (the load over ``kf dphi``), exactly.

    Point k joins the contact at ``d0 = gap_k / cos_k``; between two such thresholds the sum
    is linear in ``d0``, ``d0 S1 - S2`` with ``S1 = sum rho cos²``, ``S2 = sum rho gap cos``
    over the points already in contact, so the root follows from the thresholds in order.
    """
    ok = cos > 1e-9
    thresh = np.where(ok, gap / np.where(ok, cos, 1.0), np.inf)
    order = np.argsort(thresh, axis=1, kind="stable")
    t = np.take_along_axis(thresh, order, axis=1)
    c = np.take_along_axis(np.where(ok, cos, 0.0), order, axis=1)
    g = np.take_along_axis(np.where(ok, gap, 0.0), order, axis=1)
    r = np.take_along_axis(np.broadcast_to(rho, cos.shape), order, axis=1)
    s1 = np.cumsum(r * c * c, axis=1)
    s2 = np.cumsum(r * g * c, axis=1)
    # carried when the next point is about to join (the last: unbounded)
    nxt = np.concatenate([t[:, 1:], np.full((t.shape[0], 1), np.inf)], axis=1)
    with np.errstate(invalid="ignore"):
        at_next = np.where(np.isfinite(nxt), nxt * s1 - s2, np.inf)
    i = np.argmax(at_next >= need[:, None], axis=1)
    rows = np.arange(t.shape[0])
    return (need + s2[rows, i]) / s1[rows, i]


def conformal_wear_work(
    centre_work: np.ndarray,
    centre_force_work: np.ndarray,
    wear_depth: np.ndarray,
    point_area: np.ndarray,
    *,
    journal_radius: float,
    bearing_radius: float,
    reduced_modulus: float,
    foundation: float | None = None,
) -> np.ndarray:
    """The wear work [Pa m] per point under the conformal (Winkler) pressure.

    Parameters
    ----------
    centre_work : ndarray (Nl, Nd)
        Per layer and node, the work ``sum F |v_t| dt`` [N m] of the contacts centred there
        (the slice's force F along that node's normal; the kernel's third wear plane).
    centre_force_work : ndarray (Nl, Nd)
        ``sum F^2 |v_t| dt`` [N² m] at the same nodes: ``centre_force_work / centre_work`` is
        the work-weighted mean force [N] of those contacts.
    wear_depth : ndarray (Nl, Nd)
        The worn bore's depth h [m] (bore radius ``bearing_radius + h``), nodes at equal
        angular spacing.
    point_area : ndarray (Nl, Nd)
        The bore area of each point [m²] (``slice width x (Rb + h) dphi``).
    journal_radius, bearing_radius : float
        Rj and the unworn bore radius Rb [m].
    reduced_modulus : float
        E* of the pair [Pa] (Hertz's width, to which the foundation is matched).
    foundation : float, optional
        A fixed foundation modulus kf [Pa/m] (e.g. :func:`foundation_modulus` of a lining);
        default: matched per load to Hertz's width (:func:`hertz_matched_modulus`).

    Returns
    -------
    ndarray (Nl, Nd)
        ``integral p |ds|`` [Pa m]: each centre's work spread by its Winkler pressure, the
        pressure's resultant equal to its force (so the sum of work times area exceeds the
        centres' work by 1 / mean cos over a wide arc).
    """
    work = np.asarray(centre_work, dtype=float)
    force_work = np.asarray(centre_force_work, dtype=float)
    h = np.asarray(wear_depth, dtype=float)
    area = np.asarray(point_area, dtype=float)
    nl, nd = work.shape
    phi = np.arange(nd) * 2 * math.pi / nd
    dphi = 2 * math.pi / nd
    out = np.zeros((nl, nd))
    for n in range(nl):
        src = np.flatnonzero((work[n] > 0) & (force_work[n] > 0))
        if not src.size:
            continue
        rho = bearing_radius + h[n]
        width = float(area[n, 0] / (rho[0] * dphi))  # the slice's axial width [m]
        force = force_work[n, src] / work[n, src]
        line_load = force / width
        if foundation is None:
            kf = hertz_matched_modulus(line_load, journal_radius, bearing_radius, reduced_modulus)
        else:
            kf = np.full(src.size, float(foundation))
        gap, cos = _seated_gaps(rho, journal_radius, phi, src)
        d0 = _advance(gap, cos, rho, line_load / (kf * dphi))
        p = kf[:, None] * np.maximum(d0[:, None] * cos - gap, 0.0)  # [Pa]
        resultant = np.sum(p * np.maximum(cos, 0.0) * area[n][None, :], axis=1)  # [N]
        out[n] = np.sum((work[n, src] / resultant)[:, None] * p, axis=0)
    return out
