"""Public API of the 2D subset-DIC engine (``jointwear.dic``).

Signatures
----------
``correlate(reference, deformed, *, points=None, roi=None, subset_size=31, step=10,
shape="affine", interpolation="quintic", initial_guess=None, search_radius=48, seed_points=None,
zncc_min=0.8, tolerance=1e-3, max_iterations=40, border=4, threads=0) -> xr.Dataset``
    One image pair. ``points`` ``(N, 2)`` subset centres ``(x, y)`` [pixel] give a ``point``
    dimension with ``x``, ``y`` coordinates; otherwise a grid over ``roi`` with spacing ``step``
    gives ``(y, x)`` dimensions. ``initial_guess`` ``(N, 2)`` ``(u, v)`` [pixel], ``(N, 6)``
    affine or ``(N, 12)`` shape parameters skips the search (epipolar-guided matching,
    frame-to-frame tracking).

``SubsetCorrelator(reference, *, points=None, roi=None, params=None, **options)``
    Reference prepared once (B-spline coefficients, gradients, point layout, neighbour graph);
    ``.correlate(deformed, *, initial_guess=None, seed_points=None) -> Dataset`` and
    ``.match(...) -> MatchResult`` (raw ``params`` (N, 12), ``zncc``, ``iterations``, ``flag``).

``correlate_sequence(frames, *, reference="absolute"|"incremental", times=None, frame_rate=None,
points=None, roi=None, update_zncc=0.9, progress=False, **options) -> xr.Dataset``
    A sequence (3D array, list of images, folder of images or video file): accumulated
    displacements of the reference points over ``time``.

``plot_displacement(ds, *, time=-1, background=None, arrows=True, title=None) -> Figure`` and
``save_quicklook(ds, path, **kwargs)``
    Quick-look figure: colour maps of u and v with arrows, invalid points masked.

Output variables
----------------
``u``, ``v`` [pixel] (x right, y down; NaN where the flag is not ``ok``), ``du_dx``, ``du_dy``,
``dv_dx``, ``dv_dy`` [1] (and second derivatives with ``shape="quadratic"``), ``zncc`` [1],
``iterations``, ``converged`` and ``flag`` (CF ``flag_values``/``flag_meanings``: ok,
not_converged, low_correlation, subset_outside_image, no_texture, invalid_pixels, not_reached,
diverged). A failed point is flagged, never dropped.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import xarray as xr

from jointwear.dic.subset._correlator import CorrelationParams, MatchResult, SubsetCorrelator
from jointwear.dic.subset._quicklook import plot_displacement, save_quicklook
from jointwear.dic.subset._sequence import correlate_sequence, read_frames

__all__ = [
    "correlate",
    "SubsetCorrelator",
    "CorrelationParams",
    "MatchResult",
    "correlate_sequence",
    "read_frames",
    "plot_displacement",
    "save_quicklook",
]


def correlate(
    reference: np.ndarray,
    deformed: np.ndarray,
    *,
    points: np.ndarray | None = None,
    roi: Sequence[float] | None = None,
    subset_size: int = 31,
    step: int = 10,
    shape: str = "affine",
    interpolation: str = "quintic",
    initial_guess: np.ndarray | None = None,
    search_radius: int = 48,
    seed_points: np.ndarray | None = None,
    zncc_min: float = 0.8,
    tolerance: float = 1e-3,
    max_iterations: int = 40,
    border: int = 4,
    threads: int = 0,
    u_outlier_factor: float = CorrelationParams.u_outlier_factor,
    neighbour_outlier_factor: float = CorrelationParams.neighbour_outlier_factor,
) -> xr.Dataset:
    """Subset DIC between two images (ZNSSD criterion, IC-GN on B-spline interpolation).

    Parameters
    ----------
    reference, deformed : ndarray (H, W)
        Grey images of the same size and dtype; NaN pixels are invalid (their subsets are
        flagged).
    points : ndarray (N, 2), optional
        Subset centres ``(x, y)`` [pixel] in the reference (x = column, y = row).
    roi : (x_min, y_min, x_max, y_max), optional
        Region [pixel, inclusive] the grid subsets must lie in (default: the whole image).
    subset_size : int
        Subset side [pixel], odd.
    step : int
        Grid spacing [pixel].
    shape : {"affine", "quadratic"}
        Subset shape function (first or second order).
    interpolation : {"cubic", "quintic"}
        B-spline order of the interpolation (prefiltered coefficients).
    initial_guess : ndarray, optional
        ``(N, 2)`` displacements ``(u, v)`` [pixel], ``(N, 6)`` affine parameters
        ``(u, du/dx, du/dy, v, dv/dx, dv/dy)`` or ``(N, 12)`` shape parameters; one row is
        broadcast to all points. Without it, seeds are searched (``search_radius``) and the
        solution propagates (reliability-guided).
    search_radius : int
        Integer search half-width for seeds [pixel].
    seed_points : ndarray (K, 2), optional
        Where to start the propagation ``(x, y)`` [pixel].
    zncc_min : float
        Matches below this ZNCC are flagged ``low_correlation``.
    tolerance : float
        IC-GN convergence threshold on the parameter update [pixel].
    max_iterations : int
        IC-GN iteration limit.
    border : int
        Margin [pixel] subsets keep from the image edges, where the B-spline interpolant is
        less exact.
    threads : int
        numba threads (0: min(2, available)).
    u_outlier_factor, neighbour_outlier_factor : float
        The outlier tests: matches that disagree with their grid neighbours by
        ``neighbour_outlier_factor`` times the image's median uncertainty are flagged
        ``neighbour_outlier``, matches without neighbours whose uncertainty exceeds
        ``u_outlier_factor`` times it ``uncertainty_outlier`` (0: no test; see
        :class:`CorrelationParams`).

    Returns
    -------
    Dataset
        ``u``, ``v`` [pixel], gradients [1], ``zncc``, ``iterations``, ``converged``, ``flag``
        over ``(y, x)`` (grid) or ``point`` (with ``x``, ``y`` coordinates [pixel]).

    Raises
    ------
    BadInputError
        Images of different sizes or dtypes, not 2D, malformed points or guesses.
    ParameterError
        Even or too small subset size, unknown shape/interpolation, bad roi.

    Examples
    --------
    Speckle images moved by an exact sub-pixel shift:

    >>> from jointwear.datasets.speckle import RigidField, speckle_pair
    >>> pair = speckle_pair((128, 128), RigidField(translation=(1.3, -0.7)))  # exact shift [pixel]
    >>> from jointwear.dic import correlate
    >>> ds = correlate(pair.reference, pair.deformed, subset_size=31, step=16)
    >>> dict(ds.sizes)
    {'x': 6, 'y': 6}
    >>> print(f"u = {float(ds['u'].mean()):.3f}, v = {float(ds['v'].mean()):.3f} pixel")
    u = 1.300, v = -0.700 pixel
    """
    params = CorrelationParams(
        subset_size=subset_size,
        step=step,
        shape=shape,  # type: ignore[arg-type]
        interpolation=interpolation,  # type: ignore[arg-type]
        search_radius=search_radius,
        zncc_min=zncc_min,
        tolerance=tolerance,
        max_iterations=max_iterations,
        border=border,
        threads=threads,
        u_outlier_factor=u_outlier_factor,
        neighbour_outlier_factor=neighbour_outlier_factor,
    )
    corr = SubsetCorrelator(reference, points=points, roi=roi, params=params)
    return corr.correlate(deformed, initial_guess=initial_guess, seed_points=seed_points)
