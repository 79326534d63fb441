"""Public names of :mod:`jointwear.compare` (alignment in xarray and validation metrics)."""

from jointwear.compare.align import MOTION_VARIABLES, align_time_series, align_wear_maps
from jointwear.compare.comparison import DEFAULT_AXES, Comparison, compare
from jointwear.compare.criteria import Criteria, load_criteria
from jointwear.compare.ensemble import Ensemble, as_ensemble
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
from jointwear.compare.origin import origin_of, side_origin
from jointwear.compare.storage import (
    compare_files,
    load_comparison,
    metrics_table,
    save_comparison,
)
from jointwear.compare.verdicts import FLAG_MEANINGS, FLAG_VALUES, STATES, summary_line
from jointwear.compare.verification import GCI, gci, numerical_uncertainty

__all__ = [
    "MOTION_VARIABLES",
    "align_time_series",
    "align_wear_maps",
    "Comparison",
    "Criteria",
    "DEFAULT_AXES",
    "Ensemble",
    "as_ensemble",
    "origin_of",
    "side_origin",
    "FLAG_MEANINGS",
    "FLAG_VALUES",
    "STATES",
    "summary_line",
    "GCI",
    "gci",
    "numerical_uncertainty",
    "compare",
    "compare_files",
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
