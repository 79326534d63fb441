"""Public API of :mod:`jointwear.metrology` (re-exported by the package ``__init__``)."""

from __future__ import annotations

from jointwear.metrology.assess import CentringWarning, assess, assess_points, form_table
from jointwear.metrology.filters import (
    STANDARD_CUTOFFS,
    filter_profile,
    harmonic_spectrum,
    remove_outliers,
    transmission,
)
from jointwear.metrology.fit import (
    CircleFit,
    CylinderFit,
    fit_circle,
    fit_circle_polar,
    fit_cylinder,
    fit_cylinder_polar,
)
from jointwear.metrology.form import (
    REFERENCES,
    ZoneResult,
    circle_zone,
    cylinder_zone,
    cylindricity,
    limacon_error,
    roundness,
)
from jointwear.metrology.plot import plot_wear_map
from jointwear.metrology.readers import (
    ScanReading,
    TextFormat,
    read_scan,
    read_talyrond,
    read_text,
)
from jointwear.metrology.wearmap import register_angle, wear_map, worn_volume

__all__ = [
    "REFERENCES",
    "STANDARD_CUTOFFS",
    "CentringWarning",
    "CircleFit",
    "CylinderFit",
    "ScanReading",
    "TextFormat",
    "ZoneResult",
    "assess",
    "assess_points",
    "circle_zone",
    "cylinder_zone",
    "cylindricity",
    "filter_profile",
    "fit_circle",
    "fit_circle_polar",
    "fit_cylinder",
    "fit_cylinder_polar",
    "form_table",
    "harmonic_spectrum",
    "limacon_error",
    "plot_wear_map",
    "read_scan",
    "read_talyrond",
    "read_text",
    "register_angle",
    "remove_outliers",
    "roundness",
    "transmission",
    "wear_map",
    "worn_volume",
]
