"""Roundness and cylindricity metrology (``jointwear.metrology``): readers, ISO form, wear maps."""

__all__: list[str] = []
