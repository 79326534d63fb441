"""Digital image correlation (``jointwear.dic``): 2D subset DIC, stereo DIC, footage tracking."""

from jointwear.dic import _api2d, _api3d
from jointwear.dic._api2d import *  # noqa: F403
from jointwear.dic._api3d import *  # noqa: F403

__all__ = [*_api2d.__all__, *_api3d.__all__]
