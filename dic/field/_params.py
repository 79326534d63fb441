"""The options of a full-field measurement, :class:`FieldParams` (public as
``jointwear.dic.FieldParams``): one source for :func:`jointwear.dic.measure_field` and
``jointwear dic field``, whose defaults and help are read from it (light: no numpy)."""

from __future__ import annotations

import numbers
from dataclasses import dataclass
from typing import Literal

from jointwear.dic.subset import CorrelationParams
from jointwear.errors import ParameterError

__all__ = ["FieldParams"]


@dataclass(frozen=True)
class FieldParams:
    """Options of :func:`measure_field`.

    Parameters
    ----------
    subset_size : int
        Subset side [pixel], odd.
    step : int
        Grid spacing of the subset centres [pixel].
    strain_window : int
        Side of the strain fit window [grid points], odd >= 3 (0: no strain).
    frame : {"world", "plane"}
        Stereo output frame: the calibration's world frame, or the best-fit plane of the
        reference surface (origin at its centroid, z its normal towards the cameras, x the
        world x axis projected onto it).
    zncc_min : float
        Matches below this ZNCC are flagged.
    epipolar_max_px : float
        Largest RMS reprojection residual of a triangulated pair [pixel] before the point is
        flagged ``epipolar_mismatch``.
    consistency_max_px : float
        Stereo: distance [pixel] between a left subset centre and where its right match lands
        when matched back into the left reference image beyond which the point is flagged
        ``left_right_inconsistent`` (or 5 times the two matches' median combined noise if larger; on
        the virtual rig's static scenes the two agree within 0.002 pixel, subsets straddling a
        20 mm depth step miss by 0.05-0.36 pixel).
    interpolation, tolerance, max_iterations, search_radius, threads, u_outlier_factor,
    neighbour_outlier_factor
        As :class:`jointwear.dic.CorrelationParams`.
    """

    subset_size: int = CorrelationParams.subset_size
    step: int = CorrelationParams.step
    strain_window: int = 5
    frame: Literal["world", "plane"] = "world"
    zncc_min: float = CorrelationParams.zncc_min
    epipolar_max_px: float = 1.0
    consistency_max_px: float = 0.02
    interpolation: Literal["cubic", "quintic"] = CorrelationParams.interpolation
    tolerance: float = CorrelationParams.tolerance
    max_iterations: int = CorrelationParams.max_iterations
    search_radius: int = CorrelationParams.search_radius
    threads: int = CorrelationParams.threads
    u_outlier_factor: float = CorrelationParams.u_outlier_factor
    neighbour_outlier_factor: float = CorrelationParams.neighbour_outlier_factor

    def __post_init__(self) -> None:
        w = self.strain_window
        if not isinstance(w, numbers.Integral) or (w != 0 and (w < 3 or w % 2 == 0)):
            raise ParameterError(
                f"strain_window={w!r}: expected an odd number of grid points >= 3 (0: no strain)"
            )
        if self.frame not in ("world", "plane"):
            raise ParameterError(
                f"frame={self.frame!r}: expected 'world' (calibration) or 'plane' (best fit)"
            )
        if not self.consistency_max_px > 0:
            raise ParameterError(
                f"consistency_max_px={self.consistency_max_px!r}: expected > 0 pixel"
            )
        if not self.epipolar_max_px > 0:
            raise ParameterError(f"epipolar_max_px={self.epipolar_max_px!r}: expected > 0 pixel")

    def correlation(self):
        return CorrelationParams(
            subset_size=self.subset_size,
            step=self.step,
            interpolation=self.interpolation,
            tolerance=self.tolerance,
            max_iterations=self.max_iterations,
            zncc_min=self.zncc_min,
            search_radius=self.search_radius,
            threads=self.threads,
            u_outlier_factor=self.u_outlier_factor,
            neighbour_outlier_factor=self.neighbour_outlier_factor,
        )
