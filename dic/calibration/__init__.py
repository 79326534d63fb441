"""Camera models and stereo calibration: pinhole + Brown-Conrady cameras, calibration
from board views and its quality gate, importers (OpenCV, VIC-3D), stereo geometry
(triangulation with covariance, epipolar distance, noise floor).

Implementation only: public names are re-exported from :mod:`jointwear.dic`.
"""
