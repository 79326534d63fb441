"""Defaults of the simulator that the command line shows, in a light module (no numpy, no
parameter classes): ``jointwear --help`` reads them without importing :mod:`jointwear.sim.parameters`,
which takes them from here (one literal each)."""

from __future__ import annotations

__all__ = ["DEFAULT_PARAMETER_SET", "BORE_LAYERS", "BORE_POINTS"]

#: Name of the default parameter set (Tables 1-2 of the reference study).
DEFAULT_PARAMETER_SET = "zhang2023"

#: Layers over the bearing width of the bore grid (``joint.n_layers``), unless a set says.
BORE_LAYERS = 20

#: Points per layer of the bore grid (``joint.n_points``), unless a set says.
BORE_POINTS = 200
