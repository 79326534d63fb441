"""The virtual rig's configuration, :class:`RigConfig` (public as
``jointwear.datasets.rig.RigConfig``), and the codecs it writes: one source for the library and
``jointwear datasets rig``, whose defaults are read from here (light: no numpy)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal, get_args

from jointwear.errors import BadInputError
from jointwear.params import check_fields, positive

__all__ = ["BOARD_KINDS", "CODECS", "DEFAULT_CODEC", "RigConfig"]

#: Video codecs the bundled OpenCV/FFmpeg can write here: name -> (fourcc, extension, lossless).
#: Decoding one 1280 x 1024 grey frame here: grey (raw) 4 ms, mp4v 5 ms, mjpg 7 ms, png 21 ms,
#: ffv1 38 ms; mjpg and mp4v as written by OpenCV are lossy (errors of 30+ grey levels on speckle).
CODECS: dict[str, tuple[str, str, bool]] = {
    "ffv1": ("FFV1", ".avi", True),
    "mjpg": ("MJPG", ".avi", False),
    "mp4v": ("mp4v", ".mp4", False),
    "png": ("png ", ".avi", True),
    "grey": ("GREY", ".avi", True),
}


#: Codec of the videos unless told.
DEFAULT_CODEC = "ffv1"

#: Calibration boards the rig renders.
BoardKind = Literal["chessboard", "charuco"]
BOARD_KINDS = get_args(BoardKind)


@dataclass(frozen=True)
class RigConfig:
    """Parameters of the virtual rig (SI units; pixel quantities say so).

    The defaults describe a rig like the study's: two 1280 x 1024 cameras 1.0 m from the
    mechanism plane, 0.30 m apart (toe-in towards ``look_at``), a 0.42 m x 0.34 m field of view
    (0.33 mm per pixel) covering the follower and joint C, 50 frames/s.

    Parameters
    ----------
    width, height : int
        Image size [pixel], at least 64.
    fov_width : float
        Width of the field of view in the mechanism plane [m].
    distance : float
        Distance of the cameras from the mechanism plane [m].
    baseline : float
        Distance between the two cameras [m].
    look_at : tuple of float
        Point both cameras aim at [m], mechanism frame.
    distortion : tuple of float
        Lens distortion (k1, k2, p1, p2, k3), OpenCV's model.
    principal_offset_px : tuple of float
        Principal point's offset from the image centre [pixel].
    fps : float
        Frame rate [1/s].
    duration : float
        Recorded time [s].
    crank_speed_rpm : float
        Crank speed [rev/min].
    crank_angle0_deg : float
        Crank angle of the first frame [degree].
    z_amplitude : float
        Out-of-plane amplitude of joint C [m].
    z_phase_deg : float
        Phase of that out-of-plane motion against the crank [degree].
    journal_size : float
        Side of the journal's speckled plate [m].
    journal_z, crank_z : float
        Out-of-plane offsets of the journal's and the crank's plates [m].
    follower_width : float
        Width of the follower's speckled strip [m].
    speckle_size : float or None
        Speckle size on the parts [m]; None: 4 pixel footprints.
    noise_sigma : float
        Sensor noise [grey levels].
    blur_sigma_px : float
        Optical blur sigma [pixel].
    exposure : float
        Brightness gain.
    exposure_time : float
        Exposure time [s] over which ``motion_blur_samples`` sub-frames are averaged.
    motion_blur_samples : int
        Sub-frames per frame (1: no motion blur).
    background : float
        Background grey level [0..255].
    seed : int
        Random seed of the speckle and the noise.
    drop_frames : tuple of int
        Frame indices to drop: frames the camera lost.
    duplicate_frames : tuple of int
        Frame indices to duplicate: frames the camera wrote twice.
    board_squares : tuple of int
        Calibration board squares along x and y.
    board_square_size : float
        Side of a board square [m].
    board_views : int
        Calibration views rendered.
    board_kind : str
        Calibration board: chessboard or charuco.
    board_marker_size : float
        Side of a ChArUco marker [m].
    board_dictionary : str
        ArUco dictionary of the ChArUco markers.
    board_legacy : bool
        ChArUco in the layout of OpenCV < 4.6 (boards printed from it).
    """

    width: int = 1280
    height: int = 1024
    fov_width: float = 0.42
    distance: float = 1.0
    baseline: float = 0.30
    look_at: tuple[float, float, float] = (0.29, 0.16, 0.0)
    distortion: tuple[float, float, float, float, float] = (-0.08, 0.10, 2e-4, -1e-4, 0.0)
    principal_offset_px: tuple[float, float] = (6.0, -4.0)
    fps: float = positive(50.0)
    duration: float = positive(1.0)
    crank_speed_rpm: float = 120.0
    crank_angle0_deg: float = 30.0
    z_amplitude: float = 2.5e-3
    z_phase_deg: float = 0.0
    journal_size: float = 0.04
    journal_z: float = 0.02
    crank_z: float = 0.03
    follower_width: float = 0.03
    speckle_size: float | None = None
    noise_sigma: float = 1.0
    blur_sigma_px: float = 0.6
    exposure: float = 1.0
    exposure_time: float = 2e-4
    motion_blur_samples: int = 1
    background: float = 40.0
    seed: int = 0
    drop_frames: tuple[int, ...] = ()
    duplicate_frames: tuple[int, ...] = ()
    board_squares: tuple[int, int] = (10, 8)
    board_square_size: float = 0.025
    board_views: int = 12
    board_kind: BoardKind = "chessboard"
    board_marker_size: float = 0.01875
    board_dictionary: str = "DICT_5X5_100"
    board_legacy: bool = False

    def __post_init__(self) -> None:
        if self.width < 64 or self.height < 64:
            raise BadInputError(f"rig image size {self.width}x{self.height} is too small")
        check_fields(self, "rig")
        if self.motion_blur_samples < 1:
            raise BadInputError("motion_blur_samples must be >= 1")

    @property
    def focal_px(self) -> float:
        """Focal length [pixel] giving ``fov_width`` at ``distance``."""
        return self.width * self.distance / self.fov_width

    @property
    def n_frames(self) -> int:
        return int(round(self.duration * self.fps))

    @property
    def omega(self) -> float:
        """Crank angular speed [rad/s]."""
        return self.crank_speed_rpm * 2 * math.pi / 60.0
