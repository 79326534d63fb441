"""Archard wear of the bearing with cycle updates (``jointwear.sim.wear``).

Owns the wear loop (:func:`simulate_wear`, :class:`WearRun`: cycle updates, adaptive update
interval, checkpoints and resume) and what it is made of: the run settings and the checks on
kw, the contact models that give one cycle's wear work, the update-interval control, the
wear-map Dataset of a run, versioned checkpoints, and the calibration of the wear coefficient
kw against measured wear. The modules are private; the public names are importable from here
and from :mod:`jointwear.sim`, loaded on first use.
"""

from jointwear._lazy import lazy_api

__getattr__, __dir__ = lazy_api(
    __name__,
    ["jointwear.sim.wear._loop", "jointwear.sim.wear._contact", "jointwear.sim.wear._calibration"],
)
