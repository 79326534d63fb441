"""The evaluation kernels run without numba's runtime (``sim/kernels/_jit.py``).

Counting array references took half of an integration step's time; the kernels an
integration step calls are compiled without the runtime, so they can neither allocate nor count.
A kernel decorated with plain ``numba.njit`` would silently bring the cost back: this test names
it.
"""

from __future__ import annotations

import importlib
import math
import pkgutil

import numpy as np
from numba.core.registry import CPUDispatcher

import jointwear.sim.kernels as kernels
from jointwear.params import replace_nested
from jointwear.sim import PARAMETER_SETS
from jointwear.sim.dynamics import _layers, _pack, point_area
from jointwear.sim.kernels._contact import _contact
from jointwear.sim.kernels._context import make_context
from jointwear.sim.kernels._layout import C_GEO, C_LAYER, C_NODE, C_VEC, C_WSC

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


def _aligned_journal_past_the_edge(junk):
    """One contact evaluation of a journal parallel to the bore, pressed 1 µm into every layer
    it spans and shifted 1.5 mm along -z, so that its end lies between the two +z layers; the
    context's scratch arrays are filled with ``junk`` first."""
    p = replace_nested(
        PARAMETER_SETS["zhang2023"],
        **{"joint.n_layers": 10, "joint.n_points": 100, "joint.axial_grading": 0.0},
    )
    j = p.joint
    P, IP = _pack(p)
    zl, wl = _layers(p)
    h = np.zeros((j.n_layers, j.n_points))
    ww = np.zeros((2, j.n_layers, j.n_points))
    acc = np.zeros(4)
    ctx = make_context(P, IP, h, h.min(axis=1), zl, wl, point_area(p), np.zeros(12), ww, acc)
    for slot in (C_VEC, C_LAYER, C_GEO, C_WSC):
        ctx[slot][...] = junk
    ctx[C_NODE][...] = 7
    shift = 1.5e-3
    assert 0.5 * j.journal_length - shift < zl[0] and 0.5 * j.journal_length - shift > zl[1]
    J0 = np.array([-(j.radial_clearance + 1e-6), 0.0, -shift])
    u = np.array([0.0, 0.0, 1.0])
    V0 = np.array([0.0, 0.05, -1e-3])
    wrench = np.zeros(12)
    out = _contact(J0, u, V0, np.zeros(3), ctx, wrench, True, 1e-4)
    assert math.isfinite(out[0]) and out[4] > 0  # elastic energy; contacting slices
    return out, wrench, ww, acc


def test_a_contact_never_reads_what_the_scratch_arrays_held():
    """The scratch arrays are reused from one evaluation to the next: nothing may read a slot
    this evaluation did not write (here the stiffness of a layer beyond the journal's end)."""
    first = _aligned_journal_past_the_edge(0.0)
    second = _aligned_journal_past_the_edge(1e30)
    for a, b in zip(first, second, strict=True):
        np.testing.assert_array_equal(np.asarray(a, dtype=float), np.asarray(b, dtype=float))
