"""The evaluation kernels run without numba's runtime (``sim/kernels/_jit.py``).

Counting array references took about three quarters of an integration step; the kernels an
integration step calls are compiled without the runtime, so they can neither allocate nor count.
A kernel decorated with plain ``numba.njit`` would silently bring the cost back: this test names
it.
"""

from __future__ import annotations

import importlib
import pkgutil

from numba.core.registry import CPUDispatcher

import jointwear.sim.kernels as kernels

#: Kernels that keep the runtime: they allocate (the integration's arrays and its context) or,
#: like the closed-form kinematics, also serve the Python API with arrays.
WITH_RUNTIME = {"integrate", "make_context", "closed_form"}


def _dispatchers():
    for info in pkgutil.iter_modules(kernels.__path__):
        module = importlib.import_module(f"{kernels.__name__}.{info.name}")
        for name, obj in vars(module).items():
            if isinstance(obj, CPUDispatcher) and obj.py_func.__module__ == module.__name__:
                yield name, obj


def test_every_evaluation_kernel_is_compiled_without_the_runtime():
    found = dict(_dispatchers())
    assert {"_eval", "_slices", "clearance_joint", "integrate"} <= set(found)
    with_runtime = {n for n, d in found.items() if d.targetoptions.get("_nrt", True)}
    assert with_runtime == WITH_RUNTIME
