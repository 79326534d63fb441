"""Public names of the sweep part of jointwear.sim (ensembles, sensitivity, dask execution)."""

from jointwear.sim.sweep._driver import STATUS, run_sweep, to_grid
from jointwear.sim.sweep._models import analytic_sobol
from jointwear.sim.sweep._spec import SweepSpec, make_design, read_spec
from jointwear.sim.sweep._verify import VerifySpec, read_verify_spec, verify_wear

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
