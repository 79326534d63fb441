"""Per-point results of the 2D subset-DIC engine as an xarray Dataset (the data contract)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import xarray as xr

import jointwear.dic.icgn._flags as _flags

if TYPE_CHECKING:
    from jointwear.dic.subset._params import CorrelationParams

__all__ = ["result_dataset"]


_GRAD_NAMES = [
    ("u", 0, "pixel", "displacement along x (image columns, right)"),
    ("du_dx", 1, "1", "displacement gradient du/dx"),
    ("du_dy", 2, "1", "displacement gradient du/dy"),
    ("v", 6, "pixel", "displacement along y (image rows, down)"),
    ("dv_dx", 7, "1", "displacement gradient dv/dx"),
    ("dv_dy", 8, "1", "displacement gradient dv/dy"),
]
_SECOND = [  # d2u_dx2 .. d2v_dy2: shape parameters 3-5 (u) and 9-11 (v)
    (f"d2{c}_{d}", first + k, "pixel-1", f"second derivative d2{c}/{d}")
    for c, first in (("u", 3), ("v", 9))
    for k, d in enumerate(("dx2", "dxdy", "dy2"))
]


def result_dataset(
    centres, P, zncc, iterations, flag, params: CorrelationParams, grid=None, sigma=None
):
    """Per-point arrays -> Dataset following the data contract (leading dims allowed).

    ``sigma`` (..., N, 2): standard uncertainty of (u, v) [pixel] -> ``u_u``, ``v_u``.
    """
    P = np.asarray(P, float)
    ok = np.asarray(flag) == _flags.FLAG_OK
    lead = P.shape[:-2]
    lead_dims = ("time",) if len(lead) == 1 else ()
    if grid is not None:
        xs, ys = grid
        dims = (*lead_dims, "y", "x")
        shape = (*lead, ys.size, xs.size)
        coords = {
            "x": ("x", xs, {"units": "pixel", "long_name": "subset centre column (reference)"}),
            "y": ("y", ys, {"units": "pixel", "long_name": "subset centre row (reference)"}),
        }
    else:
        dims = (*lead_dims, "point")
        shape = (*lead, centres.shape[0])
        coords = {
            "point": ("point", np.arange(centres.shape[0]), {"long_name": "point of interest"}),
            "x": ("point", centres[:, 0], {"units": "pixel", "long_name": "subset centre column"}),
            "y": ("point", centres[:, 1], {"units": "pixel", "long_name": "subset centre row"}),
        }
    data = {}
    names = _GRAD_NAMES + (_SECOND if params.quadratic else [])
    for name, k, units, long in names:
        vals = np.where(ok, P[..., k], np.nan).reshape(shape)
        data[name] = xr.DataArray(vals, dims=dims, attrs={"units": units, "long_name": long})
    data["zncc"] = xr.DataArray(
        np.asarray(zncc, float).reshape(shape),
        dims=dims,
        attrs={"units": "1", "long_name": "zero-normalised cross-correlation coefficient (final)"},
    )
    data["iterations"] = xr.DataArray(
        np.asarray(iterations, np.int32).reshape(shape),
        dims=dims,
        attrs={"units": "1", "long_name": "IC-GN iterations"},
    )
    data["converged"] = xr.DataArray(
        ok.astype(np.int8).reshape(shape),
        dims=dims,
        attrs={
            "units": "1",
            "long_name": "IC-GN converged to an accepted match",
            "flag_values": np.array([0, 1], np.int8),
            "flag_meanings": "no yes",
        },
    )
    data["flag"] = xr.DataArray(
        np.asarray(flag, np.int8).reshape(shape),
        dims=dims,
        attrs={
            "units": "1",
            "long_name": "correlation quality flag",
            "flag_values": _flags.FLAG_VALUES,
            "flag_meanings": _flags.FLAG_MEANINGS,
        },
    )
    if sigma is not None:
        sig = np.asarray(sigma, float)
        for k, name in enumerate(("u", "v")):
            data[f"{name}_u"] = xr.DataArray(
                np.where(ok, sig[..., k], np.nan).reshape(shape),
                dims=dims,
                attrs={
                    "units": "pixel",
                    "long_name": f"standard uncertainty of {name} from the match residual "
                    "(image noise; excludes interpolation bias)",
                },
            )
    ds = xr.Dataset(data, coords=coords)
    for name in ("u", "v"):
        extra = f" {name}_u" if sigma is not None else ""
        ds[name].attrs["ancillary_variables"] = f"zncc flag{extra}"
    ds.attrs.update(
        {
            "title": "2D subset DIC displacement field",
            "dic_criterion": "ZNSSD (IC-GN)",
            "dic_subset_size_pixel": int(params.subset_size),
            "dic_step_pixel": int(params.step),
            "dic_shape_function": params.shape,
            "dic_interpolation": f"{params.interpolation} B-spline (prefiltered)",
            "dic_tolerance_pixel": float(params.tolerance),
            "dic_zncc_min": float(params.zncc_min),
            "displacement_convention": (
                "Lagrangian: the subset centred at (x, y) of the reference moved by (u, v); x to "
                "the right, y down, pixel centres at integers"
            ),
        }
    )
    return ds
