"""Choices and defaults of a comparison, one source for :mod:`jointwear.compare` and the
``compare``/``report`` commands, whose help states them (light: no numpy)."""

from __future__ import annotations

__all__ = ["ALIGN_METHOD", "ALIGN_METHODS", "DEFAULT_AXES", "MOTION_VARIABLES"]

#: time-series variables compared by default when both sides have them (contract names).
#: Positions (``follower_position``) are left out: they depend on where each record puts its
#: origin (a DIC calibration's world frame is the board's); ask for them explicitly.
MOTION_VARIABLES = (
    "follower_velocity",
    "journal_offset",
    "journal_displacement",
    "contact_force",
)

#: vector components compared by default: the mechanism is planar; the out-of-plane (z) motion of
#: a rig record is set by the rig, not by the mechanism, unless the user asks for it (axes=)
DEFAULT_AXES = ("x", "y")

#: how the two motion records are put on one time axis (``auto``: by crank angle when both
#: records have one, else by cross-correlation), and the default
ALIGN_METHODS = ("auto", "crank_angle", "cross_correlation")
ALIGN_METHOD = "auto"
