"""Sanity gate of a stereo calibration: a result that cannot be right is an error, not a file.

A stereo calibration can converge to numbers that look like a calibration but are not one: an
RMS of tens of pixels, a baseline of dozens of board lengths, focal lengths differing by 25x
between two identical cameras. :func:`check_calibration` lists what is implausible;
:func:`calibrate_stereo <jointwear.dic.calibrate_stereo>` raises :class:`PoorCalibration`
(exit code 1, the calibration attached for inspection) unless told to accept it.
"""

from __future__ import annotations

import numpy as np

from jointwear.dic.calibration._camera import StereoCalibration
from jointwear.dic.calibration._defaults import MAX_RMS_PX
from jointwear.errors import EXIT_VALIDATION_FAILED, CalibrationError

__all__ = ["PoorCalibration", "check_calibration", "view_table"]

#: Plausible horizontal field of view of a measurement camera [degree].
FOV_RANGE_DEG = (0.5, 130.0)
#: Largest relative difference between fx and fy (square pixels) [1].
MAX_ASPECT_DEVIATION = 0.05
#: Plausible ratio of the baseline to the distance of the board from the cameras [1].
BASELINE_TO_DISTANCE = (0.01, 2.5)


class PoorCalibration(CalibrationError):
    """A stereo calibration failed its sanity checks (exit code 1).

    Attributes
    ----------
    calibration : StereoCalibration
        The rejected result, to be written for inspection.
    problems : tuple of str
        Each failed check.
    """

    exit_code = EXIT_VALIDATION_FAILED

    def __init__(self, message: str, calibration: StereoCalibration, problems: tuple[str, ...]):
        super().__init__(message)
        self.calibration = calibration
        self.problems = problems


def check_calibration(
    cal: StereoCalibration,
    *,
    max_rms: float = MAX_RMS_PX,
    board_distance: float | None = None,
) -> list[str]:
    """What is implausible about a stereo calibration (empty list: nothing found).

    Parameters
    ----------
    cal : StereoCalibration
    max_rms : float
        Largest acceptable stereo reprojection RMS [pixel].
    board_distance : float, optional
        Median distance of the calibration board from the left camera, in the calibration's
        length unit; enables the baseline check.
    """
    problems = []
    if cal.rms is not None and not cal.rms <= max_rms:
        problems.append(
            f"stereo reprojection RMS {cal.rms:.3g} px exceeds {max_rms:g} px (--max-rms)"
        )
    for name, cam in cal.cameras.items():
        fx, fy = cam.focal
        w, h = cam.image_size
        fov = float(np.degrees(2 * np.arctan(w / (2 * fx))))
        if not FOV_RANGE_DEG[0] <= fov <= FOV_RANGE_DEG[1]:
            problems.append(
                f"{name} camera: focal length {fx:.1f} px gives a {fov:.1f} degree field of view "
                f"over {w} px (plausible {FOV_RANGE_DEG[0]:g}-{FOV_RANGE_DEG[1]:g})"
            )
        if abs(fx / fy - 1) > MAX_ASPECT_DEVIATION:
            problems.append(
                f"{name} camera: fx {fx:.1f} px and fy {fy:.1f} px differ by "
                f"{abs(fx / fy - 1):.0%} (pixels are square to a few per cent)"
            )
        cx, cy = cam.matrix[0, 2], cam.matrix[1, 2]
        if not (0.1 * w <= cx <= 0.9 * w and 0.1 * h <= cy <= 0.9 * h):
            problems.append(
                f"{name} camera: principal point ({cx:.0f}, {cy:.0f}) px is far from the centre "
                f"of the {w}x{h} px image"
            )
    fl, fr = cal.left.focal[0], cal.right.focal[0]
    if max(fl, fr) / min(fl, fr) > 3:
        problems.append(
            f"focal lengths {fl:.1f} and {fr:.1f} px differ by more than 3x; the two cameras "
            "of a stereo rig see the same field"
        )
    if board_distance is not None and board_distance > 0:
        ratio = cal.baseline / board_distance
        if not BASELINE_TO_DISTANCE[0] <= ratio <= BASELINE_TO_DISTANCE[1]:
            problems.append(
                f"baseline {cal.baseline:.4g} is {ratio:.3g} times the board distance "
                f"{board_distance:.4g} (plausible {BASELINE_TO_DISTANCE[0]:g}-"
                f"{BASELINE_TO_DISTANCE[1]:g})"
            )
    # the right camera seen from the left one: to its right (x > 0) for --left/--right as named
    R, T = cal.relative_pose
    c_right = -R.T @ T  # right camera centre in the left camera frame
    if c_right[0] < 0 and abs(c_right[0]) > abs(c_right[1]):
        problems.append(
            f"the right camera sits to the LEFT of the left camera (x = {c_right[0]:.4g} in the "
            "left camera frame): the --left and --right images look swapped (swap them; if the "
            "camera given as --left really sits on the right, or is mounted upside down, accept "
            "with --accept-poor)"
        )
    return problems


def view_table(cal: StereoCalibration) -> list[str]:
    """Lines of a per-view residual table (accepted views with their RMS, then rejections)."""
    lines = []
    names = cal.view_names or tuple(f"view {i}" for i in range(cal.views_used))
    pv = cal.per_view_rms if cal.per_view_rms is not None else np.full((len(names), 2), np.nan)
    width = max([len(n) for n in names] + [4])
    lines.append(f"  {'view':<{width}}  RMS left  RMS right [px]")
    for name, (a, b) in zip(names, pv, strict=False):
        lines.append(f"  {name:<{width}}  {a:8.3f}  {b:9.3f}")
    for reason in cal.rejected:
        lines.append(f"  rejected {reason}")
    return lines
