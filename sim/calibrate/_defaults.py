"""Defaults of the calibration and prediction, one source for the library and ``jointwear sim
calibrate/predict`` (light: the CLI reads them without importing the spec reader)."""

#: Default number of posterior samples ``sim predict`` simulates (the ensemble's size).
PREDICT_SAMPLES = 16
