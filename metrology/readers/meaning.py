"""What the numbers of a column mean: angle unit, angular span, value kind."""

from __future__ import annotations

import numpy as np

__all__ = []


def _guess_angle_kind(col: np.ndarray) -> str:
    c = col[np.isfinite(col)]
    if c.size < 2:
        return "angle_deg"
    span = float(np.max(c) - np.min(c))
    if (
        np.all(np.abs(c - np.round(c)) < 1e-9)
        and np.min(c) >= 0
        and span == c.size - 1
        and c.size != 360
    ):
        return "index"
    if np.max(np.abs(c)) <= 2 * np.pi + 1e-6 and c.size > 8:
        return "angle_rad"
    return "angle_deg"


def _value_kind(v: np.ndarray) -> str:
    f = v[np.isfinite(v)]
    if f.size == 0:
        return "deviation"
    mean = float(np.mean(f))
    ptp = float(np.ptp(f))
    return "radius" if mean > 0 and mean > 20 * max(ptp, 1e-300) else "deviation"
