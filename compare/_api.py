"""Public names of :mod:`jointwear.compare` (alignment in xarray and validation metrics)."""

from jointwear.compare.align import MOTION_VARIABLES, align_time_series, align_wear_maps
from jointwear.compare.comparison import (
    Comparison,
    Criteria,
    compare,
    load_comparison,
    load_criteria,
    metrics_table,
    save_comparison,
)
from jointwear.compare.metrics import (
    DEFINITIONS,
    VV20,
    SpragueGeers,
    area_validation_metric,
    lsq_cylindricity,
    max_location,
    nrmse,
    pearson_r,
    rmse,
    sprague_geers,
    vv20,
    worn_volume,
    wrap_angle_deg,
)

__all__ = [
    "MOTION_VARIABLES",
    "align_time_series",
    "align_wear_maps",
    "Comparison",
    "Criteria",
    "compare",
    "load_comparison",
    "load_criteria",
    "metrics_table",
    "save_comparison",
    "DEFINITIONS",
    "VV20",
    "SpragueGeers",
    "area_validation_metric",
    "lsq_cylindricity",
    "max_location",
    "nrmse",
    "pearson_r",
    "rmse",
    "sprague_geers",
    "vv20",
    "worn_volume",
    "wrap_angle_deg",
]
