"""Quality flags of the 2D DIC engine (CF ``flag_values`` / ``flag_meanings``), numba-free."""

from __future__ import annotations

import numpy as np

FLAG_OK = 0
FLAG_NOT_CONVERGED = 1
FLAG_LOW_CORRELATION = 2
FLAG_OUTSIDE = 3
FLAG_NO_TEXTURE = 4
FLAG_INVALID_PIXELS = 5
FLAG_NOT_REACHED = 6
FLAG_DIVERGED = 7

FLAG_MEANINGS = (
    "ok not_converged low_correlation subset_outside_image no_texture invalid_pixels "
    "not_reached diverged"
)
FLAG_VALUES = np.arange(8, dtype=np.int8)

#: a match whose own standard uncertainty is far above its image's (set after the matching,
#: by :func:`flag_uncertainty_outliers`; 11, after the full field's flags 8-10, so that a value
#: means one thing in every file)
FLAG_U_OUTLIER = 11
#: the flags of a 2D result file (the engine's and the uncertainty outliers)
OUTPUT_FLAG_VALUES = np.array([*range(8), FLAG_U_OUTLIER], dtype=np.int8)
OUTPUT_FLAG_MEANINGS = FLAG_MEANINGS + " uncertainty_outlier"
#: fewer ok points than this in an image: no robust median, no outlier test
MIN_POINTS_OUTLIER_TEST = 10
#: an outlier's uncertainty is also above this [pixel]: on (nearly) noise-free images every u
#: is tiny (1e-6-1e-3 px) and their ratios to the median say nothing about the match. 0.02
#: rather than 0.01: on GT4 with 1 grey level of noise (benchmarks/bench_dic_outliers.py) a
#: match with u of 0.01-0.02 px, 2-4 times that image's median, is within 0.05 px of the truth
#: but for a few in ten thousand, and flagging them took up to 3.5 % of the good points (2.3 %
#: at 0.02) without lowering the share of ok points off by more than 0.05 px (0.11 % at most
#: either way). No per-image threshold on u alone (a multiple of the median, median + k MAD,
#: the same on log u) met both <= 2 % good points flagged and <= 0.2 % off on all six
#: noise/shift cases: the off points lie on faint texture with residuals as small as the good
#: ones', and only their u (not their ZNCC or residual) sets them apart.
U_OUTLIER_FLOOR_PX = 0.02

#: positions of the affine parameters (u, du/dx, du/dy, v, dv/dx, dv/dy) in the 12-vector
AFFINE_INDEX = np.array([0, 1, 2, 6, 7, 8])


def flag_uncertainty_outliers(flag: np.ndarray, sigma: np.ndarray, factor: float) -> np.ndarray:
    """``flag`` with ``uncertainty_outlier`` where a match's own uncertainty is ``factor``
    times its image's median or more.

    Parameters
    ----------
    flag : ndarray (..., N) int
        Flags of the N points of every image (leading dims: images).
    sigma : ndarray (..., N, 2)
        Standard uncertainties of (u, v) [pixel] from the match residual.
    factor : float
        A point whose larger component exceeds ``factor`` times the median of that larger
        component over the image's ok points, and ``U_OUTLIER_FLOOR_PX``, is flagged (0: no
        test). Images with fewer than ``MIN_POINTS_OUTLIER_TEST`` ok points are not tested.

    Returns
    -------
    ndarray
        A new flag array (the input is not changed).
    """
    out = np.array(flag, dtype=np.int8, copy=True)
    if not factor:
        return out
    u = np.max(np.asarray(sigma, float), axis=-1).reshape(-1, out.shape[-1])
    rows = out.reshape(-1, out.shape[-1])
    for f, s in zip(rows, u, strict=True):
        ok = (f == FLAG_OK) & np.isfinite(s)
        if ok.sum() < MIN_POINTS_OUTLIER_TEST:
            continue
        f[ok & (s > max(factor * np.median(s[ok]), U_OUTLIER_FLOOR_PX))] = FLAG_U_OUTLIER
    return out
