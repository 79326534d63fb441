"""The options that reproduce the simulator before issue 16 still give its numbers.

``contact.wear_projection = "lumped"`` with ``contact.impact_latch = "layer"`` and equally
spaced layers (``joint.axial_grading = 0``; and the per-point formulation) must reproduce the kernels as they were before the edge projection,
the per-region impact latch and the deduplication of ``sim/_kernels.py``. The reference
``data/legacy_kernels.npz`` was computed with the pre-issue-16 kernels (commit 00de2ba) on a
worn profile; short runs, so that the impact dynamics cannot amplify last-bit differences of
another machine's maths library beyond the tolerance.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from jointwear.params import replace_nested
from jointwear.sim import PARAMETER_SETS, run_cycles

LEGACY = {
    "contact.wear_projection": "lumped",
    "contact.impact_latch": "layer",
    "joint.axial_grading": 0.0,
}
_BASE = replace_nested(PARAMETER_SETS["zhang2023"], **LEGACY)
CASES = {
    "slice": (replace_nested(_BASE, **{"joint.n_layers": 12, "joint.n_points": 120}), 0.3),
    "per_point": (
        replace_nested(
            _BASE,
            **{"joint.n_layers": 8, "joint.n_points": 80, "contact.formulation": "per_point"},
        ),
        0.2,
    ),
}
REFERENCE = Path(__file__).parent / "data" / "legacy_kernels.npz"


def worn_profile(params):
    """A smooth worn bore: a band around theta = 240 degrees, deeper at the edges [m]."""
    j = params.joint
    th = np.arange(j.n_points) * 2 * math.pi / j.n_points
    z = np.linspace(1, -1, j.n_layers)
    return 8e-6 * np.maximum(np.cos(th - 4.2), 0)[None, :] ** 2 * (1 + 0.8 * z[:, None] ** 2)


@pytest.mark.parametrize("name", list(CASES))
def test_legacy_options_reproduce_the_kernels_before_issue_16(name):
    ref = np.load(REFERENCE)
    p, cycles = CASES[name]
    r = run_cycles(p, cycles=cycles, wear_depth=worn_profile(p), record=False)
    got = {
        "wear_work": r.wear_work,
        "sliding": r.sliding_distance,
        "y": r.state.y,
        "vimp": r.state.impact_velocity,
        "work": np.array([r.normal_work, r.axial_normal_work, r.normal_impulse]),
    }
    for key, value in got.items():
        want = ref[f"{name}_{key}"]
        scale = float(np.max(np.abs(want))) or 1.0
        np.testing.assert_allclose(value, want, rtol=1e-9, atol=1e-9 * scale, err_msg=key)


def test_defaults_differ_from_the_legacy_options():
    # the reference would not catch a default silently equal to the legacy form
    p, cycles = CASES["slice"]
    new = replace_nested(
        p,
        **{
            "contact.wear_projection": "local_conserving",
            "contact.impact_latch": "region",
            "joint.axial_grading": 0.75,
        },
    )
    a = run_cycles(p, cycles=cycles, wear_depth=worn_profile(p), record=False)
    b = run_cycles(new, cycles=cycles, wear_depth=worn_profile(p), record=False)
    assert not np.allclose(a.wear_work, b.wear_work, rtol=1e-3)
