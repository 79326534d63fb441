"""Defaults of the importers of other tools' tables (:mod:`jointwear.external`), one source for
the library and ``jointwear import`` (light: the CLI reads them without numpy)."""

from __future__ import annotations

__all__ = ["TIME_COLUMN", "TIME_UNIT", "VELOCITY_COLUMNS", "WEAR_MAP_COLUMNS", "Z_MID_WIDTH"]

#: the time column of a motion table and its unit
TIME_COLUMN = "time"
TIME_UNIT = "s"
#: the velocity columns of a motion table, x, y[, z] in the bearing frame
VELOCITY_COLUMNS = ("vx", "vy", "vz")
#: the theta, z and depth columns of a wear-map table
WEAR_MAP_COLUMNS = ("theta", "z", "wear_depth")
#: z of the bearing mid-width in a wear-map table [its z unit]
Z_MID_WIDTH = 0.0
