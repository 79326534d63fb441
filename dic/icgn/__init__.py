"""IC-GN subset matching (numba kernels): B-spline image interpolation, reference
subsets, warp algebra, the Gauss-Newton solve and its driver, and the quality flags.

Implementation only: public names are re-exported from :mod:`jointwear.dic`.
"""
