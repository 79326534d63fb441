"""Options and input checks of the 2D subset-DIC engine: :class:`CorrelationParams`, image
checks, numba thread count, and the summed-area table of invalid pixels."""

from __future__ import annotations

import numbers
from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal

from jointwear.errors import BadInputError, ParameterError

if TYPE_CHECKING:  # numpy is imported by the checks that use it: the CLI's option
    import numpy as np  # declarations read this module without it

    from jointwear.dic.icgn import ShapeFunction

__all__ = [
    "CorrelationParams",
    "MIN_STEP",
    "MIN_SUBSET",
    "UPDATE_ZNCC",
    "set_threads",
    "check_image",
    "check_pair",
    "IMAGE_ORIGINS",
    "check_image_origin",
]

#: smallest subset side [pixel] (odd) and grid step [pixel] the correlation accepts
MIN_SUBSET = 7
MIN_STEP = 1

#: default median ZNCC below which an incremental sequence moves its reference forward
UPDATE_ZNCC = 0.9

#: what DIC images can be (the results' ``data_origin``): camera images or generated ones
IMAGE_ORIGINS = ("measured", "synthetic")


@dataclass(frozen=True)
class CorrelationParams:
    """Options of the subset correlation.

    Parameters
    ----------
    subset_size : int
        Side of the square subset [pixel], odd, >= 7.
    step : int
        Grid spacing of the points of interest [pixel] (grids only).
    shape : str
        Subset shape function, a name of the table
        :data:`~jointwear.dic.icgn._shapes.SHAPE_FUNCTIONS`: ``"affine"`` (first order) or
        ``"quadratic"`` (second order).
    interpolation : str
        ``"cubic"`` or ``"quintic"`` B-spline on prefiltered coefficients.
    max_iterations : int
        IC-GN iteration limit per point.
    tolerance : float
        Convergence: a point stops when its last parameter update (gradients scaled by the
        subset half-width) moves the subset edge by less than this [pixel] (Pan et al. 2013
        use 0.001). Gauss-Newton converges fast near the optimum, so the remaining error is far
        below this value; the propagation therefore measures the contraction per iteration
        ``rho`` on its first points and lets later points also stop on their first or second
        update when ``rho`` times it, the predicted remaining error, is below this value
        (:func:`jointwear.dic.icgn._drive.rg_propagate`; points refined from given guesses
        use the first criterion only).
    zncc_min : float
        Points below this ZNCC are flagged ``low_correlation`` and do not propagate.
    search_radius : int
        Half-width of the integer-pixel search window for seeds [pixel].
    min_texture : float
        Subsets whose intensity standard deviation is below this fraction of the image's are
        flagged ``no_texture``.
    border : int
        Margin [pixel] subsets must keep from the image edges (reference and deformed): the
        B-spline interpolant is less accurate within a few pixels of an edge (errors up to
        ~0.003 px at 2-3 px from it). Subsets closer are flagged ``subset_outside_image``.
    threads : int
        numba threads (at most 2 on the shared machine; 0 = min(2, available)).
    u_outlier_factor : float
        A match whose standard uncertainty (the larger of u's and v's) exceeds this multiple of
        the image's median over its ok points is on faint texture: it is no reference for its
        neighbours' test, its own gradients do not excuse a disagreement with them, and
        without 3 other usable grid neighbours (or off a grid) it is flagged
        ``uncertainty_outlier`` when its u also exceeds 0.02 pixel (on noise-free images all
        u are tiny). 0: no such test.
    neighbour_outlier_factor : float
        A match on a grid whose displacement lies further from its usable neighbours' median
        than this multiple of the image's median u (and 0.02 pixel), also after carrying the
        neighbours' values to it along the image's median gradient and along the measured
        gradients, is flagged ``neighbour_outlier`` (0: no test; see
        :func:`jointwear.dic.icgn._flags.flag_uncertainty_outliers`). On the GT4 texture moved by
        a known shift with 1-2 grey levels of noise (benchmarks/bench_dic_outliers.py), 4 (with
        ``u_outlier_factor`` 2) leaves at most 0.2 % of the ok points off by more than 0.05
        pixel and flags at most 2 % of the points within 0.05 pixel.
    """

    subset_size: int = 31
    step: int = 10
    shape: Literal["affine", "quadratic"] = "affine"
    interpolation: Literal["cubic", "quintic"] = "quintic"
    max_iterations: int = 40
    tolerance: float = 1e-3
    zncc_min: float = 0.8
    search_radius: int = 48
    min_texture: float = 0.05
    border: int = 4
    threads: int = 0
    u_outlier_factor: float = 2.0
    neighbour_outlier_factor: float = 4.0

    def __post_init__(self) -> None:
        s = self.subset_size
        is_int = isinstance(s, numbers.Integral) and not isinstance(s, bool)
        if not is_int or s < MIN_SUBSET or s % 2 == 0:
            raise ParameterError(
                f"subset_size={s!r}: expected an odd integer >= {MIN_SUBSET} (the subset is "
                f"centred on its point); use {s + 1 if is_int and s >= MIN_SUBSET - 1 else 31}"
            )
        if not isinstance(self.step, numbers.Integral) or self.step < MIN_STEP:
            raise ParameterError(f"step={self.step!r}: expected an integer >= {MIN_STEP} pixel")
        self.shape_function  # noqa: B018 - a name not in the table is refused, naming them
        if self.interpolation not in ("cubic", "quintic"):
            raise ParameterError(
                f"interpolation={self.interpolation!r}: expected 'cubic' or 'quintic' (B-spline)"
            )
        if not (0.0 < self.tolerance < 1.0):
            raise ParameterError(f"tolerance={self.tolerance!r}: expected 0 < tolerance < 1 pixel")
        if not (-1.0 <= self.zncc_min < 1.0):
            raise ParameterError(f"zncc_min={self.zncc_min!r}: expected a value in [-1, 1)")
        if self.max_iterations < 1:
            raise ParameterError(f"max_iterations={self.max_iterations!r}: expected >= 1")
        if not isinstance(self.border, numbers.Integral) or self.border < 0:
            raise ParameterError(f"border={self.border!r}: expected an integer >= 0 pixel")
        if not (self.u_outlier_factor == 0 or self.u_outlier_factor > 1):
            raise ParameterError(
                f"u_outlier_factor={self.u_outlier_factor!r}: expected a multiple of the median "
                "uncertainty > 1 (2 marks the far tail), or 0 for no test"
            )
        if not (self.neighbour_outlier_factor == 0 or self.neighbour_outlier_factor >= 1):
            raise ParameterError(
                f"neighbour_outlier_factor={self.neighbour_outlier_factor!r}: expected a "
                "multiple of the median uncertainty >= 1 (4 flags points far from their "
                "neighbours), or 0 for no test"
            )
        if self.search_radius < 0:
            raise ParameterError(f"search_radius={self.search_radius!r}: expected >= 0 pixel")

    @property
    def half(self) -> int:
        return self.subset_size // 2

    @property
    def shape_function(self) -> ShapeFunction:
        """The shape's record in :data:`~jointwear.dic.icgn._shapes.SHAPE_FUNCTIONS`."""
        from jointwear.dic.icgn import shape_function

        return shape_function(self.shape)


def set_threads(threads: int = 0) -> int:
    """Set numba's thread count to ``threads`` (0: min(2, available)); returns it."""
    import numba

    avail = numba.config.NUMBA_NUM_THREADS
    n = min(avail, 2) if not threads else max(1, min(int(threads), avail))
    numba.set_num_threads(n)
    return n


def check_image(image, name: str) -> np.ndarray:
    """A 2D numeric image as an array, or a BadInputError naming ``name``."""
    import numpy as np

    arr = np.asarray(image)
    if arr.ndim == 3 and arr.shape[2] in (3, 4):
        raise BadInputError(
            f"{name}: expected a single-channel (grey) image, got shape {arr.shape} (colour); "
            "convert it to grey first, e.g. cv2.cvtColor(img, cv2.COLOR_BGR2GRAY)"
        )
    if arr.ndim != 2:
        raise BadInputError(f"{name}: expected a 2D image (rows, columns), got shape {arr.shape}")
    if arr.dtype.kind not in "uif" or arr.dtype == np.bool_:
        raise BadInputError(f"{name}: expected numeric pixels, got dtype {arr.dtype}")
    if min(arr.shape) < 8:
        raise BadInputError(f"{name}: image {arr.shape} is too small (need at least 8x8 pixels)")
    if arr.dtype.kind == "f" and np.isinf(arr).any():
        raise BadInputError(
            f"{name}: contains infinite pixel values; replace them by NaN (flagged) or finite values"
        )
    return arr


def check_pair(reference: np.ndarray, deformed: np.ndarray, what: str = "deformed image") -> None:
    """Sizes and dtypes must agree."""
    if reference.shape != deformed.shape:
        raise BadInputError(
            f"{what}: size {deformed.shape[1]}x{deformed.shape[0]} (width x height) differs from "
            f"the reference {reference.shape[1]}x{reference.shape[0]}; crop or resize so that both "
            "images have the same size"
        )
    if reference.dtype != deformed.dtype:
        raise BadInputError(
            f"{what}: pixel type {deformed.dtype} differs from the reference's {reference.dtype}; "
            "images of one sequence must come from the same camera setting - convert both to the "
            "same type (e.g. .astype(np.float64)) if that is intended"
        )


def check_image_origin(data_origin: str) -> str:
    """``data_origin`` if it is one of :data:`IMAGE_ORIGINS`, else a ParameterError naming
    ``data_origin`` (``--origin``) and the two choices."""
    if data_origin not in IMAGE_ORIGINS:
        raise ParameterError(
            f"data_origin={data_origin!r} (--origin): say what the images are, 'measured' "
            "(camera images) or 'synthetic' (generated)"
        )
    return data_origin


def _integral_invalid(valid: np.ndarray) -> np.ndarray:
    """Summed-area table of invalid pixels; a (1, 1) array when every pixel is valid."""
    import numpy as np

    if valid.all():
        return np.zeros((1, 1), dtype=np.int64)
    inv = (~valid).astype(np.int64)
    out = np.zeros((inv.shape[0] + 1, inv.shape[1] + 1), dtype=np.int64)
    out[1:, 1:] = inv.cumsum(0).cumsum(1)
    return out
