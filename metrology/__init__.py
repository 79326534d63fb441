"""Roundness and cylindricity metrology (``jointwear.metrology``): readers, ISO form, wear maps."""

from jointwear.metrology._api import *  # noqa: F403
from jointwear.metrology._api import __all__  # noqa: F401
