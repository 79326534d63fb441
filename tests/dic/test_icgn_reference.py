"""The IC-GN kernels against numbers recorded before they were refactored (issue 24: shared
numerics written once as inlined helpers; the results must not change).

The reference values were computed by the pre-refactor kernels (commit 94bfa2d) on this
synthetic pair; the refactored kernels reproduced them bit for bit on the development machine.
The tolerance (1e-12 pixel) admits only the last-bit differences another CPU's vector width can
give under fastmath; any change of the algorithm (a different iteration, weight or stopping
rule) moves the matches by far more.
"""

from __future__ import annotations

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

#: (interpolation, shape) -> u, v [pixel] of the first four grid points, sum of ZNCC
GRID_REFERENCE = {
    ("cubic", "affine"): (
        [2.642369373627558, 2.619208312815629, 2.5920161508902386, 2.57700112028518],
        [-1.8752059150399256, -1.036295461719005, -0.19716278350187713, 0.6371538225379556],
        15.993707019148353,
    ),
    ("cubic", "quadratic"): (
        [2.643500652386356, 2.6188123035234074, 2.5861910719539707, 2.576303289276919],
        [-1.8757291721952154, -1.0394378305596261, -0.19371855735480067, 0.6414866402900082],
        15.993789308796636,
    ),
    ("quintic", "affine"): (
        [2.6423543570381502, 2.6194787968476314, 2.5922366687567333, 2.5769763440758484],
        [-1.8751787656418235, -1.0360093311145842, -0.19686506086087693, 0.6373423140745657],
        15.993751762571117,
    ),
    ("quintic", "quadratic"): (
        [2.6445767472246224, 2.6188228313359345, 2.5861528997576153, 2.5766630101722017],
        [-1.8755521878439314, -1.0395397424438697, -0.19337372712177361, 0.641911290698027],
        15.993828479630782,
    ),
}

#: interpolation -> u, v [pixel] at two subset centres off the pixel grid (the reference
#: subset is itself interpolated)
POINTS = np.array([[40.3, 50.7], [55.5, 44.25]])
POINTS_REFERENCE = {
    "cubic": ([1.1699303188234667, 1.4844920876147905], [-1.007328176311062, -0.20465751118047149]),
    "quintic": (
        [1.1705013378305318, 1.484285248243715],
        [-1.0082773541279015, -0.2037664827938114],
    ),
}


@pytest.fixture(scope="module")
def pair():
    return sp.speckle_pair(**_PAIR)


@pytest.mark.parametrize(("interpolation", "shape"), list(GRID_REFERENCE))
def test_grid_matches_equal_the_pre_refactor_kernels(pair, interpolation, shape):
    ds = correlate(
        pair.reference, pair.deformed, subset_size=21, step=16, interpolation=interpolation,
        shape=shape, threads=1,
    )  # fmt: skip
    u, v, zncc_sum = GRID_REFERENCE[(interpolation, shape)]
    assert (ds.flag.values == 0).all()
    np.testing.assert_allclose(ds.u.values.ravel()[:4], u, rtol=0, atol=1e-12)
    np.testing.assert_allclose(ds.v.values.ravel()[:4], v, rtol=0, atol=1e-12)
    assert float(ds.zncc.sum()) == pytest.approx(zncc_sum, rel=0, abs=1e-11)


@pytest.mark.parametrize("interpolation", list(POINTS_REFERENCE))
def test_off_grid_points_equal_the_pre_refactor_kernels(pair, interpolation):
    ds = correlate(
        pair.reference, pair.deformed, points=POINTS, subset_size=21,
        interpolation=interpolation, threads=1,
    )  # fmt: skip
    u, v = POINTS_REFERENCE[interpolation]
    assert (ds.flag.values == 0).all()
    np.testing.assert_allclose(ds.u.values, u, rtol=0, atol=1e-12)
    np.testing.assert_allclose(ds.v.values, v, rtol=0, atol=1e-12)
