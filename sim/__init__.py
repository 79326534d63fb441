"""Simulator of the spatial four-bar linkage with a 3D revolute clearance joint (``jointwear.sim``).

Dynamics, contact and friction live in the modules listed by :mod:`jointwear.sim._api_dynamics`;
Archard wear with cycle updates in :mod:`jointwear.sim._api_wear`.
"""

from jointwear.sim import _api_dynamics, _api_wear
from jointwear.sim._api_dynamics import *  # noqa: F403
from jointwear.sim._api_wear import *  # noqa: F403

__all__ = [*_api_dynamics.__all__, *_api_wear.__all__]
