"""Contact law of joint C: Lankarani-Nikravesh force with constant or time-varying stiffness.

Eqs. 6-10 of the reference study. The per-step contact search and force assembly run in numba
(:mod:`jointwear.sim.kernels`); the functions here give the same laws for single values, for
analysis and tests.
"""

from __future__ import annotations

import math

import numpy as np

from jointwear.sim.parameters import SimParameters

__all__ = ["contact_constant", "contact_stiffness", "lankarani_nikravesh_force"]


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
