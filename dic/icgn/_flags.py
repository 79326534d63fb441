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

#: positions of the affine parameters (u, du/dx, du/dy, v, dv/dx, dv/dy) in the 12-vector
AFFINE_INDEX = np.array([0, 1, 2, 6, 7, 8])
