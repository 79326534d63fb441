"""Validation reports (``jointwear.reports``): self-contained HTML with figures, and the demo."""

from jointwear.reports._api import *  # noqa: F403
from jointwear.reports._api import __all__  # noqa: F401
