"""Alignment of simulation and measurement in xarray, and validation metrics (``jointwear.compare``)."""

from jointwear._lazy import lazy_api

# Public names come from the modules below; they are imported on first use (PEP 562) so that
# the command line starts fast.
__getattr__, __dir__ = lazy_api(__name__, ["jointwear.compare._api"])
