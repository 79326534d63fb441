"""The kernels split by physics (``sim/kernels/``) give the numbers of the one-file kernels.

``data/default_kernels.npz`` was computed with ``sim/_kernels.py`` before the split (commit
7a7587e) with the default options (edge projection, per-region latch, graded layers) on the
worn profile of ``test_legacy_kernels``: the wear work, sliding distance, final state and impact
velocities of a short run, slice and per-point formulations. On the machine that made it the
split reproduced every array bit for bit; the tolerance only allows for last-bit differences of
another machine's maths library.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from test_legacy_kernels import worn_profile  # noqa: I001

from jointwear.params import replace_nested
from jointwear.sim import PARAMETER_SETS, run_cycles

_GRID = {"joint.n_layers": 12, "joint.n_points": 120}
CASES = {
    "slice": ({**_GRID}, 0.3),
    "per_point": (
        {"joint.n_layers": 8, "joint.n_points": 80, "contact.formulation": "per_point"},
        0.2,
    ),
}
REFERENCE = Path(__file__).parent / "data" / "default_kernels.npz"


@pytest.mark.parametrize("name", list(CASES))
def test_split_kernels_reproduce_the_single_module(name):
    ref = np.load(REFERENCE)
    changes, cycles = CASES[name]
    p = replace_nested(PARAMETER_SETS["zhang2023"], **changes)
    r = run_cycles(p, cycles=cycles, wear_depth=worn_profile(p), record=False)
    assert np.max(r.wear_work) > 0  # the worn bore is in contact: every array is exercised
    works = [r.normal_work, r.axial_normal_work, r.normal_impulse]
    arrays = zip(
        ("wear_work", "sliding", "y", "vimp", "work"),
        (r.wear_work, r.sliding_distance, r.state.y, r.state.impact_velocity, np.array(works)),
        strict=True,
    )
    for key, value in arrays:
        want = ref[f"{name}_{key}"]
        tol = 1e-9 * (float(np.max(np.abs(want))) or 1.0)
        np.testing.assert_allclose(value, want, rtol=1e-9, atol=tol, err_msg=key)
