"""Parameter sweeps, ensembles and sensitivity analysis on dask (``jointwear.sim.sweep``).

Owns the sweep driver (:func:`run_sweep`, :func:`to_grid`: design, execution, assembly,
Sobol indices), the TOML spec and its design, the swept parameters, one run and its outputs,
the executors (in-process, local or remote dask cluster), the part files that make a sweep
resumable, the analytic models that test the machinery cheaply, and the verification study of a
wear run (:func:`verify_wear`, ``jointwear sim verify``) built on them. The modules are private;
the public names are importable from here and from :mod:`jointwear.sim`, loaded on first use.
"""

import lazy_loader

# The public names: the __all__ of these modules (module -> None) or the names listed. They are
# imported on first use so that the command line starts fast; ``python docs/scripts/lazy_stubs.py``
# writes them into __init__.pyi, which lazy_loader reads.
_EXPORTS = {
    "_driver": ("*", "Execution", "assemble", "run_and_save"),
    "_verify": None,
    # the machinery of a sweep the calibration and the demo reuse
    "_run": ("evaluate_run", "RunTask"),
    "_params": ("apply_values", "parse_parameter", "parameter_units"),
    "_spec": ("Design", "read_spec", "spec_digest"),
}

__getattr__, __dir__, __all__ = lazy_loader.attach_stub(__name__, __file__)
