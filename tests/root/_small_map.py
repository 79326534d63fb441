"""A small wear map of the data contract, for the CLI tests of ``tests/root``."""

from __future__ import annotations

import numpy as np
import xarray as xr

import jointwear.conventions as C


def small_wear_map() -> xr.Dataset:
    """5 layers over z = -5…+5 mm, every 10 degree: wear depth 1 µm · |sin theta| [m]."""
    theta = C.theta_coord(np.arange(0.0, 360.0, 10.0))
    z = C.z_coord(np.linspace(-5e-3, 5e-3, 5))
    depth = 1e-6 * np.abs(np.sin(np.radians(theta.values)))[None, :] * np.ones((5, 1))
    return xr.Dataset(
        {"wear_depth": (("z", "theta"), depth, C.variable_attrs("wear_depth"))},
        coords={"z": z, "theta": theta},
    )
