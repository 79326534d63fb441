"""The shared file-name helpers: glob patterns and the natural order of numbered files."""

from __future__ import annotations

import doctest
from pathlib import Path

import pytest

from jointwear import filenames
from jointwear.filenames import GLOB_CHARS, natural_key


def test_numbered_files_sort_by_the_value_of_their_digit_groups():
    names = ["cam_1_10.tif", "cam_1_9.tif", "cam_0_100.tif", "cam_1_0010a.tif", "cam_0_99.tif"]
    ordered = sorted((Path(n) for n in names), key=natural_key)
    # camera 0 before 1, then frames by value (9 < 10, 99 < 100); "0010a" ties 10 and sorts by
    # what follows the digits
    assert [p.name for p in ordered] == [
        "cam_0_99.tif",
        "cam_0_100.tif",
        "cam_1_9.tif",
        "cam_1_10.tif",
        "cam_1_0010a.tif",
    ]


@pytest.mark.parametrize(
    ("name", "is_pattern"),
    [("*_0.tif", True), ("frame_?.png", True), ("f[0-9].png", True), ("frame_0001.png", False)],
)
def test_glob_characters(name, is_pattern):
    assert (GLOB_CHARS.search(name) is not None) is is_pattern


def test_the_example_runs():
    assert doctest.testmod(filenames).failed == 0
