"""A netCDF file's header read with netCDF4 alone: what ``jointwear info`` shows and checks.

``jointwear info`` needs the names, dimensions, attributes and the (small) coordinate values of
a file, not its data: reading them through netCDF4 instead of xarray spares xarray's and
pandas' import (about 0.3 CPU s, more than the rest of the command). :class:`Header` offers the
few parts of an :class:`xarray.Dataset` that :func:`jointwear.conventions.validate` and the
summary read (``attrs``, ``sizes``, ``dims``, ``coords``, ``data_vars``), with xarray's split
between coordinates (a variable named as its dimension, or listed in a ``coordinates``
attribute) and data variables.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["Header", "HeaderVariable", "read_header"]

#: attributes xarray consumes when it decodes a variable (not shown as its attrs)
_ENCODING = frozenset(
    ("_FillValue", "missing_value", "coordinates", "scale_factor", "add_offset", "_Unsigned")
)


@dataclass(frozen=True)
class HeaderVariable:
    """One variable of a :class:`Header`: dimensions, attributes, dtype; values of coordinates."""

    dims: tuple[str, ...]
    attrs: dict[str, Any]
    dtype: np.dtype
    values: np.ndarray | None = None  # read for coordinates only

    @property
    def ndim(self) -> int:
        return len(self.dims)


@dataclass(frozen=True)
class Header:
    """A file's header in the shape of an :class:`xarray.Dataset`'s (read-only)."""

    attrs: dict[str, Any]
    sizes: dict[str, int]
    coords: dict[str, HeaderVariable] = field(default_factory=dict)
    data_vars: dict[str, HeaderVariable] = field(default_factory=dict)

    @property
    def dims(self) -> dict[str, int]:
        return self.sizes


def read_header(path: str | Path) -> Header:
    """The header of the netCDF file ``path`` (raises OSError/ValueError as netCDF4 does)."""
    import netCDF4

    with netCDF4.Dataset(str(path), "r") as nc:
        nc.set_auto_mask(False)
        listed: set[str] = set(str(nc.__dict__.get("coordinates", "")).split())
        for var in nc.variables.values():
            listed.update(str(var.__dict__.get("coordinates", "")).split())
        coords, data = {}, {}
        for name, var in nc.variables.items():
            attrs = {k: v for k, v in var.__dict__.items() if k not in _ENCODING}
            is_coord = name in listed or (var.dimensions == (name,))
            values = np.asarray(var[...]) if is_coord else None
            fill = var.__dict__.get("_FillValue")
            if values is not None and values.dtype.kind == "f" and fill is not None:
                values = np.where(values == fill, np.nan, values)  # as xarray decodes it
            dtype = values.dtype if values is not None else np.dtype(var.dtype)
            entry = HeaderVariable(tuple(var.dimensions), attrs, dtype, values)
            (coords if is_coord else data)[name] = entry
        # dimensions in the order xarray lists them: as the data variables use them first
        order = [d for var in [*data.values(), *coords.values()] for d in var.dims]
        order += list(nc.dimensions)
        sizes = {name: len(nc.dimensions[name]) for name in dict.fromkeys(order)}
        return Header(dict(nc.__dict__), sizes, coords, data)
