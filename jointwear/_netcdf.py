"""A dataset as plain NumPy arrays, and its netCDF file written without xarray.

Importing xarray (and pandas under it) costs about 0.3 CPU s, a third of a short command's
start-up. A command whose result is a handful of arrays on one grid (``jointwear dic
correlate`` of an image pair) builds a :class:`Record` - variables with dims, values and
attrs, coordinates, global attributes - and writes it with :func:`write_record`, which gives
the same file as :func:`jointwear.io.save` of :meth:`Record.to_dataset` (the same global
attributes, history and provenance, the same encoding: a NaN ``_FillValue`` on floating-point
variables, the CF ``coordinates`` attribute for non-dimension coordinates, attributes encoded
by :func:`jointwear.io.encode_attrs`), atomically. The library keeps returning the Dataset:
:meth:`Record.to_dataset` builds it from the same record.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    import xarray as xr

__all__ = ["Variable", "Record", "write_record"]


@dataclass(frozen=True)
class Variable:
    """One variable: dimension names, values (an ndarray of that many dimensions) and attrs."""

    dims: tuple[str, ...]
    values: np.ndarray
    attrs: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if np.ndim(self.values) != len(self.dims):
            raise ValueError(f"values of shape {np.shape(self.values)} for dims {self.dims}")


@dataclass(frozen=True)
class Record:
    """Variables, coordinates and global attributes of a dataset, as NumPy arrays.

    Read like a Dataset where a reader only needs arrays: ``record["u"].values``,
    ``.dims``, ``.attrs``, ``"u" in record``, ``record.attrs``.
    """

    data_vars: dict[str, Variable]
    coords: dict[str, Variable]
    attrs: dict[str, Any] = field(default_factory=dict)

    def __getitem__(self, name: str) -> Variable:
        if name in self.data_vars:
            return self.data_vars[name]
        return self.coords[name]

    def __contains__(self, name: object) -> bool:
        return name in self.data_vars or name in self.coords

    @property
    def variables(self) -> dict[str, Variable]:
        """Dimension coordinates, data variables, other coordinates: the order in which
        xarray writes the Dataset of this record."""
        index = {k: v for k, v in self.coords.items() if v.dims == (k,)}
        other = {k: v for k, v in self.coords.items() if k not in index}
        return {**index, **self.data_vars, **other}

    @property
    def dims(self) -> dict[str, int]:
        """Dimension sizes in order of first use by :attr:`variables`."""
        sizes: dict[str, int] = {}
        for var in self.variables.values():
            for dim, n in zip(var.dims, np.shape(var.values), strict=True):
                if sizes.setdefault(dim, n) != n:
                    raise ValueError(f"dimension {dim!r} has sizes {sizes[dim]} and {n}")
        return sizes

    def to_dataset(self) -> xr.Dataset:
        """The xarray Dataset of this record (imports xarray)."""
        import xarray as xr

        data = {
            k: xr.DataArray(v.values, dims=v.dims, attrs=dict(v.attrs))
            for k, v in self.data_vars.items()
        }
        coords = {k: (v.dims, v.values, dict(v.attrs)) for k, v in self.coords.items()}
        return xr.Dataset(data, coords=coords, attrs=dict(self.attrs))


def _coordinates_attr(record: Record, name: str, var: Variable) -> str | None:
    """CF ``coordinates`` attribute of a variable: the non-dimension coordinates whose
    dimensions it spans (sorted, as xarray writes it)."""
    dims = set(var.dims)
    if name in record.coords:
        return None
    names = sorted(
        c
        for c, cv in record.coords.items()
        if c not in cv.dims and set(cv.dims) <= dims and c not in var.dims
    )
    return " ".join(names) or None


def _fill_value(values: np.ndarray) -> Any:
    """The ``_FillValue`` xarray gives a variable without an encoding: NaN for floats."""
    return values.dtype.type(np.nan) if values.dtype.kind in "fc" else None


def write_record(record: Record, path: str | Path, **provenance: Any) -> Path:
    """Write ``record`` to netCDF-4 atomically, as :func:`jointwear.io.save` writes its Dataset.

    ``provenance`` are the keywords of :func:`jointwear.io.save` (``inputs``, ``parameters``,
    ``command``, ``source``, ``title``; ``parents`` as provenance dicts), given to
    :func:`jointwear.io.file_attrs`. The record is not checked against the data contract (build
    it with code whose Dataset is).

    Returns
    -------
    Path
        The written file.
    """
    import netCDF4

    from jointwear.io import atomic_path, encode_attrs, file_attrs

    path = Path(path)
    attrs = file_attrs(record.attrs, **provenance)
    variables = record.variables
    dims = record.dims
    with atomic_path(path) as tmp:
        with netCDF4.Dataset(tmp, "w", format="NETCDF4") as nc:
            for dim, n in dims.items():
                nc.createDimension(dim, n)
            for name, var in variables.items():
                values = np.asarray(var.values)
                if values.dtype.kind not in "fiu":  # xarray encodes others its own way
                    raise TypeError(
                        f"write_record: variable {name!r} is {values.dtype}; only integer and "
                        "floating-point values are written this way (use jointwear.io.save)"
                    )
                if not values.dtype.isnative:
                    values = values.astype(values.dtype.newbyteorder("="))
                nc_var = nc.createVariable(
                    name,
                    values.dtype,
                    var.dims,
                    zlib=False,
                    contiguous=False,
                    fill_value=_fill_value(values),
                )
                var_attrs = encode_attrs(var.attrs)
                coordinates = _coordinates_attr(record, name, var)
                if coordinates is not None:
                    var_attrs["coordinates"] = coordinates
                nc_var.setncatts(var_attrs)
                nc_var.set_auto_maskandscale(False)
                nc_var[...] = values
            for key, value in attrs.items():
                nc.setncattr(key, value)
    return path
