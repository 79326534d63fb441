"""Alignment of simulation and measurement in xarray, and validation metrics (``jointwear.compare``)."""

import lazy_loader

# The public names: the __all__ of these modules (module -> None) or the names listed. They are
# imported on first use so that the command line starts fast; ``python docs/scripts/lazy_stubs.py``
# writes them into __init__.pyi, which lazy_loader reads.
# ``_cli_options``: the option types the compare and report commands share (typer, no numpy)
_EXPORTS = {"_api": None, "_wear": ("band_label",), "_cli_options": None}

__getattr__, __dir__, __all__ = lazy_loader.attach_stub(__name__, __file__)
