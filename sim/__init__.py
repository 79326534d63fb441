"""Simulator of the spatial four-bar linkage with a 3D revolute clearance joint (``jointwear.sim``).

Dynamics, contact and friction: :mod:`jointwear.sim._api_dynamics`; Archard wear with cycle
updates: :mod:`jointwear.sim._api_wear`; sweeps and sensitivity on dask:
:mod:`jointwear.sim._api_sweep`.
"""

import lazy_loader

# The public names: the __all__ of these modules (module -> None) or the names listed. They are
# imported on first use so that the command line starts fast; ``python docs/scripts/lazy_stubs.py``
# writes them into __init__.pyi, which lazy_loader reads.
_EXPORTS = {"_api_dynamics": None, "_api_wear": None, "_api_sweep": None}

__getattr__, __dir__, __all__ = lazy_loader.attach_stub(__name__, __file__)
