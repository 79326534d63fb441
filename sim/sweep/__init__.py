"""Parameter sweeps, ensembles and sensitivity analysis on dask (``jointwear.sim.sweep``).

Owns the sweep driver (:func:`run_sweep`, :func:`to_grid`: design, execution, assembly,
Sobol indices), the TOML spec and its design, the swept parameters, one run and its outputs,
the executors (in-process, local or remote dask cluster), the part files that make a sweep
resumable, the analytic models that test the machinery cheaply, and the verification study of a
wear run (:func:`verify_wear`, ``jointwear sim verify``) built on them. The modules are private;
the public names are importable from here and from :mod:`jointwear.sim`, loaded on first use.
"""

from jointwear._lazy import lazy_api

__getattr__, __dir__ = lazy_api(
    __name__, ["jointwear.sim.sweep._driver", "jointwear.sim.sweep._verify"]
)
