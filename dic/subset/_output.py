"""Per-point results of the 2D subset-DIC engine following the data contract: as a
:class:`~jointwear._netcdf.Record` of NumPy arrays (:func:`result_record`, what ``jointwear dic
correlate`` writes without importing xarray) and as the xarray Dataset built from it
(:func:`result_dataset`, what the library returns)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from jointwear._netcdf import Record, Variable
from jointwear.dic import icgn as _flags

if TYPE_CHECKING:
    import xarray as xr

    from jointwear.dic.subset._params import CorrelationParams

__all__ = ["result_dataset", "result_record"]


def result_dataset(*args, **kwargs) -> xr.Dataset:
    """Per-point arrays -> Dataset following the data contract (leading dims allowed): the
    :func:`result_record` of the same arguments, as a Dataset.

    ``sigma`` (..., N, 2): standard uncertainty of (u, v) [pixel] -> ``u_u``, ``v_u``;
    ``neighbour_images``: the images the neighbour outlier test applies to (default: all).
    """
    return result_record(*args, **kwargs).to_dataset()


def result_record(
    centres,
    P,
    zncc,
    iterations,
    flag,
    params: CorrelationParams,
    grid=None,
    sigma=None,
    neighbour_images=None,
) -> Record:
    """Per-point arrays -> :class:`~jointwear._netcdf.Record` of :func:`result_dataset`;
    matches that disagree with their grid neighbours by ``params.neighbour_outlier_factor`` times
    their image's median u are flagged ``neighbour_outlier``, matches off a grid whose u is
    ``params.u_outlier_factor`` times it ``uncertainty_outlier``
    (:func:`~jointwear.dic.icgn._flags.flag_uncertainty_outliers`)."""
    P = np.asarray(P, float)
    if sigma is not None:
        index = None
        if grid is not None:  # the points in row-major order over (y, x)
            index = np.indices((grid[1].size, grid[0].size)).reshape(2, -1).T
        flag = _flags.flag_uncertainty_outliers(
            flag, sigma, params.u_outlier_factor, P=P, centres=np.asarray(centres, float),
            index=index, neighbour_factor=params.neighbour_outlier_factor,
            reach=_flags.neighbour_reach(params.subset_size, params.step),
            neighbour_images=neighbour_images,
        )  # fmt: skip
    ok = np.asarray(flag) == _flags.FLAG_OK
    lead = P.shape[:-2]
    lead_dims = ("time",) if len(lead) == 1 else ()
    if grid is not None:
        xs, ys = grid
        dims = (*lead_dims, "y", "x")
        shape = (*lead, ys.size, xs.size)
        coords = {
            "x": Variable(
                ("x",), xs, {"units": "pixel", "long_name": "subset centre column (reference)"}
            ),
            "y": Variable(
                ("y",), ys, {"units": "pixel", "long_name": "subset centre row (reference)"}
            ),
        }
    else:
        dims = (*lead_dims, "point")
        shape = (*lead, centres.shape[0])
        point = ("point",)
        coords = {
            "point": Variable(
                point, np.arange(centres.shape[0]), {"long_name": "point of interest"}
            ),
            "x": Variable(
                point, centres[:, 0], {"units": "pixel", "long_name": "subset centre column"}
            ),
            "y": Variable(
                point, centres[:, 1], {"units": "pixel", "long_name": "subset centre row"}
            ),
        }
    data = {}
    for name, k, units, long in params.shape_function.outputs:
        vals = np.where(ok, P[..., k], np.nan).reshape(shape)
        data[name] = Variable(dims, vals, {"units": units, "long_name": long})
    data["zncc"] = Variable(
        dims,
        np.asarray(zncc, float).reshape(shape),
        {"units": "1", "long_name": "zero-normalised cross-correlation coefficient (final)"},
    )
    data["iterations"] = Variable(
        dims,
        np.asarray(iterations, np.int32).reshape(shape),
        {"units": "1", "long_name": "IC-GN iterations"},
    )
    data["converged"] = Variable(
        dims,
        ok.astype(np.int8).reshape(shape),
        {
            "units": "1",
            "long_name": "IC-GN converged to an accepted match",
            "flag_values": np.array([0, 1], np.int8),
            "flag_meanings": "no yes",
        },
    )
    data["flag"] = Variable(
        dims,
        np.asarray(flag, np.int8).reshape(shape),
        {
            "units": "1",
            "long_name": "correlation quality flag",
            "flag_values": _flags.OUTPUT_FLAG_VALUES,
            "flag_meanings": _flags.OUTPUT_FLAG_MEANINGS,
        },
    )
    if sigma is not None:
        sig = np.asarray(sigma, float)
        for k, name in enumerate(("u", "v")):
            data[f"{name}_u"] = Variable(
                dims,
                np.where(ok, sig[..., k], np.nan).reshape(shape),
                {
                    "units": "pixel",
                    "long_name": f"standard uncertainty of {name} from the match residual "
                    "(image noise; excludes interpolation bias)",
                },
            )
    for name in ("u", "v"):
        extra = f" {name}_u" if sigma is not None else ""
        data[name].attrs["ancillary_variables"] = f"zncc flag{extra}"
    attrs = {
        "title": "2D subset DIC displacement field",
        "dic_criterion": "ZNSSD (IC-GN)",
        "dic_subset_size_pixel": int(params.subset_size),
        "dic_step_pixel": int(params.step),
        "dic_shape_function": params.shape,
        "dic_interpolation": f"{params.interpolation} B-spline (prefiltered)",
        "dic_tolerance_pixel": float(params.tolerance),
        "dic_max_iterations": int(params.max_iterations),
        "dic_u_outlier_factor": float(params.u_outlier_factor),
        "dic_neighbour_outlier_factor": float(params.neighbour_outlier_factor),
        "dic_outlier_floor_pixel": float(_flags.U_OUTLIER_FLOOR_PX),
        "dic_zncc_min": float(params.zncc_min),
        "displacement_convention": (
            "Lagrangian: the subset centred at (x, y) of the reference moved by (u, v); x to "
            "the right, y down, pixel centres at integers"
        ),
    }
    return Record(data, coords, attrs)
