"""Public names of the sweep part of jointwear.sim (ensembles, sensitivity, dask execution)."""

from jointwear.sim._sweep_models import analytic_sobol
from jointwear.sim._sweep_spec import SweepSpec, make_design, read_spec
from jointwear.sim.sweep import STATUS, run_sweep, to_grid
from jointwear.sim.verification import VerifySpec, read_verify_spec, verify_wear

__all__ = [
    "run_sweep",
    "read_spec",
    "SweepSpec",
    "make_design",
    "to_grid",
    "analytic_sobol",
    "STATUS",
    "verify_wear",
    "VerifySpec",
    "read_verify_spec",
]
