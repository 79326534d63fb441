"""Camera models and stereo calibration: pinhole + Brown-Conrady cameras, calibration
from board views and its quality gate, importers (OpenCV, VIC-3D), stereo geometry
(triangulation with covariance, epipolar distance, noise floor).

The modules are private: the public names are re-exported from :mod:`jointwear.dic`; the
names its sibling subpackages use are importable from here (``_EXPORTS``), loaded on first use.
"""

import lazy_loader

_EXPORTS = {
    "_camera": ("Camera", "StereoCalibration"),
    "_importers": ("read_calibration", "metres_per_unit"),
    "_stereo": (
        "epipolar_distance",
        "stereo_noise_floor",
        "triangulate",
        "undistorted_pixels",
        "project_undistorted",
    ),
}

__getattr__, __dir__, __all__ = lazy_loader.attach_stub(__name__, __file__)
