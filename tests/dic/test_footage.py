"""Footage tracking on the virtual rig: out-of-plane accuracy, follower velocity, bad input.

The accuracy tests use a rig like the study's: two 1280 x 1024 cameras 1.0 m from the
mechanism plane, 0.30 m apart, a 0.42 m x 0.34 m field of view (0.33 mm/pixel), 50 frames/s,
one crank revolution (0.5 s), joint C moving 2.5 mm out of plane, 1 grey level sensor noise.
"""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from jointwear import io
from jointwear.datasets.rig import RigConfig, VirtualRig, generate_rig
from jointwear.dic.footage._track import (
    FRAME_FLAGS,
    BodySpec,
    TrackConfig,
    read_bodies,
    track_footage,
)
from jointwear.dic.footage._video import check_stereo_pair, open_frames
from jointwear.errors import BadInputError, ParameterError

pytest.importorskip("jointwear.dic.subset._correlator")  # the 2D engine (DIC part 1)


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    out = tmp_path_factory.mktemp("study_rig")
    cfg = RigConfig(duration=0.5)
    written = generate_rig(out, cfg, video=False, images=True, calibration_images=False)
    truth = io.load(written["truth"])
    cal = VirtualRig(cfg).calibration  # exact cameras, world = mechanism frame
    tc, bodies = read_bodies(written["bodies"])
    tc = dataclasses.replace(tc, world_origin=[0.0, 0.0, 0.0])
    ds = track_footage(
        written["left_images"],
        written["right_images"],
        fps=cfg.fps,
        bodies=bodies,
        calibration=cal,
        config=tc,
        out=out / "motion.nc",
    )
    return cfg, truth, ds, out / "motion.nc"


def test_out_of_plane_displacement_accuracy_and_noise_floor(study):
    cfg, truth, ds, _ = study
    err = (
        ds["journal_displacement"].sel(axis="z").values
        - truth["journal_displacement"].sel(axis="z").values
    )
    rms = float(np.sqrt(np.mean(err**2)))
    floor_body = ds.attrs["journal_noise_floor_z_body_m"] * np.sqrt(2)  # displacement: 2 poses
    u = float(np.mean(ds["journal_displacement_u"].sel(axis="z").values[1:]))
    print(
        f"\njournal z: RMS error {rms * 1e6:.2f} um, noise floor Z^2/(fB) sqrt(2) sigma_u / sqrt(N) "
        f"x sqrt(2) = {floor_body * 1e6:.2f} um (sigma_u = {ds.attrs['journal_match_sigma_px']:.4f} px, "
        f"per point {ds.attrs['journal_noise_floor_z_per_point_m'] * 1e6:.1f} um), propagated u = {u * 1e6:.2f} um"
    )
    assert np.ptp(truth["journal_displacement"].sel(axis="z").values) > 4e-3  # mm-scale motion
    assert rms <= 3e-6
    # the error is of the order the stereo geometry predicts (not hidden by smoothing)
    assert 0.2 < rms / floor_body < 5
    assert 0.2 < rms / u < 5


def test_follower_velocity_within_one_percent_of_peak(study):
    cfg, truth, ds, _ = study
    assert cfg.fps == 50
    v, vt = ds["follower_velocity"].values, truth["follower_velocity"].values
    peak = float(np.max(np.linalg.norm(vt, axis=1)))
    ok = np.all(np.isfinite(v), axis=1)
    assert ok.sum() >= len(v) - 2  # only the first and last frame lack a velocity
    rms = np.sqrt(np.mean((v[ok] - vt[ok]) ** 2, axis=0))
    print(
        f"\nfollower velocity RMS error [% of peak {peak:.2f} m/s]: {np.round(rms / peak * 100, 3)}"
    )
    assert np.all(rms <= 0.01 * peak)
    # positions of the centre of mass to a few micrometres
    perr = ds["follower_position"].values - truth["follower_position"].values
    assert np.sqrt(np.mean(perr**2)) < 5e-6


def test_follower_velocity_uncertainty_covers_the_error(study):
    # the differentiator's truncation error dominates at 50 frames/s; an uncertainty of the
    # image noise alone is ~1000x too small. |error| <= 2 u for >= 90 % of the samples, and the
    # uncertainty is not vacuous (at most 4x the RMS error on the dominant axes)
    cfg, truth, ds, _ = study
    v, vt = ds["follower_velocity"].values, truth["follower_velocity"].values
    u = ds["follower_velocity_u"]
    ok = np.all(np.isfinite(v), axis=1)
    err = np.abs(v[ok] - vt[ok])
    cover = np.mean(err <= 2 * u.values[ok])
    rms_err = np.sqrt(np.mean(err**2, axis=0))
    rms_u = np.sqrt(np.mean(u.values[ok] ** 2, axis=0))
    print(
        f"\nvelocity 2-sigma coverage {cover:.3f}; RMS u / RMS error {np.round(rms_u / rms_err, 2)}"
    )
    assert cover >= 0.9
    assert np.all(rms_u[:2] <= 4 * rms_err[:2])
    from jointwear.dic.footage._rigid import time_derivative

    _, gain = time_derivative(ds["time"].values, ds["follower_position"].values)
    propagated = np.nanmedian(gain) * np.median(ds["follower_position_u"].values, axis=0)
    assert np.all(propagated[:2] < 0.01 * rms_err[:2])  # what was reported before
    assert u.attrs["calibration_median"].startswith("not assessed")  # exact cameras


def test_output_follows_the_contract(study):
    *_, path = study
    ds = io.load(path)
    for name in ("follower_velocity", "follower_position", "journal_displacement", "frame_flag"):
        assert name in ds and "units" in ds[name].attrs
    assert ds["follower_velocity"].attrs["units"] == "m s-1"
    assert list(ds["axis"].values) == ["x", "y", "z"]
    assert ds.attrs["status"] == "complete"
    assert ds.attrs["duplicated_frames"] == "[]" and ds.attrs["dropped_frames_estimated"] == 0
    assert "provenance" in ds.attrs


@pytest.fixture(scope="module")
def small(tmp_path_factory):
    """Reduced rig (640 x 512) with a dropped and a duplicated frame, videos and images."""
    out = tmp_path_factory.mktemp("small_rig")
    cfg = RigConfig(
        width=640, height=512, duration=0.2, drop_frames=(6,), duplicate_frames=(3,), board_views=7
    )
    written = generate_rig(out, cfg, video=True, images=True, calibration_images=True)
    return cfg, written, out


def _track_small(small, *, config=None, max_frames=None, folders=None, **options):
    """Track the small rig's image sequences (``folders``: other left/right folders)."""
    cfg, written, _ = small
    tc, bodies = read_bodies(written["bodies"])
    f = folders or {"left": written["left_images"], "right": written["right_images"]}
    scheduler = options.pop("scheduler", None)
    return track_footage(
        f["left"],
        f["right"],
        fps=50,
        bodies=bodies,
        calibration=VirtualRig(cfg).calibration,
        config=dataclasses.replace(tc, **options) if config is None else config,
        max_frames=max_frames,
        scheduler=scheduler,
    )


def _track_cli(left, right, bodies, cal, out, *options: str) -> int:
    """Exit code of ``jointwear dic track`` on the two cameras' footage."""
    from jointwear.cli import main

    return main(
        ["dic", "track", "--left", str(left), "--right", str(right), "--bodies", str(bodies),
         "-c", str(cal), "--out", str(out), *options]
    )  # fmt: skip


def test_cli_chain_calibrate_track_plot(small):
    from jointwear.cli import main

    cfg, written, out = small
    cal = out / "cal.nc"
    n = cfg.board_views
    assert (
        main(
            [
                "dic",
                "calibrate",
                "--left",
                str(out / "calibration/left"),
                "--right",
                str(out / "calibration/right"),
                "--squares",
                *map(str, cfg.board_squares),
                "--square-mm",
                str(cfg.board_square_size * 1e3),
                "--world-view",
                str(n),
                "--out",
                str(cal),
            ]
        )
        == 0
    )
    motion = out / "motion.nc"
    images = (written["left_images"], written["right_images"])
    assert _track_cli(*images, written["bodies"], cal, motion, "--fps", "50", "--plot",
                      str(out / "motion.png")) == 0  # fmt: skip
    ds = io.load(motion)
    truth = io.load(written["truth"])
    # the duplicated frame (frame 4 repeats frame 3) and the dropped frame 6 are reported
    assert ds.attrs["duplicated_frames"] == "[4]"
    assert ds.attrs["dropped_frames_estimated"] == 1
    assert ds["frame_flag"].values[4] & 1 and ds["frame_flag"].values[6] & 2
    # calibrated from board images, world frame from the board on the mechanism plane
    t = truth.sel(time=ds["time"].values)
    origin = np.asarray(truth.attrs["world_board_origin_m"])
    good = np.all(np.isfinite(ds["follower_position"].values), axis=1)
    perr = ds["follower_position"].values[good] - (t["follower_position"].values[good] - origin)
    assert np.max(np.abs(perr)) < 3e-5
    # the board calibration states its length uncertainty: a part of the velocity's budget
    cal_u = ds["follower_velocity_u"].attrs["calibration_median"]
    assert isinstance(cal_u, (list, np.ndarray)) and 0 < np.max(cal_u) < 1e-3
    assert (out / "motion.png").stat().st_size > 10_000
    # videos (FFV1, lossless): same result for the first frames, frame rate from the container
    motion_v = out / "motion_video.nc"
    videos = (written["left_video"], written["right_video"])
    assert _track_cli(*videos, written["bodies"], cal, motion_v, "--max-frames", "4") == 0
    dv = io.load(motion_v)
    assert np.allclose(
        dv["follower_position"].values, ds["follower_position"].values[:4], atol=1e-9
    )


def test_partial_results_are_kept(small, tmp_path):
    import shutil

    cfg, written, out = small
    for cam in ("left", "right"):
        shutil.copytree(written[f"{cam}_images"], tmp_path / cam)
    files = sorted((tmp_path / "left").iterdir())
    files[5].write_bytes(b"not a png")
    tc, bodies = read_bodies(written["bodies"])
    tc = dataclasses.replace(tc, chunk_size=2)
    cal = VirtualRig(cfg).calibration
    target = tmp_path / "motion.nc"
    with pytest.raises(
        BadInputError, match=r"frame 5\) could not be read.*5 frames processed before are saved"
    ):
        track_footage(
            tmp_path / "left",
            tmp_path / "right",
            fps=50,
            bodies=bodies,
            calibration=cal,
            config=tc,
            out=target,
        )
    ds = io.load(target)
    assert ds.sizes["time"] == 5 and ds.attrs["status"].startswith("stopped after 5 frames")


def test_bad_footage_errors(small, tmp_path):
    import cv2

    cfg, written, out = small
    bad = tmp_path / "clip.mp4"
    bad.write_bytes(b"\x00" * 4096)
    with pytest.raises(
        BadInputError, match=r"could not open this 'mp4' container.*ffmpeg -i IN -c:v ffv1"
    ):
        open_frames(bad)
    # a container that opens but whose stream cannot be decoded (truncated FFV1)
    w = cv2.VideoWriter(
        str(tmp_path / "t.avi"), cv2.VideoWriter_fourcc(*"FFV1"), 50, (64, 48), False
    )
    for k in range(5):
        w.write(np.random.default_rng(k).integers(0, 255, (48, 64), dtype=np.uint8))
    w.release()
    (tmp_path / "cut.avi").write_bytes((tmp_path / "t.avi").read_bytes()[:6000])
    with pytest.raises(
        BadInputError,
        match=r"'avi' container opened but its video stream \(codec 'ffv1'\) could not be decoded",
    ):
        open_frames(tmp_path / "cut.avi")
    with pytest.raises(BadInputError, match="unsupported file type '.txt'"):
        (tmp_path / "a.txt").write_text("x")
        open_frames(tmp_path / "a.txt")
    with pytest.raises(BadInputError, match="image sequence: give the frame rate"):
        open_frames(written["left_images"])
    # left/right of different lengths and rates
    for name, fps, n in (("l.avi", 50, 5), ("r.avi", 25, 4)):
        w = cv2.VideoWriter(
            str(tmp_path / name), cv2.VideoWriter_fourcc(*"FFV1"), fps, (64, 48), False
        )
        for _ in range(n):
            w.write(np.zeros((48, 64), np.uint8))
        w.release()
    with pytest.raises(
        BadInputError, match=r"frame rates differ \(50 vs 25.*lengths differ \(5 vs 4"
    ):
        check_stereo_pair(open_frames(tmp_path / "l.avi"), open_frames(tmp_path / "r.avi"))
    # a region of interest outside the image
    tc, bodies = read_bodies(written["bodies"])
    outside = BodySpec("follower", "follower", [[600.0, 10.0], [700.0, 10.0], [700.0, 60.0]])
    with pytest.raises(
        BadInputError,
        match="region of interest of body 'follower' reaches outside the 640x512 image",
    ):
        track_footage(
            written["left_images"],
            written["right_images"],
            fps=50,
            bodies=[outside],
            calibration=VirtualRig(cfg).calibration,
            config=tc,
        )
    # calibration of another resolution
    big = VirtualRig(RigConfig()).calibration
    with pytest.raises(
        BadInputError, match="640x512 pixel frames but the calibration's left camera is 1280x1024"
    ):
        track_footage(
            written["left_images"],
            written["right_images"],
            fps=50,
            bodies=bodies,
            calibration=big,
            config=tc,
        )


def test_bodies_file_errors(tmp_path):
    p = tmp_path / "b.toml"
    p.write_text('[bodies.follower]\nrole = "follower"\npolygon = [[1, 2], [3, 4]]\n')
    with pytest.raises(ParameterError, match="needs at least 3"):
        read_bodies(p)
    p.write_text("[track]\nsubset_size = 20\n[bodies.a]\npolygon = [[1, 2], [3, 4], [5, 6]]\n")
    with pytest.raises(ParameterError, match="subset_size=20"):
        read_bodies(p)
    p.write_text('[bodies.a]\nrole = "wheel"\npolygon = [[1, 2], [3, 4], [5, 6]]\n')
    with pytest.raises(ParameterError, match="role"):
        read_bodies(p)
    assert TrackConfig().velocity_window == 9


def test_parallel_chunks_match_sequential(small):
    # two worker processes, each chunk starting from SIFT features: same poses as sequential
    runs = {w: _track_small(small, max_frames=4, workers=w, chunk_size=2) for w in (1, 2)}
    a, b = runs[1]["follower_position"].values, runs[2]["follower_position"].values
    assert a.shape == b.shape == (4, 3)
    # IC-GN stops within ~1e-3 px of the optimum: different starting guesses (previous frame
    # vs SIFT) agree to a few thousandths of a pixel (0.66 mm/px here)
    assert np.allclose(a, b, atol=3e-6, equal_nan=True)
    assert runs[2].attrs["workers"] == 2


def test_crank_angle_tracked_and_reveals_frames_lost_in_a_video(tmp_path):
    # a wider view that includes the crank (0.65 mm/px); the crank turns 14.4 degrees per frame;
    # frame 3 is lost in a constant-rate video (no time gap to see)
    cfg = RigConfig(
        width=960,
        height=768,
        duration=0.14,
        look_at=(0.15, 0.08, 0.0),
        fov_width=0.62,
        drop_frames=(3,),
    )
    w = generate_rig(tmp_path, cfg, video=True, images=False, calibration_images=False)
    tc, bodies = read_bodies(w["bodies"])
    tc = dataclasses.replace(tc, world_origin=[0.0, 0.0, 0.0], subset_size=15, step=6)
    crank = [b for b in bodies if b.role == "crank"]
    ds = track_footage(
        w["left_video"],
        w["right_video"],
        bodies=crank,
        calibration=VirtualRig(cfg).calibration,
        config=tc,
    )
    truth = io.load(w["truth"])
    recorded = truth["frame_recorded"].values == 1
    true_angle = truth["crank_angle"].values[recorded]
    err = np.degrees(ds["crank_angle"].values - true_angle)
    assert np.ptp(np.degrees(true_angle)) > 70
    assert np.max(np.abs(err)) < 0.02
    assert ds["crank_angle"].attrs["units"] == "rad"
    assert ds.attrs["dropped_frames_from_crank"] == '{"3": 1}'
    assert ds["frame_flag"].values[3] & 8


def _one_camera(bodies):
    """The rig's bodies without their mechanism-frame points (which one camera cannot place)."""
    return [dataclasses.replace(b, centroid_mechanism=None) for b in bodies]


def test_single_camera_tracks_in_pixels(small, tmp_path):
    cfg, written, out = small
    tc, bodies = read_bodies(written["bodies"])
    bodies = _one_camera(bodies)
    target = tmp_path / "mono.nc"
    ds = track_footage(
        written["left_images"], fps=50, bodies=bodies, config=tc, max_frames=4, out=target
    )
    assert (
        "follower_velocity" not in ds
        and ds["follower_image_velocity"].attrs["units"] == "pixel s-1"
    )
    # the follower moves by pixels to tens of pixels per frame in the image
    step = np.linalg.norm(np.diff(ds["follower_image_position"].values, axis=0), axis=1)
    assert np.all(step > 1) and step.sum() > 20
    assert io.load(target).attrs["world_frame"] == "left image (pixels)"


def test_plot_needs_motion_variables():
    import xarray as xr

    from jointwear.dic import plot_body_motion

    with pytest.raises(
        BadInputError, match="neither 'follower_velocity' nor 'journal_displacement'"
    ):
        plot_body_motion(xr.Dataset())


def test_journal_offset_in_the_bearing_frame(small):
    # declare the follower plate a "bearing" body centred at its centre of mass: the journal
    # cap's offset in that moving frame is compared with the ground truth
    cfg, written, out = small
    tc, bodies = read_bodies(written["bodies"])
    tc = dataclasses.replace(tc, world_origin=[0.0, 0.0, 0.0])
    bodies = [dataclasses.replace(b, role="bearing") if b.role == "follower" else b for b in bodies]
    ds = track_footage(
        written["left_images"],
        written["right_images"],
        fps=50,
        bodies=bodies,
        calibration=VirtualRig(cfg).calibration,
        config=tc,
        max_frames=4,
    )
    truth = io.load(written["truth"]).isel(time=slice(0, 4))
    rot = truth["body_rotation"].sel(body="follower").values
    rel = np.einsum("nij,kj->nik", rot, rot[0])  # rotation since the first frame
    d = truth["journal_position"].values - truth["follower_position"].values
    expected = np.einsum("nji,nj->ni", rel, d)
    assert ds["journal_offset"].attrs["units"] == "m"
    assert np.max(np.abs(ds["journal_offset"].values - expected)) < 3e-5


def test_per_subset_and_body_displacements_do_not_collide(small, tmp_path):
    """The journal body's per-subset field and its body-level displacement are both kept."""
    cfg, written, out = small
    tc, bodies = read_bodies(written["bodies"])
    bodies = _one_camera(bodies)
    ds = track_footage(
        written["left_images"],
        fps=50,
        bodies=bodies,
        config=tc,
        max_frames=3,
        out=tmp_path / "mono2.nc",
    )
    assert "journal_subset_displacement" in ds
    assert ds["journal_subset_displacement"].ndim == 3
    assert ds["journal_image_displacement"].dims == ("time", "axis")


def test_a_blank_frame_is_flagged_and_tracking_resumes_after_it(small, tmp_path):
    # frame 4 is blank in both cameras (a flash, a lens cap): tracking is lost there; the
    # frame after it, already tracked speculatively from frame 4, is tracked again from the
    # frames before and comes out as in the clean footage
    import shutil

    import cv2

    from jointwear.dic.footage._track import FRAME_FLAGS

    cfg, written, out = small
    for cam in ("left", "right"):
        shutil.copytree(written[f"{cam}_images"], tmp_path / cam)
        f4 = sorted((tmp_path / cam).iterdir())[4]
        img = cv2.imread(str(f4), cv2.IMREAD_UNCHANGED)
        cv2.imwrite(str(f4), np.full_like(img, 128))
    clean = _track_small(small, max_frames=8)
    blank = _track_small(
        small, max_frames=8, folders={"left": tmp_path / "left", "right": tmp_path / "right"}
    )
    flags = blank["frame_flag"].values
    assert flags[4] & FRAME_FLAGS["tracking_failed"]
    assert np.isnan(blank["follower_position"].values[4]).all()
    keep = np.arange(8) != 4
    assert not np.any(flags[keep] & FRAME_FLAGS["tracking_failed"])
    a = blank["follower_position"].values[keep]
    b = clean["follower_position"].values[keep]
    assert np.allclose(a, b, atol=3e-6, equal_nan=True)


def test_lost_tracking_is_reinitialised_and_the_speculative_next_frame_redone(small, monkeypatch):
    # the pose of frame 1 "fails" once (as when tracking is lost): the body is found again
    # from SIFT features, the next frame (tracked meanwhile from frame 1's matches) is
    # discarded and tracked again, and every pose equals the undisturbed run's
    import jointwear.dic.footage._frames as footage

    def run():
        return _track_small(small, max_frames=7)

    clean = run()
    t1 = float(clean["time"].values[1])
    real_pose = footage._body_pose
    calls = []

    def flaky_pose(st, left, right, cfg, calibration):
        res = real_pose(st, left, right, cfg, calibration)
        if st.spec.name == "follower":
            calls.append(True)
            if len(calls) == 2:  # frame 1, first attempt
                return footage._failed_pose(3, len(st.ref3d))
        return res

    forgotten = []
    real_forget = footage._CameraBodyTracker.forget_after
    monkeypatch.setattr(footage, "_body_pose", flaky_pose)
    monkeypatch.setattr(
        footage._CameraBodyTracker,
        "forget_after",
        lambda self, t: (forgotten.append(t), real_forget(self, t)),
    )
    redone = run()
    assert forgotten and min(forgotten) == t1
    assert not np.any(redone["frame_flag"].values & footage.FRAME_FLAGS["tracking_failed"])
    a, b = redone["follower_position"].values, clean["follower_position"].values
    # frame 1 itself starts from other guesses; its subsets agree to ~3e-5 px, but one
    # borderline subset may leave or join the rigid fit's inliers (tens of micrometres at
    # 0.66 mm/px); every later frame is as in the undisturbed run
    np.testing.assert_allclose(a[1], b[1], atol=5e-5)
    np.testing.assert_allclose(np.delete(a, 1, 0), np.delete(b, 1, 0), atol=3e-6)


def test_sixteen_bit_image_sequences_track_like_eight_bit(small, tmp_path):
    # machine-vision cameras store 12/16-bit TIFF/PNG frames: the same scene scaled to 16 bits
    # (x 257) is tracked from the stored integers and gives the same poses
    import cv2

    cfg, written, out = small
    for cam in ("left", "right"):
        (tmp_path / cam).mkdir()
        for f in sorted(written[f"{cam}_images"].iterdir()):
            img = cv2.imread(str(f), cv2.IMREAD_UNCHANGED)
            cv2.imwrite(str(tmp_path / cam / (f.stem + ".png")), img.astype(np.uint16) * 257)
    eight = _track_small(small, max_frames=5)
    sixteen = _track_small(
        small, max_frames=5, folders={"left": tmp_path / "left", "right": tmp_path / "right"}
    )
    assert not np.any(sixteen["frame_flag"].values & 4)
    np.testing.assert_allclose(
        sixteen["follower_position"].values, eight["follower_position"].values, atol=3e-6
    )


def test_resume_continues_a_stopped_run(small, tmp_path):
    import shutil

    cfg, written, out = small
    for cam in ("left", "right"):
        shutil.copytree(written[f"{cam}_images"], tmp_path / cam)
    files = sorted((tmp_path / "left").iterdir())
    good = files[6].read_bytes()
    files[6].write_bytes(b"not a png")
    tc, bodies = read_bodies(written["bodies"])
    cal = VirtualRig(cfg).calibration
    target = tmp_path / "motion.nc"
    run = dict(fps=50, bodies=bodies, calibration=cal, out=target)
    with pytest.raises(BadInputError, match="6 frames processed before are saved"):
        track_footage(tmp_path / "left", tmp_path / "right", config=tc, **run)
    partial = io.load(target)
    assert partial.sizes["time"] == 6
    files[6].write_bytes(good)  # the frame is repaired
    # other tracking options than the partial run's: refused, naming the option
    with pytest.raises(BadInputError, match=r"cannot resume.*track.subset_size was 21, now 25"):
        track_footage(
            tmp_path / "left",
            tmp_path / "right",
            config=dataclasses.replace(tc, subset_size=25),
            resume=True,
            **run,
        )
    resumed = track_footage(
        tmp_path / "left",
        tmp_path / "right",
        config=dataclasses.replace(tc, chunk_size=3),  # chunking may change
        resume=True,
        **run,
    )
    whole = _track_small(small)
    assert resumed.attrs["status"] == "complete"
    assert resumed.sizes["time"] == whole.sizes["time"] == len(files)
    # the kept frames are the partial run's, bit for bit
    assert np.array_equal(
        resumed["follower_position"].values[:6],
        partial["follower_position"].values,
        equal_nan=True,  # frame 3 is a duplicate: no position
    )
    # the resumed frames start again from the reference features (as a parallel chunk does):
    # the same poses as the uninterrupted run to within the IC-GN stopping tolerance
    d = resumed["follower_position"].values - whole["follower_position"].values
    assert np.nanmax(np.abs(d)) < 3e-6
    assert np.array_equal(np.isnan(d), np.isnan(whole["follower_position"].values))
    # and within the results' own uncertainty (the point of interest lies 0.3 m off the
    # follower here: a flipped rigid-fit inlier used to tilt it by 13x its stated u)
    u = np.hypot(resumed["follower_position_u"].values, whole["follower_position_u"].values)
    ok = np.isfinite(d)
    assert np.all(np.abs(d[ok]) <= u[ok])
    assert np.array_equal(resumed["follower_n_points"].values, whole["follower_n_points"].values)
    assert resumed.attrs["duplicated_frames"] == whole.attrs["duplicated_frames"] == "[4]"
    assert np.array_equal(resumed["frame_flag"].values, whole["frame_flag"].values)
    # a complete result is returned as it is
    again = track_footage(tmp_path / "left", tmp_path / "right", config=tc, resume=True, **run)
    assert np.array_equal(
        again["follower_velocity"].values, resumed["follower_velocity"].values, equal_nan=True
    )


def test_position_uncertainty_holds_the_lever_arm_of_the_point_of_interest(small):
    # with the exact cameras (world = mechanism frame), the bodies file's world_origin (meant
    # for a calibration on the board view) puts each point of interest 0.3 m off its body:
    # the poorly determined tilt of the narrow follower plate and the small journal cap moves
    # it by tens of micrometres, which *_position_u must hold (it held only the subsets'
    # centroid's uncertainty: errors of 40x and 70x u in z)
    cfg, written, _ = small
    truth = io.load(written["truth"])
    rec = truth["frame_recorded"].values.astype(bool)
    tc, _ = read_bodies(written["bodies"])
    assert np.hypot(*tc.world_origin[:2]) > 0.25
    ds = _track_small(small)
    bodies = list(truth["body"].values)
    for spec_name, poi in (("follower", "follower_position"), ("journal", "journal_position")):
        spec = next(b for b in read_bodies(written["bodies"])[1] if b.name == spec_name)
        p0 = np.asarray(spec.centroid_mechanism) - np.asarray(tc.world_origin)
        k = bodies.index(spec_name)
        Rk = truth["body_rotation"].values[rec][:, k]
        ok = truth["body_origin"].values[rec][:, k]
        true_pos = np.einsum("kij,j->ki", Rk, Rk[0].T @ (p0 - ok[0])) + ok
        x, u = ds[poi].values, ds[f"{poi}_u"].values
        err = (x - x[0]) - (true_pos - true_pos[0])
        good = np.all(np.isfinite(err), axis=1)
        good[0] = False
        ratio = np.abs(err[good]) / u[good]
        assert ratio.max() < 4, (spec_name, ratio.max(axis=0))
        assert np.sqrt(np.mean(ratio**2)) > 0.2  # not vacuous


def test_rigid_fit_keeps_ordinary_points_and_its_point_uncertainty_covers_a_lever_arm():
    from jointwear.dic.footage._rigid import fit_rigid_robust, pose_point_uncertainty

    rng = np.random.default_rng(3)
    # a thin plate (40 x 4 mm), z 10x noisier than x and y, as a stereo rig measures it
    n = 60
    P = np.column_stack([rng.uniform(-0.02, 0.02, n), rng.uniform(-0.002, 0.002, n), np.zeros(n)])
    sig = np.array([1e-6, 1e-6, 1e-5])
    cov = np.broadcast_to(np.diag(sig**2), (n, 3, 3)).copy()
    poi = np.array([0.0, 0.3, 0.0])  # 0.3 m off the plate, across it
    a = 0.2
    R = np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])
    t = np.array([0.1, 0.2, 0.0])
    errs, us, kept = [], [], []
    for _ in range(300):
        Q = P @ R.T + t + rng.normal(size=(n, 3)) * sig
        Q[:2] += 1e-3  # two wrong matches
        Rf, tf, inl, _ = fit_rigid_robust(P, Q, cov_p=0 * cov, cov_q=cov)
        assert not inl[:2].any()
        kept.append(inl[2:].mean())
        errs.append((Rf - R) @ poi + tf - t)
        us.append(pose_point_uncertainty(P, Q, Rf, tf, inl, poi, cov))
    errs, us = np.array(errs), np.array(us)
    # ordinary points stay in (the MAD limit alone trims a few of every set)
    assert np.mean(kept) > 0.999
    # the tilt's lever arm: z uncertainty of the point far above the centroid's 1e-5 / sqrt(n)
    assert np.median(us[:, 2]) > 20 * sig[2] / np.sqrt(n)
    spread = errs.std(axis=0)
    assert np.all(np.abs(np.median(us, axis=0) / spread - 1) < 0.2)


def test_cli_shared_folders_patterns_and_resume(small, tmp_path, capsys):
    """Both cameras' images in one folder, named as VIC-3D does (name_<frame>_<camera>), selected
    with patterns; a run stopped by a damaged frame is resumed from its partial result."""
    import shutil

    from jointwear.cli import main

    cfg, written, out = small
    cal_dir, run_dir = tmp_path / "cal", tmp_path / "run"
    cal_dir.mkdir()
    run_dir.mkdir()
    for c, cam in enumerate(("left", "right")):
        for i, f in enumerate(sorted((out / "calibration" / cam).iterdir())):
            shutil.copy(f, cal_dir / f"CalB_{i + 1:04d}_{c}.png")
        for f in sorted(written[f"{cam}_images"].iterdir()):
            k = int(f.stem.split("_")[1])  # frame_000006 -> 6 (the dropped frame has no file)
            shutil.copy(f, run_dir / f"Run-{k:04d}_{c}.png")
    cal = tmp_path / "cal.nc"
    args = ["--squares", *map(str, cfg.board_squares), "--square-mm", "25", "--out", str(cal)]
    args += ["--world-view", str(cfg.board_views)]  # the board on the mechanism plane
    both = ["--left", str(cal_dir / "*_0.png"), "--right", str(cal_dir / "*_1.png")]
    assert main(["dic", "calibrate", *both, *args]) == 0
    assert "calibrated from 8 views (0 rejected)" in capsys.readouterr().out
    # the folder alone holds two cameras: refused with the pattern to use
    folders = ["--left", str(cal_dir), "--right", str(cal_dir), "--overwrite"]
    assert main(["dic", "calibrate", *folders, *args]) == 3
    assert "'folder/*_0.tif'" in capsys.readouterr().err

    motion = tmp_path / "motion.nc"
    track = ["dic", "track", "--left", str(run_dir / "*_0.png"), "--right"]
    track += [str(run_dir / "*_1.png"), "--fps", "50", "--bodies", str(written["bodies"])]
    track += ["-c", str(cal), "--out", str(motion)]
    damaged = run_dir / "Run-0008_0.png"
    good = damaged.read_bytes()
    damaged.write_bytes(b"broken")
    assert main(track) == 3
    assert "frames processed before are saved" in capsys.readouterr().err
    partial = io.load(motion)
    assert partial.attrs["status"].startswith("stopped after 7 frames")  # frames 0-5, 7
    damaged.write_bytes(good)
    assert main([*track, "--resume"]) == 0
    ds = io.load(motion)
    assert (
        ds.attrs["status"] == "complete" and ds.sizes["time"] == len(list(run_dir.iterdir())) // 2
    )
    # the dropped frame 6 is seen in the names' numbering; the duplicate 4 in the content
    assert ds.attrs["dropped_frames_estimated"] == 1 and ds.attrs["duplicated_frames"] == "[4]"
    # world frame = the board on the mechanism plane: positions against the truth
    truth = io.load(written["truth"])
    t = truth.sel(time=ds["time"].values)
    origin = np.asarray(truth.attrs["world_board_origin_m"])
    ok = np.all(np.isfinite(ds["follower_position"].values), axis=1)
    assert ok.sum() == ds.sizes["time"] - 1  # all but the duplicated frame
    perr = ds["follower_position"].values[ok] - (t["follower_position"].values[ok] - origin)
    assert np.max(np.abs(perr)) < 3e-5


def test_chunks_inside_a_daemon_process_and_on_a_dask_cluster(small, monkeypatch):
    # a dask worker is a daemonic process, which may not start processes ("daemonic
    # processes are not allowed to have children"): the chunks run in threads there; and
    # --scheduler runs them as tasks on a cluster; both give the sequential poses
    import multiprocessing

    seq = _track_small(small, max_frames=4, workers=1, chunk_size=2)
    proc = multiprocessing.current_process()
    monkeypatch.setattr(proc, "_config", {**proc._config, "daemon": True})
    assert multiprocessing.current_process().daemon
    in_daemon = _track_small(small, max_frames=4, workers=2, chunk_size=2)
    monkeypatch.undo()
    from distributed import LocalCluster

    with LocalCluster(
        n_workers=1, threads_per_worker=2, processes=False, dashboard_address=":0"
    ) as cluster:
        on_cluster = _track_small(
            small, max_frames=4, workers=1, chunk_size=2, scheduler=cluster.scheduler_address
        )
    a = seq["follower_position"].values
    for other in (in_daemon, on_cluster):
        assert np.allclose(other["follower_position"].values, a, atol=3e-6, equal_nan=True)


def _shifted_calibration(cfg, dy_px):
    from jointwear.dic.calibration._camera import Camera

    cal = VirtualRig(cfg).calibration
    r = cal.right
    K = r.matrix.copy()
    K[1, 2] += dy_px  # the right camera's images sit dy_px lower than the calibration says
    right = Camera(K, r.distortion, r.rotation, r.translation, r.image_size)
    return dataclasses.replace(cal, right=right)


def test_a_calibration_off_its_images_is_measured_and_the_gate_configurable(small, capsys):
    from jointwear.cli import main

    cfg, written, out = small
    tc, bodies = read_bodies(written["bodies"])
    bad = _shifted_calibration(cfg, 20.0)
    opts = {"fps": 50, "bodies": bodies, "max_frames": 3}
    imgs = (written["left_images"], written["right_images"])
    with pytest.raises(BadInputError, match=r"a median (19\.\d|20\.\d) px from the calibration"):
        track_footage(*imgs, calibration=bad, config=tc, **opts)
    # far off (the epipolar band misses the region): measured on the whole image
    far = _shifted_calibration(cfg, 60.0)
    with pytest.raises(BadInputError, match=r"a median (59\.\d|60\.\d) px from the calibration"):
        track_footage(*imgs, calibration=far, config=tc, **opts)
    # the message's figure, used as the gate, lets the (biased) calibration through
    loose = dataclasses.replace(tc, max_epipolar_px=30.0)
    ds = track_footage(*imgs, calibration=bad, config=loose, **opts)
    assert np.all(ds["follower_n_points"].values >= tc.min_points)
    # the CLI flag reaches the gate; a bad value is a usage error naming the flag
    bad.save(out / "shifted.nc")
    args = ["dic", "track", "--left", str(imgs[0]), "--right", str(imgs[1]), "--bodies",
            str(written["bodies"]), "--calibration", str(out / "shifted.nc"), "--fps", "50",
            "--max-frames", "2", "--out", str(out / "shifted_motion.nc"), "--overwrite"]  # fmt: skip
    assert main(args) == 3
    assert "max_epipolar_px" in capsys.readouterr().err
    assert main([*args, "--max-epipolar-px", "30"]) == 0
    assert main([*args, "--max-epipolar-px", "-1"]) == 2
    assert "--max-epipolar-px" in capsys.readouterr().err


def test_reinitialisations_are_counted_and_limited(small, monkeypatch):
    import jointwear.dic.footage._frames as frames

    real_pose = frames._body_pose
    calls = []

    def flaky_pose(st, left, right, cfg, calibration):
        res = real_pose(st, left, right, cfg, calibration)
        frame = len(st.rows.get("poi", ()))
        if st.spec.name == "follower" and frame in (1, 3) and frame not in calls:
            calls.append(frame)  # frames 1 and 3 lose the follower (first attempt)
            return frames._failed_pose(3, len(st.ref3d))
        return res

    monkeypatch.setattr(frames, "_body_pose", flaky_pose)
    ds = _track_small(small, max_frames=5)
    assert ds["follower_reinitialised"].values.tolist() == [0, 1, 0, 1, 0]
    assert json.loads(ds.attrs["sift_reinitialisations"])["follower"] == 2
    assert not np.any(ds["frame_flag"].values & FRAME_FLAGS["tracking_failed"])
    calls.clear()
    limited = _track_small(small, max_frames=5, max_reinit=1)
    assert limited["follower_reinitialised"].values.tolist() == [0, 1, 0, 0, 0]
    failed = (limited["frame_flag"].values & FRAME_FLAGS["tracking_failed"]) > 0
    assert failed.tolist() == [False, False, False, True, False]
