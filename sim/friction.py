"""Smoothed Coulomb friction of joint C (eq. 12 of the reference study)."""

from __future__ import annotations

import numpy as np

from jointwear.sim.parameters import FrictionParameters

__all__ = ["friction_coefficient"]


def friction_coefficient(
    sliding_speed: np.ndarray | float, friction: FrictionParameters | None = None
) -> np.ndarray:
    """Friction coefficient mu(|v|) of eq. 12.

    mu = mu_s sin(pi |v| / (2 v_s)) for |v| < v_s; a cosine blend from mu_s to mu_d for
    v_s <= |v| <= v_d; mu_d above v_d. The friction force opposes the relative sliding velocity
    with magnitude mu F_n. Zero when friction is disabled.

    Parameters
    ----------
    sliding_speed : array_like
        Relative tangential speed |v| [m/s].
    friction : FrictionParameters, optional
        Coefficients and velocities (default: the study's values).
    """
    f = friction or FrictionParameters()
    v = np.abs(np.asarray(sliding_speed, dtype=float))
    if not f.enabled:
        return np.zeros_like(v)
    mus, mud, vs, vd = (
        f.static_coefficient,
        f.dynamic_coefficient,
        f.stick_velocity,
        f.slide_velocity,
    )
    low = mus * np.sin(0.5 * np.pi * v / vs)
    mid = mud + (mus - mud) * 0.5 * (1 + np.cos(np.pi * (v - vs) / (vd - vs)))
    return np.where(v < vs, low, np.where(v <= vd, mid, mud))
