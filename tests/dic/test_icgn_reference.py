"""The IC-GN kernels against numbers recorded before they were refactored (issue 24: shared
numerics written once as inlined helpers; the results must not change).

The reference values (data/icgn_reference.json) were computed by the pre-refactor kernels
(commit 94bfa2d) on this synthetic pair; the refactored kernels reproduced them bit for bit on
the development machine. They were re-recorded once, when the algorithm changed on purpose
(issue 39: the Gauss-Newton step scaled by the subset's kappa, which moved the matches by at
most 5.2e-5 pixel, inside the 1e-3 pixel tolerance, and cut the iterations under noise).
The tolerance (1e-12 pixel) admits only the last-bit differences another CPU's vector width can
give under fastmath, and those of LLVM inlining the fastmath sampling kernels or not, which
depends on what numba compiles in the same session (a cold cache: the pre-refactor kernels
themselves moved by up to 6e-14 pixel against a warm one); any change of the algorithm (a
different iteration, weight or stopping rule) moves the matches by far more.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from jointwear.datasets import speckle as sp
from jointwear.dic import correlate

# a 3-degree turn plus a shift: every shape function and interpolant has work to do
_PAIR = dict(
    shape=(96, 96),
    field=sp.RigidField((1.3, -0.6), 3.0, (48, 48)),
    params=sp.SpeckleParams(noise_std=1.0),
    seed=11,
)

#: matches recorded before the refactor: "grid" (interpolation/shape -> u, v [pixel] of the first
#: four grid points, sum of ZNCC), "points" (interpolation -> u, v [pixel] at POINTS)
REFERENCE = json.loads((Path(__file__).parent / "data" / "icgn_reference.json").read_text())
GRID_CASES = [tuple(key.split("/")) for key in REFERENCE["grid"]]
POINT_CASES = list(REFERENCE["points"])

#: subset centres off the pixel grid (the reference subset is itself interpolated)
POINTS = np.array([[40.3, 50.7], [55.5, 44.25]])


@pytest.fixture(scope="module")
def pair():
    return sp.speckle_pair(**_PAIR)


@pytest.mark.parametrize(("interpolation", "shape"), GRID_CASES)
def test_grid_matches_equal_the_pre_refactor_kernels(pair, interpolation, shape):
    ds = correlate(
        pair.reference, pair.deformed, subset_size=21, step=16, interpolation=interpolation,
        shape=shape, threads=1,
    )  # fmt: skip
    ref = REFERENCE["grid"][f"{interpolation}/{shape}"]
    u, v, zncc_sum = ref["u"], ref["v"], ref["zncc_sum"]
    assert (ds.flag.values == 0).all()
    np.testing.assert_allclose(ds.u.values.ravel()[:4], u, rtol=0, atol=1e-12)
    np.testing.assert_allclose(ds.v.values.ravel()[:4], v, rtol=0, atol=1e-12)
    assert float(ds.zncc.sum()) == pytest.approx(zncc_sum, rel=0, abs=1e-11)


@pytest.mark.parametrize("interpolation", POINT_CASES)
def test_off_grid_points_equal_the_pre_refactor_kernels(pair, interpolation):
    ds = correlate(
        pair.reference, pair.deformed, points=POINTS, subset_size=21,
        interpolation=interpolation, threads=1,
    )  # fmt: skip
    u, v = REFERENCE["points"][interpolation]["u"], REFERENCE["points"][interpolation]["v"]
    assert (ds.flag.values == 0).all()
    np.testing.assert_allclose(ds.u.values, u, rtol=0, atol=1e-12)
    np.testing.assert_allclose(ds.v.values, v, rtol=0, atol=1e-12)
