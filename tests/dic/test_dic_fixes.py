"""Issue 23, part 3: inputs that used to crash, be misdiagnosed or be silently ignored."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from jointwear import io
from jointwear.cli import main
from jointwear.datasets import speckle as sp
from jointwear.errors import BadInputError, CalibrationError


# --- calibration --------------------------------------------------------------------------
@pytest.fixture(scope="module")
def rig_boards():
    from jointwear.datasets.rig import RigConfig, VirtualRig

    rig = VirtualRig(RigConfig(width=640, height=512, board_views=8))
    return rig, rig.board_images()


def test_inner_corners_given_as_squares_are_named(rig_boards):
    from jointwear.dic.calibration._board import CalibrationBoard, calibrate_stereo

    rig, boards = rig_boards
    sx, sy = rig.config.board_squares  # 10 x 8 squares: 9 x 7 inner corners
    wrong = CalibrationBoard("chessboard", sx - 1, sy - 1, rig.config.board_square_size)
    views = boards[:3]  # fewer than the 6 needed: the count is checked on the failed views
    with pytest.raises(CalibrationError, match=rf"--squares {sx} {sy}") as info:
        calibrate_stereo([b[0] for b in views], [b[1] for b in views], wrong)
    assert "inner corners" in str(info.value)
    assert "record more views" not in str(info.value)
    # the right count with too few views: no hint about the squares, the views are the problem
    right = CalibrationBoard("chessboard", sx, sy, rig.config.board_square_size)
    with pytest.raises(CalibrationError, match="record more views") as info:
        calibrate_stereo([b[0] for b in views], [b[1] for b in views], right)
    assert "--squares" not in str(info.value)


def test_baseline_is_stored_in_the_calibration_length_unit(rig_boards):
    from jointwear.dic.calibration._board import CalibrationBoard, calibrate_stereo

    rig, boards = rig_boards
    sx, sy = rig.config.board_squares
    board = CalibrationBoard("chessboard", sx, sy, 1.0, length_unit="square")
    cal = calibrate_stereo([b[0] for b in boards], [b[1] for b in boards], board)
    attrs = cal.to_dataset().attrs
    assert "baseline_m" not in attrs
    # the rig's baseline in squares of the board
    expected = rig.calibration.baseline / rig.config.board_square_size
    assert attrs["baseline_square"] == pytest.approx(expected, rel=5e-3)
    metric = calibrate_stereo(
        [b[0] for b in boards],
        [b[1] for b in boards],
        CalibrationBoard("chessboard", sx, sy, rig.config.board_square_size),
    ).to_dataset()
    assert metric.attrs["baseline_m"] == pytest.approx(rig.calibration.baseline, rel=5e-3)
    assert "baseline_square" not in metric.attrs


# --- import-field -------------------------------------------------------------------------
def _dice_2d(path, n=4):
    rows = ["COORDINATE_X,COORDINATE_Y,DISPLACEMENT_X,DISPLACEMENT_Y,SIGMA"]
    rows += [f"{10 * k},{20},{0.1 * k},{-0.2},0.01" for k in range(n)]
    path.write_text("\n".join(rows) + "\n")


def test_import_field_length_unit_on_pixel_files_is_refused(tmp_path, capsys):
    for k in range(2):
        _dice_2d(tmp_path / f"DICe_solution_{k}.txt")
    args = ["dic", "import-field", str(tmp_path / "DICe_solution_*.txt"), "--format", "dice"]
    args += ["--origin", "measured", "--out", str(tmp_path / "d.nc")]
    assert main([*args, "--length-unit", "mm"]) == 3
    err = capsys.readouterr().err
    assert "--length-unit" in err and "pixel" in err
    assert main(args) == 0
    assert io.load(tmp_path / "d.nc").displacement.attrs["units"] == "pixel"


# --- track with one camera ------------------------------------------------------------------
@pytest.fixture(scope="module")
def mono(tmp_path_factory):
    from jointwear.datasets.rig import RigConfig, generate_rig

    out = tmp_path_factory.mktemp("mono_rig")
    cfg = RigConfig(width=640, height=512, duration=0.1)
    written = generate_rig(out, cfg, video=False, images=True, calibration_images=False)
    return written


def test_one_camera_track_refuses_a_world_centroid_and_takes_a_pixel_one(mono):
    import dataclasses

    from jointwear.dic.footage._track import read_bodies, track_footage

    tc, bodies = read_bodies(mono["bodies"])
    plain = [dataclasses.replace(b, centroid=None, centroid_mechanism=None) for b in bodies]
    world = [dataclasses.replace(plain[0], centroid=[0.3, 0.15, 0.0]), *plain[1:]]
    with pytest.raises(BadInputError, match=r"centroid = \[x, y\]"):
        track_footage(mono["left_images"], fps=50, bodies=world, config=tc, max_frames=2)
    mech = [dataclasses.replace(plain[0], centroid_mechanism=[0.3, 0.15, 0.0]), *plain[1:]]
    with pytest.raises(BadInputError, match="centroid_mechanism"):
        track_footage(mono["left_images"], fps=50, bodies=mech, config=tc, max_frames=2)
    # a pixel point of the body: reported where it is (frame 0) and moving with the body
    base = track_footage(mono["left_images"], fps=50, bodies=plain, config=tc, max_frames=3)
    name = plain[0].name
    p0 = base[f"{name}_image_position"].values[0]
    at = [dataclasses.replace(plain[0], centroid=[float(p0[0]), float(p0[1])]), *plain[1:]]
    ds = track_footage(mono["left_images"], fps=50, bodies=at, config=tc, max_frames=3)
    np.testing.assert_allclose(
        ds[f"{name}_image_position"].values, base[f"{name}_image_position"].values, atol=1e-6
    )


# --- sequences: names, reference named differently, incremental ------------------------------
def _write(folder, names, frames):
    folder.mkdir(exist_ok=True)
    for n, f in zip(names, frames, strict=True):
        cv2.imwrite(str(folder / n), np.asarray(f, np.uint8))


def test_a_reference_named_unlike_the_frames_is_diagnosed_and_accepted_first(tmp_path, capsys):
    fields = [None] + [sp.RigidField((0.4 * k, -0.2 * k)) for k in range(1, 4)]
    frames = sp.speckle_sequence((120, 140), fields, seed=3)
    names = ["Sample3 Reference.tif"] + [f"Sample3-{k}.tif" for k in range(1, 4)]
    _write(tmp_path, names, frames)
    out = str(tmp_path / "s.nc")
    code = main(["dic", "correlate", str(tmp_path / "Sample3*.tif"), "--out", out])
    err = capsys.readouterr().err
    assert code == 3
    assert "'Sample3 Reference.tif'" in err and "both read as frame" not in err
    assert "reference" in err and "Sample3-*.tif" in err
    # the fix the message names: the reference first, then the frames' pattern
    args = ["dic", "correlate", str(tmp_path / "Sample3 Reference.tif")]
    args += [str(tmp_path / "Sample3-*.tif"), "--subset", "21", "--step", "20", "--out", out]
    assert main(args) == 0
    ds = io.load(out)
    assert ds.sizes["time"] == 4
    np.testing.assert_allclose(ds.u.values[3][ds.flag.values[3] == 0], 1.2, atol=0.02)


def test_incremental_beats_absolute_on_a_pattern_that_changes_under_large_deformation():
    """A 32 % stretch with 24 degrees of rotation while the speckle pattern is gradually
    replaced by another (as paint cracks or a surface changes under large strain): matched
    against frame 0 the subsets decorrelate and are lost; the incremental reference follows."""
    from jointwear.dic import correlate_sequence

    n = 9
    fields = [None] + [
        sp.AffineField.from_strain(exx=0.04 * k, eyy=-0.02 * k, rotation_deg=3 * k, center=(100, 100))
        for k in range(1, n)
    ]  # fmt: skip
    prm = sp.SpeckleParams(speckle_size=4, noise_std=1)
    a = sp.speckle_sequence((200, 200), fields, params=prm, seed=3)
    b = sp.speckle_sequence((200, 200), fields, params=prm, seed=4)
    frames = [
        (1 - k / (n - 1)) * x + (k / (n - 1)) * y for k, (x, y) in enumerate(zip(a, b, strict=True))
    ]
    kw = dict(subset_size=21, step=10, roi=(40, 40, 160, 160))
    absolute = correlate_sequence(frames, reference="absolute", **kw)
    incremental = correlate_sequence(frames, reference="incremental", **kw)
    X, Y = np.meshgrid(incremental.x.values, incremental.y.values)
    tu, tv = fields[-1].displacement(X, Y)
    ok_abs = absolute.flag.values[-1] == 0
    ok_inc = incremental.flag.values[-1] == 0
    assert ok_abs.mean() < 0.1 and ok_inc.mean() > 0.95
    err = np.hypot(incremental.u.values[-1] - tu, incremental.v.values[-1] - tv)[ok_inc]
    assert np.sqrt(np.mean(err**2)) < 0.6  # pixel, after 40 pixel of motion at the corners
    assert incremental.reference_frame.values[-1] > 0
    assert incremental.attrs["dic_reference_updates"] >= 1


# --- flags that cannot apply -----------------------------------------------------------------
@pytest.fixture(scope="module")
def pair(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("pair")
    frames = sp.speckle_sequence((100, 120), [None, sp.RigidField((0.5, 0.3))], seed=2)
    names = [str(tmp / "a.png"), str(tmp / "b.png")]
    for n, f in zip(names, frames, strict=True):
        cv2.imwrite(n, f)
    return tmp, names


@pytest.mark.parametrize(
    "command, extra, named",
    [
        # sequence options on a pair of images
        ("correlate", ["--sequence-mode", "incremental"], "--sequence-mode"),
        ("correlate", ["--fps", "50"], "--fps"),
        # stereo options on a 2D field
        ("field", ["--frame", "plane"], "--frame"),
        ("field", ["--epipolar-max", "2"], "--epipolar-max"),
        # a frame rate on still images given one by one
        ("field", ["--fps", "10"], "--fps"),
    ],
)
def test_flags_that_cannot_apply_to_the_input_are_usage_errors(pair, command, extra, named, capsys):
    tmp, names = pair
    out = tmp / f"{command}.nc"
    code = main(["dic", command, *names, *extra, "--out", str(out), "--overwrite"])
    assert code == 2
    assert named in capsys.readouterr().err


def test_field_points(pair, capsys):
    tmp, names = pair
    pts = tmp / "pts.txt"
    pts.write_text("40, 40\n60.5, 50\n80, 45\n")
    out = str(tmp / "p.nc")
    assert main(["dic", "field", *names, "--points", str(pts), "--subset", "21", "--out", out]) == 0
    ds = io.load(out)
    np.testing.assert_allclose(ds.x.values, [40, 60.5, 80])
    np.testing.assert_allclose(ds.displacement.values[1, :, 0], 0.5, atol=0.02)
    assert "strain" not in ds  # scattered points: no grid to fit strain on
    capsys.readouterr()
    bad = ["dic", "field", *names, "--points", str(pts), "--strain-window", "5", "--out", out]
    assert main([*bad, "--overwrite"]) == 2
    assert "--strain-window" in capsys.readouterr().err
    both = ["dic", "field", *names, "--points", str(pts), "--roi", "0,0,50,50", "--out", out]
    assert main([*both, "--overwrite"]) == 2


@pytest.mark.parametrize(
    "extra, named",
    [
        (["--calibration", "cal.nc"], "--calibration"),
        (["--max-epipolar-px", "3"], "--max-epipolar"),
    ],
)
def test_track_stereo_flags_with_one_camera_are_errors(mono, tmp_path, extra, named, capsys):
    args = ["dic", "track", "--left", str(mono["left_images"]), "--bodies", str(mono["bodies"])]
    code = main([*args, *extra, "--fps", "50", "--out", str(tmp_path / "m.nc")])
    assert code == 2
    assert named in capsys.readouterr().err


@pytest.mark.parametrize(
    "extra, named",
    [
        (["--marker", "18"], "--marker"),  # a chessboard has no markers
        (["--dictionary", "DICT_4X4_50"], "--dictionary"),  # nor an ArUco dictionary
        (["--every", "5"], "--every"),  # a folder of images has no frames to skip
    ],
)
def test_calibrate_options_that_cannot_apply_are_errors(tmp_path, extra, named, capsys):
    args = ["dic", "calibrate", "--left", str(tmp_path), "--right", str(tmp_path)]
    args += ["--board", "chessboard", "--square", "25", "--unit", "mm", *extra]
    assert main([*args, "--out", str(tmp_path / "c.nc")]) == 2
    err = capsys.readouterr().err
    assert named in err and "applies to" in err
    assert not (tmp_path / "c.nc").exists()
