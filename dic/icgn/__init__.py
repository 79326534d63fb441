"""IC-GN subset matching (numba kernels): B-spline image interpolation, reference
subsets, warp algebra, the Gauss-Newton solve and its driver, and the quality flags.

The modules are private: the public names are re-exported from :mod:`jointwear.dic`; the
names its sibling subpackages use are importable from here (``_EXPORTS``), loaded on first use.
"""

import lazy_loader

_EXPORTS = {
    "_interp": ("SplineImage", "prefilter", "prefilter_region"),
    "_reference": ("subset_kappa",),
    # the quality flags (dic.subset, dic.field use them as ``icgn.FLAG_OK``, ...)
    "_flags": (
        "AFFINE_INDEX",
        "FLAG_DIVERGED",
        "FLAG_INVALID_PIXELS",
        "FLAG_LOW_CORRELATION",
        "FLAG_MEANINGS",
        "FLAG_NEIGHBOUR_OUTLIER",
        "FLAG_NOT_CONVERGED",
        "FLAG_NOT_REACHED",
        "FLAG_NO_TEXTURE",
        "FLAG_OK",
        "FLAG_OUTSIDE",
        "FLAG_U_OUTLIER",
        "OUTPUT_FLAG_MEANINGS",
        "OUTPUT_FLAG_VALUES",
        "U_OUTLIER_FLOOR_PX",
        "flag_uncertainty_outliers",
        "neighbour_reach",
    ),
    # the matching kernels the subset correlator drives, in its order: texture, reference
    # subsets, the solve (preloaded affine, many points, one by one), propagation over the grid
    "_match": (
        "subset_std",
        "affine_references",
        "icgn_affine_loaded",
        "icgn_many",
        "icgn_serial",
        "rg_propagate",
        "CONTRACTION_PROBES",
    ),
    "_shapes": ("ShapeFunction", "shape_function"),
}

__getattr__, __dir__, __all__ = lazy_loader.attach_stub(__name__, __file__)
