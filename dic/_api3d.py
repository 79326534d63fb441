"""Public names of stereo calibration, stereo DIC and footage tracking (``jointwear.dic``).

Calibration: :class:`Camera`, :class:`StereoCalibration`, :class:`CalibrationBoard`,
:func:`calibrate_stereo`, :func:`board_world_frame`, importers :func:`read_opencv_calibration`
and :func:`read_vic3d_calibration`, :func:`read_calibration` (jointwear files).
Stereo geometry: :func:`triangulate` (with covariance), :func:`epipolar_distance`,
:func:`stereo_noise_floor`. Rigid bodies and time series: :func:`fit_rigid`,
:func:`fit_rigid_robust`, :func:`time_derivative`. Footage: :func:`open_frames`,
:func:`read_bodies`, :class:`BodySpec`, :class:`TrackConfig`, :func:`track_footage`,
:func:`plot_body_motion`.
"""

from jointwear.dic.calibration._board import CalibrationBoard, board_world_frame, calibrate_stereo
from jointwear.dic.calibration._camera import (
    Camera,
    StereoCalibration,
    cardan_to_matrix,
)
from jointwear.dic.calibration._importers import (
    read_calibration,
    read_opencv_calibration,
    read_vic3d_calibration,
)
from jointwear.dic.calibration._stereo import epipolar_distance, stereo_noise_floor, triangulate
from jointwear.dic.footage._plot import plot_body_motion
from jointwear.dic.footage._rigid import fit_rigid, fit_rigid_robust, time_derivative
from jointwear.dic.footage._track import BodySpec, TrackConfig, read_bodies, track_footage
from jointwear.dic.footage._video import FrameSource, open_frames

__all__ = [
    "Camera",
    "StereoCalibration",
    "CalibrationBoard",
    "calibrate_stereo",
    "board_world_frame",
    "cardan_to_matrix",
    "read_calibration",
    "read_opencv_calibration",
    "read_vic3d_calibration",
    "triangulate",
    "epipolar_distance",
    "stereo_noise_floor",
    "fit_rigid",
    "fit_rigid_robust",
    "time_derivative",
    "FrameSource",
    "open_frames",
    "BodySpec",
    "TrackConfig",
    "read_bodies",
    "track_footage",
    "plot_body_motion",
]
