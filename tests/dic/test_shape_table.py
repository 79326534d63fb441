"""The IC-GN's shape functions are a table (name -> record): a new row is accepted by the
parameters, drives the kernels' branch, writes its own outputs and is named in the file."""

from __future__ import annotations

import numpy as np
import pytest

from jointwear.datasets import speckle as sp
from jointwear.dic import CorrelationParams, correlate
from jointwear.dic.icgn._shapes import (
    AFFINE,
    FIRST_ORDER_OUTPUTS,
    SHAPE_FUNCTIONS,
    ShapeFunction,
    register_shape,
    shape_function,
)
from jointwear.errors import ParameterError


@pytest.fixture
def toy():
    """A toy row: the affine kernels, reporting the displacement only."""
    row = ShapeFunction(
        name="toy_displacement",
        description="affine warp, displacement only",
        parameters=AFFINE.parameters,
        outputs=tuple(o for o in FIRST_ORDER_OUTPUTS if o[0] in ("u", "v")),
        aliases=("toy",),
    )
    register_shape(row)
    yield row
    for key in (row.name, *row.aliases):
        del SHAPE_FUNCTIONS[key]


def test_a_registered_row_is_a_shape_like_the_others(toy):
    pair = sp.speckle_pair((96, 96), sp.RigidField((0.4, -0.3)), seed=5)
    base = correlate(pair.reference, pair.deformed, subset_size=21, step=12, threads=1)
    ds = correlate(pair.reference, pair.deformed, subset_size=21, step=12, threads=1, shape="toy")
    assert ds.attrs["dic_shape_function"] == "toy"
    assert "du_dx" not in ds and "d2u_dx2" not in ds
    np.testing.assert_array_equal(ds.u.values, base.u.values)  # the affine kernels, bit for bit
    np.testing.assert_array_equal(ds.v.values, base.v.values)
    assert CorrelationParams(shape="toy_displacement").shape_function is toy


def test_the_table_refuses_unknown_and_taken_names(toy):
    with pytest.raises(ParameterError, match="'toy_displacement' \\(affine warp"):
        CorrelationParams(shape="cubic")
    with pytest.raises(ParameterError, match="already registered"):
        register_shape(ShapeFunction("affine", "another", (0, 6), FIRST_ORDER_OUTPUTS[:1]))
    assert shape_function("first") is AFFINE and shape_function("second").second_order
