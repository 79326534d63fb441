"""Inverse-compositional Gauss-Newton (IC-GN) subset matching: the kernels' public face.

Criterion: zero-normalised sum of squared differences (ZNSSD, insensitive to offset and gain of
the intensities), ``C = sum [ (f - fm)/fn - (g - gm)/gn ]**2 = 2 (1 - ZNCC)``, minimised by IC-GN
(Baker & Matthews 2004; Pan, Li & Tong 2013). The numerics live in one module per concern:

* :mod:`jointwear.dic.icgn._warp`: warp algebra (composition, 6x6 second-order matrices after
  Gao et al. 2015, small solves, extrapolation to a neighbour);
* :mod:`jointwear.dic.icgn._reference`: reference subsets (values, central-difference
  gradients, texture, invalid pixels, the Gauss-Newton uncertainty);
* :mod:`jointwear.dic.icgn._sample`: B-spline weights written once, sampling of the warped
  subset (one source for cubic and quintic);
* :mod:`jointwear.dic.icgn._solve`: one subset's Gauss-Newton systems and iterations;
* :mod:`jointwear.dic.icgn._drive`: many points in parallel, preloaded references,
  reliability-guided propagation.

Shape parameters (always a 12-vector, the affine case uses 6 of them)::

    p = [
        u,
        du / dx,
        du / dy,
        d2u / dx2,
        d2u / dxdy,
        d2u / dy2,
        v,
        dv / dx,
        dv / dy,
        d2v / dx2,
        d2v / dxdy,
        d2v / dy2,
    ]

so that a subset point at offset (dx, dy) from the centre maps to
``x + dx + u + ux dx + uy dy + uxx dx^2/2 + uxy dx dy + uyy dy^2/2`` (and likewise in y).

Kernel arguments are packed: ``ref = (image, gx, gy, coef, invalid)`` (reference),
``dfm = (coef, invalid)`` (deformed), ``opts = (half, quadratic, max_iter, tol, min_std,
max_shift, border, zncc_min, order)``, ``out = (zncc, iterations, flags, sigma)``.
"""

from __future__ import annotations

import numpy as np

from jointwear.dic.icgn._drive import (
    CONTRACTION_PROBES,
    affine_references,
    icgn_affine_loaded,
    icgn_many,
    icgn_serial,
    rg_propagate,
)
from jointwear.dic.icgn._reference import _box_has_invalid, _load_reference, subset_std
from jointwear.dic.icgn._sample import interp_point, sample_affine
from jointwear.dic.icgn._solve import make_work, solve_point
from jointwear.dic.icgn._warp import _compose_inverse, _extrapolate

__all__ = [
    "CONTRACTION_PROBES",
    "QUADRATIC_INDEX",
    "affine_references",
    "icgn_affine_loaded",
    "icgn_many",
    "icgn_serial",
    "rg_propagate",
    "subset_std",
    "solve_point",
    "make_work",
    "interp_point",
    "sample_affine",
    "_box_has_invalid",
    "_load_reference",
    "_compose_inverse",
    "_extrapolate",
]

QUADRATIC_INDEX = np.arange(12)
