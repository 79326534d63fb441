"""The wear map Dataset of a wear run: snapshots, their accuracy and the update history."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import xarray as xr

from jointwear.sim.wear._control import COVERAGE
from jointwear.sim.wearmap import BearingGrid, wear_map_dataset

__all__ = ["build_dataset"]

_U_NOTE = (
    f"expanded uncertainty (coverage factor k = {COVERAGE:g}) from the update control: "
    "explicit-Euler truncation dN (r_new - r_old) / 2 summed over the updates, and the "
    "statistical error of each averaged wear rate added in quadrature; NaN = not assessed "
    "(fixed or schedule scheme, one cycle per measurement). It covers the time integration "
    "and the cycle-to-cycle variability of the dynamics, not the model or its parameters"
)


def _u_attrs(units: str, of: str) -> dict[str, Any]:
    return {"units": units, "long_name": f"expanded uncertainty of {of}", "comment": _U_NOTE}


def build_dataset(
    snaps: Sequence[tuple],
    hist: np.ndarray,
    grid: BearingGrid,
    *,
    kw: float,
    attrs: dict[str, Any],
    cylindricity: bool = True,
) -> xr.Dataset:
    """Contract wear map from the snapshots ``(cycles, h, normal_work, depth_u, volume_u)``.

    ``hist`` holds one row per update: start, dN, rate change, accepted, cycles averaged,
    noise of the rate change.
    """
    n = len(snaps)
    shape = (0, *grid.shape)
    cyc = np.array([sn[0] for sn in snaps], dtype=float)
    maps = np.stack([sn[1] for sn in snaps]) if n else np.zeros(shape)
    work = np.array([sn[2] for sn in snaps], dtype=float)
    u_maps = np.stack([sn[3] for sn in snaps]) if n else np.zeros(shape)
    u_vol = np.array([sn[4] for sn in snaps], dtype=float)
    # u of the maximum depth: the u of the point holding it
    flat = maps.reshape(n, -1)
    imax = np.argmax(flat, axis=1) if n else np.zeros(0, dtype=int)
    u_max = u_maps.reshape(n, -1)[np.arange(n), imax] if n else np.zeros(0)
    extra = {
        "normal_work": xr.DataArray(
            work,
            dims="cycles",
            attrs={
                "units": "N m",
                "long_name": "accumulated normal work integral F_n |v_t| dt (Archard's F_n s)",
            },
        ),
        "archard_volume": xr.DataArray(
            kw * work,
            dims="cycles",
            attrs={"units": "m3", "long_name": "kw times accumulated normal work"},
        ),
        "max_wear_depth_u": xr.DataArray(
            u_max, dims="cycles", attrs=_u_attrs("m", "the largest wear depth")
        ),
        "worn_volume_u": xr.DataArray(
            u_vol, dims="cycles", attrs=_u_attrs("m3", "the worn volume")
        ),
        "update_start": xr.DataArray(
            hist[:, 0],
            dims="update",
            attrs={"units": "1", "long_name": "cycles done before the update"},
        ),
        "update_dn": xr.DataArray(
            hist[:, 1], dims="update", attrs={"units": "1", "long_name": "cycles per update (dN)"}
        ),
        "update_rate_change": xr.DataArray(
            hist[:, 2],
            dims="update",
            attrs={
                "units": "1",
                "long_name": "relative change of the wear-rate field over the update",
                "comment": "area-weighted L2 norm of the change of the averaged rate; the "
                "adaptive control removes update_rate_change_noise from it in quadrature",
            },
        ),
        "update_accepted": xr.DataArray(
            hist[:, 3].astype(np.int8),
            dims="update",
            attrs={
                "units": "1",
                "long_name": "update accepted (1) or rejected and redone (0)",
                "flag_values": np.array([0, 1], dtype=np.int8),
                "flag_meanings": "rejected accepted",
            },
        ),
        "update_cycles_averaged": xr.DataArray(
            hist[:, 4].astype(np.int32),
            dims="update",
            attrs={"units": "1", "long_name": "single cycles averaged in the rate measurement"},
        ),
        "update_rate_change_noise": xr.DataArray(
            hist[:, 5],
            dims="update",
            attrs={
                "units": "1",
                "long_name": "standard deviation of the rate change due to cycle-to-cycle "
                "variability (0 = not measured)",
            },
        ),
    }
    acc = hist[:, 3] == 1
    attrs = {
        **attrs,
        "n_updates": int(np.sum(acc)),
        "n_rejected": int(np.sum(~acc)),
        "accuracy_note": _U_NOTE,
    }
    ds = wear_map_dataset(maps, cyc, grid, cylindricity=cylindricity, extra=extra, attrs=attrs)
    ds["wear_depth_u"] = (
        ("cycles", "z", "theta"),
        u_maps[:, ::-1, :],  # layer order -> z ascending, as wear_depth
        _u_attrs("m", "the wear depth"),
    )
    return ds
