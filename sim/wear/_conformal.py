"""Conformal-contact wear: the wear pressure from an elastic (Winkler) foundation over the worn
bore's local geometry, as an option of the wear loop.

The dynamics spread each slice's normal force over the points the rigid journal overlaps, with
the Hertz weights of a non-conforming contact (docs/sim.md). As the bore wears into the
journal's shape the contact conforms: the gap between journal and bore closes over a wide arc,
the same load is carried over more of it, the peak pressure falls and so does the depth rate
where the bore is deepest (the volume rate, kw times the normal work, does not change). The
elastic-foundation (Winkler) model is the usual description of such conformal contact in
revolute joints with wear (S. Mukras, N.H. Kim, N.A. Mauntler, T.L. Schmitz, W.G. Sawyer,
"Analysis of planar multibody systems with revolute joint wear", Wear 268 (2010) 643-652;
K.L. Johnson, *Contact Mechanics*, 1985, sections 5.9 and 9.2). A Winkler foundation is
a poor model of a non-conforming contact, and its modulus is not a material constant (for an
elastic layer of thickness t on a rigid base ``kf = (1 - nu) E / ((1 + nu)(1 - 2 nu) t)``,
:func:`foundation_modulus`; the bush's wall is not known here). The modulus is therefore
matched, per contact and load, so that on the *unworn* bore the foundation gives Hertz's
contact width for a cylinder in a cylinder (:func:`hertz_matched_modulus`): the option then
changes nothing where the contact does not conform and spreads the load where it does.

:class:`ConformalContact` runs the dynamics as :class:`~jointwear.sim.DynamicContact` does and
then, per layer and per point with wear work, spreads that work by the Winkler pressure of a rigid
journal seated in the worn bore in that point's direction and pressed with the line load its
pressure implies (:func:`conformal_layer`, :func:`winkler_line_pressure` the scalar reference),
conserving each layer's wear work (so the worn volume is still kw times the normal work). Every
point a contact covers is taken to slide as the contact does (as the kernel does for a slice).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from scipy.optimize import brentq

from jointwear.errors import ParameterError
from jointwear.sim.wear._contact import CycleWear, DynamicContact

__all__ = [
    "ConformalContact",
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
    line_load: float,
    journal_radius: float,
    bore_radius: float,
    reduced_modulus: float,
) -> float:
    """Winkler modulus [Pa/m] that gives Hertz's contact width on the unworn bore.

    Hertz, cylinder in a cylindrical bore under ``line_load`` F' [N/m]: half-width
    ``b = sqrt(4 F' R' / (pi E*))``, ``R' = Rj Rb / (Rb - Rj)``. The foundation under a journal
    seated in the unworn bore (gap ``c' (1 - cos phi)``, ``c' = Rb c / Rj``) touches
    ``|phi| < a`` with ``cos a = c' / (d0 + c')`` and carries
    ``F' = kf Rb ((d0 + c')(a + sin a cos a) - 2 c' sin a)``; with ``a = b / Rb`` this gives kf.
    """
    rj, rb = journal_radius, bore_radius
    clearance = rb - rj
    r_eff = rj * rb / clearance
    b = math.sqrt(4 * line_load * r_eff / (math.pi * reduced_modulus))
    a = min(b / rb, 0.5 * math.pi - 1e-6)
    cp = rb * clearance / rj
    d0 = cp * (1 / math.cos(a) - 1)
    carried = rb * ((d0 + cp) * (a + math.sin(a) * math.cos(a)) - 2 * cp * math.sin(a))
    return line_load / carried


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


def conformal_layer(
    work: np.ndarray,
    sliding: np.ndarray,
    bore_radius: np.ndarray,
    journal_radius: float,
    unworn_radius: float,
    reduced_modulus: float,
) -> np.ndarray:
    """One layer's wear work [Pa m] redistributed point by point by the Winkler pressure.

    ``work``, ``sliding`` and ``bore_radius`` (worn, Rb + h) per point of the layer (canonical
    angles at equal spacing). Each point's work is taken as made by a contact centred there,
    whose line load follows from its mean pressure while sliding ``p = work / sliding`` read as
    Hertz's peak pressure, ``F' = pi R' p^2 / E*``; it is spread over the points the journal,
    seated in the worn bore in that direction and pressed with ``F'`` into a foundation matched
    to Hertz's width (:func:`hertz_matched_modulus`), compresses, in proportion to the
    pressure. On the unworn bore that spread is Hertz's width (a fraction of a grid step at the
    reference rig's loads: nothing changes); in a conforming groove it covers the groove. The
    layer's total work (area-weighted) is kept.
    """
    n = work.size
    src = np.flatnonzero((work > 0) & (sliding > 0))
    if not src.size:
        return np.array(work, dtype=float)
    phi = np.arange(n) * 2 * math.pi / n
    dphi = 2 * math.pi / n
    rho = np.asarray(bore_radius, dtype=float)
    clearance = unworn_radius - journal_radius
    r_eff = journal_radius * unworn_radius / clearance
    pbar = work[src] / sliding[src]
    load = math.pi * r_eff * pbar**2 / reduced_modulus
    kf = np.array(
        [hertz_matched_modulus(f, journal_radius, unworn_radius, reduced_modulus) for f in load]
    )
    gap, cos = _seated_gaps(rho, journal_radius, phi, src)
    cpos = np.maximum(cos, 0.0)
    r = float(np.mean(rho))

    def carried(d0: np.ndarray) -> np.ndarray:
        comp = np.maximum(d0[:, None] * cos - gap, 0.0)
        return kf * np.sum(comp * cpos, axis=1) * r * dphi

    lo = np.zeros(src.size)
    hi = load / (kf * r * dphi) + 1e-15
    while np.any(carried(hi) < load):
        hi = np.where(carried(hi) < load, 2 * hi, hi)
    for _ in range(60):  # bisection on every source at once (relative precision 1e-18)
        mid = 0.5 * (lo + hi)
        low = carried(mid) < load
        lo, hi = np.where(low, mid, lo), np.where(low, hi, mid)
    p = np.maximum(0.5 * (lo + hi)[:, None] * cos - gap, 0.0)
    weight = np.sum(p * rho[None, :], axis=1)
    out = np.array(work, dtype=float)
    out[src] = 0.0
    spread = weight > 0
    share = (work[src] * rho[src])[spread] / weight[spread]
    out += np.sum(share[:, None] * p[spread], axis=0)
    out[src[~spread]] += work[src[~spread]]
    return out


class ConformalContact(DynamicContact):
    """EXPERIMENTAL, not validated: the dynamics with conformal-contact wear pressure.

    Not an option of ``jointwear sim wear`` and not exported: on the reference rig (8 x 120,
    8e3 cycles at 50 x kw) it made the maximum depth 39 % *deeper* than the dynamics' own
    pressure: re-seating the journal along each point's direction moves the work off the point
    where the dynamics pressed (on the flank of a 20-um groove, 5 deg outwards onto the rim it
    touches first), so the worn shape drifts (docs/sim-wear.md, "Conformal contact"). The
    pressure belongs in the kernel's spreading, where the journal's true position is known.

    Parameters
    ----------
    params : SimParameters
        The rig (the materials give E*, the bore the unworn radius).
    cycle_function : callable, optional
        As for :class:`DynamicContact`.
    """

    def __init__(self, params: Any, cycle_function: Any = None) -> None:
        super().__init__(params, cycle_function)
        c = params.contact
        self.reduced_modulus = 1.0 / (
            (1 - c.journal_poisson**2) / c.journal_modulus
            + (1 - c.bearing_poisson**2) / c.bearing_modulus
        )

    def describe(self) -> dict[str, Any]:
        out = super().describe()
        out["wear_pressure"] = "conformal (Winkler foundation over the worn bore, Hertz-matched)"
        return out

    def run(
        self, wear_depth: np.ndarray, *, cycles: float, state: Any, progress: Any = None
    ) -> CycleWear:
        res = self._run_cycles(wear_depth, cycles=cycles, state=state, progress=progress)
        j = self.params.joint
        work = np.asarray(res.wear_work, dtype=float)
        slide = np.asarray(res.sliding_distance, dtype=float)
        radius = j.bearing_radius + np.asarray(wear_depth, dtype=float)
        new = np.stack(
            [
                conformal_layer(
                    work[n],
                    slide[n],
                    radius[n],
                    j.journal_radius,
                    j.bearing_radius,
                    self.reduced_modulus,
                )
                for n in range(work.shape[0])
            ]
        )
        return self._cycle_wear(res, new)
