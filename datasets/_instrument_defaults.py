"""Defaults and choices of the roundness-instrument generator, one source for
:mod:`jointwear.datasets.instruments` and ``jointwear datasets instruments`` (light: the CLI
reads them without importing numpy). SI units, as the library takes them.
"""

from __future__ import annotations

__all__ = [
    "ANGLE",
    "ANGLE_COLUMNS",
    "CONVENTION",
    "DECIMAL",
    "DELIMITER",
    "ECCENTRICITY",
    "LAYER_SPACING",
    "LAYOUT",
    "LAYOUTS",
    "LENGTH_UNITS",
    "MIN_LAYERS",
    "MIN_POINTS",
    "NOISE",
    "N_LAYERS",
    "N_POINTS",
    "QUANTISATION",
    "RADIUS",
    "SEED",
    "TILT",
    "UNITS",
    "VALUE",
    "VALUES",
    "WEAR_DEPTH",
]

# --- generate(): the scan (the reference study's instrument: 13 layers x 18000 points) ------
N_LAYERS = 13
N_POINTS = 18000
#: fewest layers and points per layer a scan may have
MIN_LAYERS, MIN_POINTS = 1, 8
#: nominal bore radius [m]
RADIUS = 8e-3
#: distance between layers [m]
LAYER_SPACING = 1e-3
#: part axis offset from the spindle at mid-width, instrument x and y [m]
ECCENTRICITY = (15e-6, -8e-6)
#: part axis tilt dx/dz, dy/dz [1]
TILT = (1.5e-3, -0.8e-3)
#: peak depth of the default wear [m]
WEAR_DEPTH = 20e-6
#: standard deviation of the probe noise [m]
NOISE = 0.02e-6
#: resolution of the readings [m]
QUANTISATION = 1e-9
#: the instrument's angle convention in the bearing frame (zero, direction)
CONVENTION = ("+y", "counterclockwise")
#: seed of the form (and of the noise without a noise seed)
SEED = 0

# --- write(): the files ---------------------------------------------------------------------
#: layouts write() supports, and its default
LAYOUTS = ("folder", "folder-names", "folder-header", "long", "wide", "single")
LAYOUT = "folder"
#: angle column styles write() supports, and its default
ANGLE_COLUMNS = ("deg", "rad", "index", "none", "xy")
ANGLE = "deg"
#: what the value column holds, and its default
VALUES = ("deviation", "radius")
VALUE = "deviation"
#: length units of the values [m per unit], and the default
LENGTH_UNITS = {"um": 1e-6, "mm": 1e-3, "m": 1.0, "inch": 0.0254}
UNITS = "um"
#: field and decimal separators
DELIMITER = "\t"
DECIMAL = "."
