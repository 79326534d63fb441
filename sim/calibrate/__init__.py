"""Bayesian calibration of the simulator's uncertain inputs, and prediction with the posterior
(``jointwear.sim.calibrate``).

Owns the calibration spec (priors in the ``sim sweep`` grammar and a ``[calibrate]`` table), the
calibration data (measured wear maps reduced within their band, stated values), the
Gaussian-process emulator with its cross-validated error, posterior sampling (emcee) with its
diagnostics, identifiability and the posterior predictive check (:func:`calibrate`,
``jointwear sim calibrate``), and the ensemble of real simulations at posterior samples
(:func:`predict`, ``jointwear sim predict``). docs/calibration.md describes the method. The
modules are private; the public names are importable from here, loaded on first use.
"""

import lazy_loader

# The public names: the __all__ of these modules. They are imported on first use so that the
# command line starts fast; ``python docs/scripts/lazy_stubs.py`` writes them into __init__.pyi,
# which lazy_loader reads.
_EXPORTS = {"_run": None, "_spec": None, "_predict": None}

__getattr__, __dir__, __all__ = lazy_loader.attach_stub(__name__, __file__)
