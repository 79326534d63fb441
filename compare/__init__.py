"""Alignment of simulation and measurement in xarray, and validation metrics (``jointwear.compare``)."""

__all__: list[str] = []
