"""Alignment of simulation and measurement in xarray, and validation metrics (``jointwear.compare``)."""

from jointwear.compare._api import *  # noqa: F403
from jointwear.compare._api import __all__  # noqa: F401
