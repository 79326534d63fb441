"""The simulated counterpart of a reported quantity, computed on a wear map at the measured places.

Pure functions on a simulated wear map (``wear_depth`` over ``z, theta`` [m], canonical angle
convention) and the description of a reported quantity (the attributes written by
:func:`jointwear.reported.reported_dataset`). What the source leaves unstated (the direction of
its angles, which end of the bore its layer 1 is at) is enumerated as *readings*
(:func:`readings`); every reading is evaluated and the caller decides whether they agree.
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
import xarray as xr

import jointwear.compare.metrics as mt
from jointwear.conventions import CANONICAL, AngleConvention

__all__ = [
    "SEPARATION",
    "Reading",
    "readings",
    "layer_z",
    "quantity_z",
    "profile_at",
    "mz_cylindricity",
    "evaluate",
    "measured_angle",
]

_DIRECTIONS = ("clockwise", "counterclockwise")


@dataclass(frozen=True)
class Reading:
    """One way to read what the source leaves unstated.

    Attributes
    ----------
    direction : str
        Direction of the reported angles (``"clockwise"``/``"counterclockwise"``, or
        ``"stated"`` when the file states it and the values are already canonical).
    first : str
        End of the bore where layer 1 lies (``"+z"``/``"-z"``, or ``""`` without layers).
    z_centre : float or None
        Axial position of the middle of the layer stack [m] when the file leaves it unstated
        (None: as stated).
    """

    direction: str
    first: str
    z_centre: float | None = None

    def label(self, attrs: Mapping[str, Any]) -> str:
        """E.g. ``"angles counterclockwise, layer 1 at +z"`` (only the unstated parts)."""
        parts = []
        if self.direction != "stated":
            parts.append(f"angles {self.direction}")
        if attrs.get("layers_first") == "unstated" and self.first:
            parts.append(f"layer 1 at {self.first}")
        if self.z_centre is not None:
            parts.append(f"layers centred at z = {self.z_centre * 1e3:+.2f} mm")
        return ", ".join(parts)


#: the derived kind: angle between the maxima of two reported layers at the same cycles
SEPARATION = "max_wear_angle_separation"

#: positions of an unstated layer stack tried across the simulated bore (both ends included)
STACK_POSITIONS = 5


def readings(
    attrs: Mapping[str, Any], q: Mapping[str, Any], z_range: tuple[float, float] | None = None
) -> list[Reading]:
    """Every reading of what the file leaves unstated that matters for quantity ``q``.

    The angle direction matters for an angle, the layer order for a quantity at one layer, the
    position of the stack (``z_centre`` unstated) for any quantity on the layers: it is tried at
    :data:`STACK_POSITIONS` positions from one end of the simulated bore (``z_range``) to the
    other.
    """
    directions = ["stated"]
    if q.get("kind") == "max_wear_angle" and q.get("angle_direction") == "unstated":
        directions = list(_DIRECTIONS)
    on_layers = "z_m" not in q and "layers_count" in attrs
    first = str(attrs.get("layers_first", ""))
    firsts = [first]
    if not on_layers or int(q.get("layer", 0)) == 0:
        firsts = ["+z"] if on_layers else [""]  # the order of the whole stack does not matter
    elif first == "unstated":
        firsts = ["+z", "-z"]
    centres: list[float | None] = [None]
    if on_layers and not np.isfinite(float(attrs.get("layers_z_centre_m", 0.0))):
        span = (int(attrs["layers_count"]) - 1) * float(attrs["layers_spacing_m"])
        lo, hi = z_range if z_range is not None else (0.0, 0.0)
        if hi - lo >= span - 1e-12:
            half = 0.5 * (hi - lo - span)
            mid = 0.5 * (hi + lo)
            centres = [float(c) for c in np.linspace(mid - half, mid + half, STACK_POSITIONS)]
        else:
            centres = [float("nan")]  # longer than the simulated bore: nowhere inside
    return [Reading(d, f, c) for d, f, c in itertools.product(directions, firsts, centres)]


def layer_z(attrs: Mapping[str, Any], first: str, z_centre: float | None = None) -> np.ndarray:
    """Axial position [m] of measured layers 1..n (z from the bearing mid-width)."""
    n = int(attrs["layers_count"])
    step = float(attrs["layers_spacing_m"])
    offsets = (np.arange(n) - (n - 1) / 2.0) * step
    sign = -1.0 if first == "+z" else 1.0  # layer 1 at the +z end: z decreases with the number
    centre = float(attrs["layers_z_centre_m"]) if z_centre is None else z_centre
    return centre + sign * offsets


def quantity_z(q: Mapping[str, Any], attrs: Mapping[str, Any], reading: Reading) -> np.ndarray:
    """Axial positions [m] where quantity ``q`` (variable attributes) was measured."""
    if "z_m" in q:
        return np.array([float(q["z_m"])])
    zs = layer_z(attrs, reading.first, reading.z_centre)
    layer = int(q.get("layer", 0))
    return zs if layer == 0 else zs[layer - 1 : layer]


def profile_at(wear: xr.DataArray, z: np.ndarray) -> np.ndarray | None:
    """Wear depth over ``(len(z), theta)`` by linear interpolation between the simulated layers.

    None when a position lies outside the simulated layers (never extrapolated).
    """
    zs = np.asarray(wear["z"].values, dtype=float)
    if not np.all(np.isfinite(z)) or np.any(z < zs.min() - 1e-12) or np.any(z > zs.max() + 1e-12):
        return None
    values = np.asarray(wear.transpose("z", "theta").values, dtype=float)
    out = np.empty((z.size, values.shape[1]))
    for j in range(values.shape[1]):
        out[:, j] = np.interp(z, zs, values[:, j])
    return out


def mz_cylindricity(field: np.ndarray, z: np.ndarray, theta_deg: np.ndarray) -> float:
    """Minimum-zone cylindricity (limaçon model) of a radial-deviation field [m].

    The smallest ``t`` such that two coaxial limaçon cylinders ``a0 + (a1 + a2 z) cos +
    (b1 + b2 z) sin`` and the same plus ``t`` enclose every point: a linear programme (HiGHS
    through :func:`scipy.optimize.linprog`). Never larger than the least-squares value.
    """
    from scipy.optimize import linprog

    f = np.asarray(field, dtype=float)
    zz, tt = np.meshgrid(np.asarray(z, dtype=float), np.deg2rad(theta_deg), indexing="ij")
    ok = np.isfinite(f)
    c, s, zk = np.cos(tt[ok]), np.sin(tt[ok]), zz[ok]
    x = np.column_stack([np.ones_like(c), c, zk * c, s, zk * s])
    h = f[ok]
    scale = float(np.max(np.abs(h))) or 1.0
    h = h / scale
    n = x.shape[1]
    # variables [beta (n), upper, lower]: minimise upper - lower with lower <= h - X beta <= upper
    cost = np.zeros(n + 2)
    cost[n], cost[n + 1] = 1.0, -1.0
    ones = np.ones((h.size, 1))
    a_ub = np.vstack([np.hstack([-x, -ones, 0 * ones]), np.hstack([x, 0 * ones, ones])])
    b_ub = np.concatenate([-h, h])
    res = linprog(cost, A_ub=a_ub, b_ub=b_ub, bounds=[(None, None)] * (n + 2), method="highs")
    if not res.success:  # pragma: no cover - the problem is always feasible and bounded
        return float("nan")
    return float(res.fun) * scale


def measured_angle(value: float, attrs: Mapping[str, Any], reading: Reading) -> float:
    """A reported angle in the canonical convention under ``reading`` [degree]."""
    if reading.direction == "stated" or attrs.get("angle_direction") != "unstated":
        return float(value)
    conv = AngleConvention(str(attrs["angle_zero"]), reading.direction)
    return float(CANONICAL.from_physical(conv.to_physical(value)))


def evaluate(
    wear: xr.DataArray, q: Mapping[str, Any], attrs: Mapping[str, Any], reading: Reading
) -> tuple[float, str]:
    """The simulated value of reported quantity ``q`` on the map ``wear`` (z, theta) [m].

    Returns
    -------
    (float, str)
        The value (m, or degree canonical) and '' - or NaN and why the simulation cannot give
        it (a position outside the simulated bore, no wear there, a definition it lacks).
    """
    kind = q["kind"]
    if kind == SEPARATION:
        (a, why_a), (b, why_b) = (evaluate(wear, p, attrs, reading) for p in q["pair"])
        if why_a or why_b:
            return float("nan"), why_a or why_b
        return abs(float(mt.wrap_angle_deg(a - b))), ""
    if kind == "other":
        return float("nan"), (
            f"jointwear's simulation has no quantity of this definition "
            f"({q.get('definition', 'not given')})"
        )
    z = quantity_z(q, attrs, reading)
    prof = profile_at(wear, z)
    if prof is None:
        zs = np.asarray(wear["z"].values, dtype=float)
        return float("nan"), (
            f"measured at z = {', '.join(f'{v * 1e3:+.2f}' for v in (z.min(), z.max()))} mm, "
            f"outside the simulated bore (z = {zs.min() * 1e3:+.2f} to {zs.max() * 1e3:+.2f} mm)"
        )
    theta = np.asarray(wear["theta"].values, dtype=float)
    if kind == "cylindricity":
        if z.size < 2:
            return float("nan"), "a cylindricity needs at least two layers"
        ls = mt.lsq_cylindricity(prof, z, theta)
        if q["reference"] == "LS":
            return ls, ""
        mz = mz_cylindricity(prof, z, theta)
        return (mz, "") if q["reference"] == "MZ" else (0.5 * (ls + mz), "")
    if not np.nanmax(prof) > 0:
        return float("nan"), "the simulation predicts no wear at the measured position"
    value, _, th = mt.max_location(prof, z, theta)
    return (th, "") if kind == "max_wear_angle" else (value, "")


def reference_spread(wear: xr.DataArray, q: Mapping[str, Any], attrs, reading) -> float:
    """Half the difference LS - MZ of the simulated cylindricity (reference not stated) [m]."""
    z = quantity_z(q, attrs, reading)
    prof = profile_at(wear, z)
    if prof is None or z.size < 2:
        return float("nan")
    theta = np.asarray(wear["theta"].values, dtype=float)
    return 0.5 * (mt.lsq_cylindricity(prof, z, theta) - mz_cylindricity(prof, z, theta))
