"""Simulator of the spatial four-bar linkage with a 3D revolute clearance joint (``jointwear.sim``).

Dynamics, contact and friction: :mod:`jointwear.sim._api_dynamics`; Archard wear with cycle
updates: :mod:`jointwear.sim._api_wear`; sweeps and sensitivity on dask:
:mod:`jointwear.sim._api_sweep`.
"""

from jointwear._lazy import lazy_api

# Public names come from the modules below; they are imported on first use (PEP 562) so that
# the command line starts fast.
__getattr__, __dir__ = lazy_api(
    __name__, ["jointwear.sim._api_dynamics", "jointwear.sim._api_wear", "jointwear.sim._api_sweep"]
)
