"""Public names of stereo calibration, stereo DIC and footage tracking."""

__all__: list[str] = []
