"""Contact law of joint C: Lankarani-Nikravesh force with constant or time-varying stiffness.

Eqs. 6-10 of the reference study. The per-step contact search and force assembly run in numba
(:mod:`jointwear.sim.kernels`); the functions here give the same laws for single values, for
analysis and tests.
"""

from __future__ import annotations

import math

import numpy as np

from jointwear.sim.parameters import SimParameters

__all__ = [
    "contact_constant",
    "contact_stiffness",
    "lankarani_nikravesh_force",
    "effective_restitution",
]


def contact_constant(params: SimParameters) -> tuple[float, float]:
    """Material factor 4 / (3 pi (hj + hb)) [Pa] and the constant stiffness K of eq. 7 [N/m^1.5].

    h_m = (1 - nu_m^2) / (pi E_m) for journal and bearing materials.
    """
    c = params.contact
    hj = (1 - c.journal_poisson**2) / (math.pi * c.journal_modulus)
    hb = (1 - c.bearing_poisson**2) / (math.pi * c.bearing_modulus)
    kfac = 4.0 / (3.0 * math.pi * (hj + hb))
    rj, rb = params.joint.journal_radius, params.joint.bearing_radius
    return kfac, kfac * math.sqrt(rj * rb / (rb - rj))


def contact_stiffness(params: SimParameters, wear_depth: np.ndarray | float = 0.0) -> np.ndarray:
    """Contact stiffness K at bearing points with local wear depth h [N/m^1.5] (eqs. 7-9).

    ``contact.stiffness = "constant"`` gives eq. 7 everywhere. ``"time_varying"`` gives eq. 9:
    K = 4/(3 pi (hj + hb)) sqrt(Rj (Rb + h) / (Rb - Rj)), or with Rb + h - Rj in the
    denominator when ``contact.worn_radius_in_denominator`` is set.

    Parameters
    ----------
    params : SimParameters
    wear_depth : array_like
        Local wear depth h [m].
    """
    kfac, k0 = contact_constant(params)
    h = np.asarray(wear_depth, dtype=float)
    if params.contact.stiffness == "constant":
        return np.full(h.shape, k0)
    rj, rb = params.joint.journal_radius, params.joint.bearing_radius
    den = (rb + h - rj) if params.contact.worn_radius_in_denominator else (rb - rj)
    return kfac * np.sqrt(rj * (rb + h) / den)


def lankarani_nikravesh_force(
    penetration: np.ndarray | float,
    penetration_rate: np.ndarray | float,
    impact_velocity: float,
    stiffness: float,
    *,
    restitution: float = 0.9,
    exponent: float = 1.5,
    impact_velocity_floor: float = 1e-2,
) -> np.ndarray:
    """Lankarani-Nikravesh normal force (eq. 6) [N].

    F = K delta^n [1 + 3 (1 - ce^2) delta_dot / (4 v)], v = max(impact_velocity, floor),
    zero without penetration and never negative (no adhesion).

    Parameters
    ----------
    penetration : array_like
        delta [m].
    penetration_rate : array_like
        d delta / dt [m/s] (positive while approaching).
    impact_velocity : float
        Approach velocity at the onset of the impact [m/s].
    stiffness : float
        K [N/m^n].
    """
    d = np.asarray(penetration, dtype=float)
    v = max(float(impact_velocity), impact_velocity_floor)
    fac = 1.0 + 3.0 * (1.0 - restitution**2) * np.asarray(penetration_rate, dtype=float) / (4 * v)
    f = stiffness * np.where(d > 0, d, 0.0) ** exponent * np.maximum(fac, 0.0)
    return np.where(d > 0, f, 0.0)


def effective_restitution(restitution: float, exponent: float = 1.5) -> float:
    """The rebound ratio one impact under the Lankarani-Nikravesh law actually gives [1].

    Lankarani and Nikravesh (1990) derived the damping term of eq. 6 for restitution
    coefficients close to 1, so the nominal ``contact.restitution`` ``ce`` is the rebound ratio
    only there; for lower values the law dissipates less than nominal (0.3 gives about 0.68).
    Computed by integrating one impact of a mass on the contact,
    ``m d'' = -K d^n (1 + 3 (1 - ce^2) d' / (4 v0))``, from ``d = 0``, ``d' = v0`` until the
    contact opens: made dimensionless with ``d* = (m v0^2 / K)^(1 / (n + 1))`` and ``d* / v0``
    it depends on ``ce`` and ``n`` only (for ``v0`` above ``contact.impact_velocity_floor``).

    Parameters
    ----------
    restitution : float
        Nominal ce in (0, 1].
    exponent : float
        n of the law (1.5: Hertz).

    Returns
    -------
    float
        Rebound velocity over approach velocity.
    """
    from scipy.integrate import solve_ivp

    ce, n = float(restitution), float(exponent)
    if not 0 < ce <= 1:
        raise ValueError(f"restitution must be in (0, 1], got {restitution!r}")
    damp = 3.0 * (1.0 - ce * ce) / 4.0

    def rhs(_t: float, s: np.ndarray) -> list[float]:
        x, v = s
        return [v, -(max(x, 0.0) ** n) * max(1.0 + damp * v, 0.0)]

    def opens(_t: float, s: np.ndarray) -> float:
        return s[0]

    opens.terminal, opens.direction = True, -1  # type: ignore[attr-defined]
    sol = solve_ivp(rhs, (0.0, 100.0), [1e-12, 1.0], events=opens, rtol=1e-11, atol=1e-14)
    return float(-sol.y_events[0][0][1])
