"""Archard wear of the bearing with cycle updates (``jointwear.sim.wear``).

Owns the wear loop (:func:`simulate_wear`, :class:`WearRun`: cycle updates, adaptive update
interval, checkpoints and resume) and what it is made of: the run settings and the checks on
kw, the contact models that give one cycle's wear work, the conformal (Winkler) wear pressure
of ``contact.wear_pressure = "conformal"``, the update-interval control, the wear-map Dataset
of a run and its verdicts, versioned checkpoints, the dotted parameter overrides of a run, and
the calibration of the wear coefficient kw against measured wear. The modules are private; the public names are importable from here
and from :mod:`jointwear.sim`, loaded on first use.
"""

import lazy_loader

# The public names: the __all__ of these modules (module -> None) or the names listed. They are
# imported on first use so that the command line starts fast; ``python docs/scripts/lazy_stubs.py``
# writes them into __init__.pyi, which lazy_loader reads.
_EXPORTS = {
    "_loop": None,
    "_contact": None,
    "_calibration": None,
    "_conformal": ["conformal_wear_work", "foundation_modulus"],
}

__getattr__, __dir__, __all__ = lazy_loader.attach_stub(__name__, __file__)
