"""Public API of :mod:`jointwear.metrology` (re-exported by the package ``__init__``)."""

from __future__ import annotations

from jointwear.metrology.form import (
    REFERENCES,
    ZoneResult,
    circle_zone,
    cylinder_zone,
    cylindricity,
    limacon_error,
    roundness,
)
from jointwear.metrology.wearmap import register_angle, wear_map, worn_volume

__all__ = [
    "REFERENCES",
    "ZoneResult",
    "circle_zone",
    "cylinder_zone",
    "cylindricity",
    "limacon_error",
    "roundness",
    "register_angle",
    "wear_map",
    "worn_volume",
]
