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

from jointwear._lazy import lazy_api

__getattr__, __dir__ = lazy_api(
    __name__,
    [
        "jointwear.sim.calibrate._run",
        "jointwear.sim.calibrate._spec",
        "jointwear.sim.calibrate._predict",
    ],
)
