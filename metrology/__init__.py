"""Roundness and cylindricity metrology (``jointwear.metrology``): readers, ISO form, wear maps."""

from jointwear._lazy import lazy_api

# Public names come from the modules below; they are imported on first use (PEP 562) so that
# the command line starts fast.
__getattr__, __dir__ = lazy_api(__name__, ["jointwear.metrology._api"])
