"""Virtual stereo rig: kinematics, rendering geometry, files written."""

from __future__ import annotations

import numpy as np
import pytest

from jointwear import io
from jointwear.datasets.rig import (
    CODECS,
    L2,
    L3,
    L4,
    RigConfig,
    VirtualRig,
    fourbar_pose,
    generate_rig,
)
from jointwear.dic.footage._track import read_bodies
from jointwear.dic.footage._video import open_frames
from jointwear.errors import BadInputError


def test_fourbar_closure_and_out_of_plane_motion():
    cfg = RigConfig(z_amplitude=3e-3)
    for t in np.linspace(0, 0.5, 11):
        p = fourbar_pose(t, cfg)
        B, C = p["B"], p["C"]
        # coupler length in the plane, follower length in 3D (spherical joint at D)
        assert np.hypot(*(C[:2] - B[:2])) == pytest.approx(L2, abs=2e-5)
        assert np.linalg.norm(C - np.array([L4, 0, 0])) == pytest.approx(L3, abs=1e-12)
        assert C[2] == pytest.approx(3e-3 * np.sin(cfg.omega * t), abs=1e-12)
        R, _ = p["follower"]
        assert np.allclose(R @ R.T, np.eye(3))
    # 120 rev/min: crank period 0.5 s
    a0 = fourbar_pose(0.0, cfg)["crank_angle"]
    assert fourbar_pose(0.5, cfg)["crank_angle"] - a0 == pytest.approx(2 * np.pi)


def test_truth_velocity_is_the_derivative_of_the_truth_position():
    rig = VirtualRig(RigConfig(width=160, height=128, duration=0.2, fps=1000))
    g = rig.ground_truth()
    x, v, t = g["follower_position"].values, g["follower_velocity"].values, g["time"].values
    fd = (x[2:] - x[:-2]) / (t[2:] - t[:-2])[:, None]
    assert np.max(np.abs(fd - v[1:-1])) < 2e-3 * np.max(np.abs(v))
    assert g.attrs["pixel_footprint_m"] == pytest.approx(0.42 / 160)


def test_rendered_patches_lie_where_the_cameras_project_them():
    rig = VirtualRig(RigConfig(width=320, height=256, noise_sigma=0.0, blur_sigma_px=0.0))
    for cam in ("left", "right"):
        img = rig._render_radiance(cam, 0.0)  # before blur, noise and quantisation
        camera = rig.calibration.cameras[cam]
        pose = fourbar_pose(0.0, rig.config)
        for patch in rig.patches:
            R, p = pose[patch.body]
            uv = camera.project(patch.corners_body() @ R.T + p)
            if np.any(uv < 0) or np.any(uv > [319, 255]):
                continue
            # inside the projected quadrilateral: speckle (not background); just outside: background
            centre = uv.mean(0)
            inner = np.rint(centre + 0.5 * (uv - centre)).astype(int)
            outer = np.rint(centre + 1.3 * (uv - centre)).astype(int)
            bg = np.float32(rig.config.background / 255.0)
            assert all(img[y, x] != bg for x, y in inner)
            assert all(img[y, x] == bg for x, y in outer if 0 <= x < 320 and 0 <= y < 256)


def test_generate_rig_files(tmp_path):
    cfg = RigConfig(
        width=160, height=128, duration=0.1, drop_frames=(2,), duplicate_frames=(0,), board_views=2
    )
    w = generate_rig(tmp_path, cfg, codec="ffv1")
    names = sorted(p.name for p in (tmp_path / "left").iterdir())
    assert names == ["frame_000000.png", "frame_000001.png", "frame_000003.png", "frame_000004.png"]
    src = open_frames(w["left_video"])
    frames = [img for _, _, img in src.frames()]
    assert len(frames) == 4 and src.fps == 50 and src.codec.upper() == "FFV1"
    assert np.array_equal(frames[0], frames[1])  # frame 1 repeats frame 0 (lossless codec)
    truth = io.load(w["truth"])
    assert list(truth["frame_recorded"].values) == [1, 1, 0, 1, 1]
    assert truth["true_camera_matrix"].sel(camera="left").values[0, 0] == pytest.approx(
        cfg.focal_px
    )
    tc, bodies = read_bodies(w["bodies"])
    assert {b.name for b in bodies} <= {"follower", "journal", "crank"}
    assert len(list((tmp_path / "calibration" / "left").iterdir())) == cfg.board_views + 1
    with pytest.raises(BadInputError, match="codec 'h265' is not available"):
        generate_rig(tmp_path / "x", cfg, codec="h265")


@pytest.mark.parametrize("codec", sorted(CODECS))
def test_codecs_round_trip(tmp_path, codec):
    from jointwear.datasets.rig import _write_video

    rng = np.random.default_rng(0)
    frames = [rng.integers(0, 256, (48, 64), dtype=np.uint8) for _ in range(3)]
    path = tmp_path / f"v{CODECS[codec][1]}"
    _write_video(path, frames, 50.0, codec, (64, 48))
    back = [img for _, _, img in open_frames(path).frames()]
    assert len(back) == 3
    if CODECS[codec][2]:  # lossless
        assert all(np.array_equal(a, b) for a, b in zip(frames, back, strict=True))


def test_prescribed_motion_from_a_dataset():
    import xarray as xr

    from jointwear.datasets.rig import PrescribedMotion

    t = np.linspace(0.0, 0.6, 61)
    theta = 0.3 + 3.0 * t + 0.5 * t**2  # a crank speeding up [rad]
    zf = 1e-3 * np.sin(5.0 * t)  # follower centre of mass out of plane [m]
    ds = xr.Dataset(
        {
            "crank_angle": ("time", theta, {"units": "rad"}),
            "follower_position": (
                ("time", "axis"),
                np.column_stack([0 * t, 0 * t, zf]),
                {"units": "m"},
            ),
        },
        coords={"time": t, "axis": ["x", "y", "z"]},
    )
    rig = VirtualRig(RigConfig(width=160, height=128, duration=0.4), motion=ds)
    g = rig.ground_truth()
    tt = g["time"].values
    assert np.allclose(g["crank_angle"].values, 0.3 + 3.0 * tt + 0.5 * tt**2, atol=1e-9)
    # the follower hangs on D: its centre of mass moves half as much out of plane as joint C
    assert np.allclose(
        g["follower_position"].sel(axis="z").values, 1e-3 * np.sin(5.0 * tt), atol=1e-9
    )
    assert "prescribed" in g.attrs["motion"]
    with pytest.raises(BadInputError, match="neither 'crank_angle' nor an out-of-plane motion"):
        PrescribedMotion.from_dataset(
            ds[["crank_angle"]].drop_vars("crank_angle").assign(x=("time", t))
        )


def test_progress_reports_every_frame_and_calibration_view(tmp_path):
    from jointwear.datasets.rig import generate_rig

    cfg = RigConfig(width=160, height=128, fps=10.0, duration=0.3)
    seen: list[tuple[str, int, int]] = []
    generate_rig(tmp_path, cfg, video=False, progress=lambda *a: seen.append(a))
    for cam in ("left", "right"):
        done = [d for s, d, t in seen if s == cam]
        assert done == list(range(1, cfg.n_frames + 1))
    views = [(d, t) for s, d, t in seen if s == "calibration"]
    n_boards = len(list((tmp_path / "calibration" / "left").glob("board_*.png")))
    assert views == [(k, n_boards) for k in range(1, n_boards + 1)]


@pytest.mark.parametrize(
    ("values", "name"),
    [({"fps": 0.0}, "fps"), ({"duration": -1.0}, "duration"), ({"duration": np.inf}, "duration")],
)
def test_rig_timing_must_be_positive_and_finite(values, name):
    # an infinite duration used to pass and end in an OverflowError when the frames were counted
    with pytest.raises(BadInputError, match=rf"rig\.{name} must be a positive finite number"):
        RigConfig(**values)
