"""A speckle data set on disk: its truth is the field asked for, ramped over the frames."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from jointwear.datasets.speckle_set import SpeckleMotion, write_speckle_set
from jointwear.errors import ParameterError


def test_truth_of_a_ramped_translation(tmp_path):
    names = write_speckle_set(tmp_path, (24, 32), SpeckleMotion(u=1.5, v=-0.7), frames=2, seed=1)
    assert names == ["frame_0000.png", "frame_0001.png", "frame_0002.png"]
    assert all((tmp_path / n).stat().st_size > 0 for n in names)
    truth = xr.load_dataset(tmp_path / "truth.nc")
    # frame 0 is the reference, frame k carries k/frames of the translation (closed form)
    np.testing.assert_array_equal(truth.u.values[0], 0.0)
    np.testing.assert_allclose(truth.u.values[1], 0.75, rtol=0, atol=1e-12)
    np.testing.assert_allclose(truth.v.values[2], -0.7, rtol=0, atol=1e-12)
    assert truth.u.shape == (3, 24, 32)


def test_rotation_about_the_image_centre():
    f = SpeckleMotion("rotation", theta_deg=90.0).at((21, 41))
    # a point one pixel right of the centre (20, 10) goes one pixel down (+y)
    u, v = f.displacement(np.array([21.0]), np.array([10.0]))
    np.testing.assert_allclose([u[0], v[0]], [-1.0, 1.0], atol=1e-12)


def test_bad_requests_are_refused_before_writing(tmp_path):
    with pytest.raises(ParameterError, match="field 'wavy'"):
        SpeckleMotion("wavy")
    with pytest.raises(ParameterError, match="frames=0"):
        write_speckle_set(tmp_path / "out", (16, 16), frames=0)
    assert not (tmp_path / "out").exists()
