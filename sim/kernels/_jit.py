"""How the evaluation kernels are compiled: cached, and without numba's runtime.

Every function an integration step calls (the right-hand sides, the clearance joint, the contact
search and forces, the impact latch) is compiled without the numba runtime (NRT). Such a
function may not allocate an array (numba refuses to compile one that does) and returns none,
so it needs no reference counts. With the runtime, numba counted a reference up and down with
an atomic operation for every array handed down the call chain (the evaluation context alone
holds 20). Without it a step takes half the time (``benchmarks/results/sim_cycle.json``: 0.110
-> 0.054 s CPU per crank cycle, results equal to the bit); a ``perf`` profile had put the two
counting functions at about three quarters of the compiled code's samples.

The scratch arrays the kernels work in are allocated once per integration, by
:func:`._context.make_context`; :func:`._integrator.integrate` and ``make_context`` keep the
runtime.

``_nrt`` is an option of numba's ``jit`` that numba does not document (its maintainers point to
it for this, numba issues 2345 and 2350); if a numba release drops it, these decorators fail at
import, loudly, rather than slowing down in silence.
"""

from __future__ import annotations

from numba import njit

__all__ = ["inline_kernel", "kernel"]

#: Decorator of an evaluation kernel: ``numba.njit`` cached and without the runtime.
kernel = njit(cache=True, _nrt=False)

#: The same, for a small kernel that numba inlines into its callers.
inline_kernel = njit(cache=True, inline="always", _nrt=False)
