"""jointwear."""

from jointwear._lazy import after_import
from jointwear._version import __version__
from jointwear._xarray_imports import install as _quiet_xarray

__all__ = ["__version__"]

# xarray would import dask, distributed and pint for every dataset it builds or writes
after_import("xarray", _quiet_xarray)
