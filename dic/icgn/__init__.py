"""IC-GN subset matching (numba kernels): B-spline image interpolation, reference
subsets, warp algebra, the Gauss-Newton solve and its driver, and the quality flags.

The modules are private: the public names are re-exported from :mod:`jointwear.dic`; the
names its sibling subpackages use are importable from here (``_EXPORTS``), loaded on first use.
"""

import lazy_loader

_EXPORTS = {
    "_interp": ("SplineImage", "prefilter", "prefilter_region"),
    "_reference": ("subset_kappa",),
    "_flags": ("FLAG_NOT_REACHED",),
    "_shapes": ("ShapeFunction", "shape_function"),
}

__getattr__, __dir__, __all__ = lazy_loader.attach_stub(__name__, __file__)
