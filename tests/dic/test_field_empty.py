"""No silent empty or mostly-flagged result: a calibration 8 pixels off its images is refused
up front with the measured epipolar error and the gate that settles it; a run with no valid
point exits 1 unless --allow-empty; a mostly flagged image names its dominant flag."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from jointwear import io
from jointwear.cli import main
from jointwear.datasets import speckle as sp
from jointwear.datasets.surface import SurfaceScene


@pytest.fixture(scope="module")
def rig(tmp_path_factory):
    """A flat speckled surface seen by the virtual rig, and a calibration whose right camera
    sits 2.5 mm too high: its images are 8 pixels off the epipolar lines."""
    from jointwear.dic import Camera, StereoCalibration

    tmp = tmp_path_factory.mktemp("off")
    sc = SurfaceScene(lambda x, y: 0.0 * x)
    left, right = sc.pair(noise_seed=0)
    cv2.imwrite(str(tmp / "L.png"), left)
    cv2.imwrite(str(tmp / "R.png"), right)
    R = sc.calibration.right
    up = Camera(R.matrix, R.distortion, R.rotation, R.translation + [0, 0.0025, 0], R.image_size)
    StereoCalibration(sc.calibration.left, up, source="off by 2.5 mm").save(tmp / "off.nc")
    sc.calibration.save(tmp / "good.nc")
    x0, y0, x1, y1 = sc.roi_left()
    roi = f"{x0:.0f},{y0:.0f},{x1:.0f},{y1:.0f}"
    return tmp, roi


def _field(tmp, roi, cal, *extra):
    return [
        "dic", "field", "--left", str(tmp / "L.png"), "--right", str(tmp / "R.png"),
        "--calibration", str(tmp / cal), "--roi", roi, "--subset", "25", "--step", "40",
        "--out", str(tmp / "f.nc"), "--overwrite", *extra,
    ]  # fmt: skip


def test_a_calibration_8_pixels_off_is_refused_up_front_with_the_figure(rig, capsys):
    tmp, roi = rig
    code = main(_field(tmp, roi, "off.nc"))
    err = capsys.readouterr().err
    assert code == 3, err
    assert "epipolar_mismatch" in err and "--epipolar-max" in err
    figure = float(err.split("median epipolar error ")[1].split(" pixel")[0])
    assert 7.0 < figure < 9.0  # the offset put in: 8 pixels
    assert not (tmp / "f.nc").exists()


def test_the_fix_the_refusal_names_reads_the_input_or_says_so(rig, capsys):
    tmp, roi = rig
    # the right calibration: no refusal, every point valid
    assert main(_field(tmp, roi, "good.nc")) == 0
    capsys.readouterr()
    # a gate raised above the figure, as the message suggests: the run goes on, and the
    # output states the measured median epipolar error beside the gate
    assert main(_field(tmp, roi, "off.nc", "--epipolar-max", "4")) == 0
    ds = io.load(tmp / "f.nc")
    assert ds.attrs["dic_epipolar_max_pixel"] == 4.0
    assert 2.0 < ds.attrs["dic_median_reprojection_pixel"] < 4.0


def test_the_gate_the_refusal_names_keeps_the_points_run_as_printed(rig, capsys):
    """The suggested --epipolar-max is measured on the images (95th percentile of the residual),
    not the median (which by construction leaves half the points flagged)."""
    tmp, roi = rig
    assert main(_field(tmp, roi, "off.nc")) == 3
    err = " ".join(capsys.readouterr().err.split())
    value = err.split("--epipolar-max ")[-1].split(" ")[0]
    median = float(err.split("median RMS reprojection residual ")[1].split(" pixel")[0])
    assert float(value) > median
    assert main(_field(tmp, roi, "off.nc", "--epipolar-max", value)) == 0
    ok = io.load(tmp / "f.nc").flag.values[0] == 0
    assert ok.mean() >= 0.9


def _unrelated_pair(tmp):
    a = sp.speckle_sequence((120, 140), [None], seed=1)[0]
    b = sp.speckle_sequence((120, 140), [None], seed=2)[0]
    cv2.imwrite(str(tmp / "a.png"), a)
    cv2.imwrite(str(tmp / "b.png"), b)
    return [str(tmp / "a.png"), str(tmp / "b.png")]


def test_no_valid_point_exits_1_naming_the_dominant_flag_unless_allowed(tmp_path, capsys):
    names = _unrelated_pair(tmp_path)
    args = ["dic", "field", *names, "--subset", "21", "--step", "20", "--search-radius", "8"]
    args += ["--out", str(tmp_path / "f.nc")]
    code = main(args)
    err = capsys.readouterr().err
    assert code == 1, err
    assert "no valid point" in err and "--allow-empty" in err
    meanings = ("low_correlation", "not_converged", "not_reached", "diverged")
    assert any(f"mostly {m}" in err for m in meanings), err
    assert main([*args, "--overwrite", "--allow-empty"]) == 0
    assert "no valid point" in capsys.readouterr().err  # still said
    assert (io.load(tmp_path / "f.nc").flag.values[-1] != 0).all()


def test_correlate_says_why_most_points_failed(tmp_path, capsys):
    names = _unrelated_pair(tmp_path)
    args = ["dic", "correlate", *names, "--subset", "21", "--step", "20", "--search-radius", "8"]
    code = main([*args, "--out", str(tmp_path / "c.nc")])
    err = capsys.readouterr().err
    assert code == 1 and "no valid point" in err and "mostly" in err


def test_a_starved_run_counts_later_frames_only_and_names_max_iterations(tmp_path, capsys):
    """Two iterations cannot reach a 3.4-pixel shift: the summary counts only the later frames
    (the reference matches itself at ZNCC 1) and the warning names --max-iterations."""
    frames = sp.speckle_sequence(
        (200, 200), [None, sp.RigidField((3.4, -2.3)), sp.RigidField((6.7, -4.6))], seed=3
    )
    for k, f in enumerate(frames):
        cv2.imwrite(str(tmp_path / f"f_{k}.png"), f)
    args = ["dic", "correlate", str(tmp_path / "f_*.png"), "--out", str(tmp_path / "s.nc")]
    code = main([*args, "--max-iterations", "2"])
    out, err = capsys.readouterr()
    assert code == 1
    assert "0/512 points ok in the 2 later frames" in out and "1.0000" not in out
    assert "ran out" in err and "--max-iterations 2" in err and "raise --max-iterations" in err
    assert main([*args, "--overwrite"]) == 0  # the default limit, as the fix says
    ds = io.load(tmp_path / "s.nc")
    assert (ds.flag.values[1:] == 0).mean() > 0.9
    assert np.nanmax(np.abs(ds.u.values[2] - 6.7)) < 0.05
