"""OpenCV calibration files that are truncated, empty or corrupt: refused with a clear error
(exit code 3), never a traceback from inside OpenCV (OpenCV 5 raises SystemError, not
cv2.error), never a silent change of meaning."""

from __future__ import annotations

import os

import cv2
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from jointwear.dic.calibration._importers import read_opencv_calibration
from jointwear.errors import BadInputError

K1 = np.array([[1523.5, 0.0, 321.25], [0.0, 1524.25, 253.5], [0.0, 0.0, 1.0]])
K2 = np.array([[1528.75, 0.0, 318.5], [0.0, 1529.0, 257.75], [0.0, 0.0, 1.0]])
D1 = np.array([[-0.08, 0.1, 2e-4, -1e-4, 0.0]])
D2 = np.array([[-0.072, 0.09, 1.8e-4, -0.9e-4, 0.0]])
ANG = np.deg2rad(16.7)
R = np.array([[np.cos(ANG), 0, -np.sin(ANG)], [0, 1.0, 0], [np.sin(ANG), 0, np.cos(ANG)]])
T = np.array([[-287.5], [1.25], [41.0]])  # mm


def _write(path, *, size=True):
    fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_WRITE)
    if size:
        fs.write("image_width", 640)
        fs.write("image_height", 512)
    for key, val in (("K1", K1), ("D1", D1), ("K2", K2), ("D2", D2), ("R", R), ("T", T)):
        fs.write(key, val)
    fs.release()
    return path


@pytest.fixture(scope="module")
def originals(tmp_path_factory):
    d = tmp_path_factory.mktemp("ocv")
    return {ext: _write(d / f"stereo.{ext}").read_bytes() for ext in ("yml", "xml")}


def _matches_original(cal) -> bool:
    Rm, Tm = cal.relative_pose
    return (
        np.allclose(cal.left.matrix, K1)
        and np.allclose(cal.right.matrix, K2)
        and np.allclose(cal.left.distortion[:5], D1.ravel())
        and np.allclose(cal.right.distortion[:5], D2.ravel())
        and np.allclose(Rm, R, atol=1e-9)
        and np.allclose(Tm, T.ravel() * 1e-3)
        and cal.left.image_size == (640, 512)
    )


def _read_or_refuse(path):
    """Either a calibration identical to the original or a BadInputError; nothing else."""
    try:
        cal = read_opencv_calibration(path, length_unit="mm")
    except BadInputError as exc:
        assert str(path) in str(exc) or path.name in str(exc)
        return "refused"
    assert _matches_original(cal), "a corrupt file was read with a different meaning"
    return "read"


@pytest.mark.parametrize("ext", ["yml", "xml"])
def test_issue_cases_exit_3(tmp_path, originals, ext, capsys):
    from jointwear.cli import main

    data = originals[ext]
    cases = {"truncated": data[: len(data) // 2], "empty": b"", "header only": data[:12]}
    for what, content in cases.items():
        path = tmp_path / f"{what.replace(' ', '_')}.{ext}"
        path.write_bytes(content)
        with pytest.raises(BadInputError, match="could not be read as an OpenCV|cannot be read"):
            read_opencv_calibration(path, length_unit="mm")
        args = ["dic", "import-calibration", str(path), "--format", "opencv"]
        assert main([*args, "--length-unit", "mm", "-o", str(tmp_path / "o.nc")]) == 3, what
        err = capsys.readouterr().err
        assert "Traceback" not in err and "SystemError" not in err and path.name in err
    path = tmp_path / f"whole.{ext}"
    path.write_bytes(data)
    assert _read_or_refuse(path) == "read"


FUZZ_EXAMPLES = 25 if os.environ.get("CI") else 300


@settings(
    max_examples=FUZZ_EXAMPLES,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)
@given(
    ext=st.sampled_from(["yml", "xml"]),
    cut=st.floats(0.0, 1.0),
    edits=st.lists(
        st.tuples(
            st.floats(0.0, 1.0),
            st.sampled_from(["delete_line", "dup_line", "junk", "nul"]),
        ),
        max_size=3,
    ),
)
def test_fuzzed_files_are_read_right_or_refused(tmp_path, originals, ext, cut, edits):
    # structural damage (truncation, lost or repeated lines, junk, NUL bytes); a changed digit
    # inside a number is a different valid file and cannot be detected by any reader
    data = bytearray(originals[ext])
    for where, kind in edits:
        pos = int(where * max(len(data) - 1, 0))
        if kind in ("delete_line", "dup_line"):
            lines = bytes(data).split(b"\n")
            k = int(where * (len(lines) - 1))
            lines = lines[:k] + (lines[k + 1 :] if kind == "delete_line" else lines[k:])
            data = bytearray(b"\n".join(lines))
        elif kind == "junk":
            data[pos:pos] = b"}]>&:"
        elif kind == "nul":
            data[pos:pos] = b"\x00"
    data = data[: int(cut * len(data)) + 1] if cut < 1.0 else data
    path = tmp_path / f"fuzz.{ext}"
    path.write_bytes(bytes(data))
    _read_or_refuse(path)
