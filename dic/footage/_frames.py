"""Footage tracking: body set-up at the reference frames and the per-frame pipeline."""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from jointwear.dic.calibration import epipolar_distance, triangulate
from jointwear.dic.footage._config import FRAME_FLAGS, BodySpec, TrackConfig
from jointwear.dic.footage._features import (
    MatchReport,
    _homography_guess,
    _sift_features,
    _sift_homography,
    epipolar_band,
)
from jointwear.dic.footage._rigid import fit_rigid_robust, pose_point_uncertainty
from jointwear.dic.footage._tracker import (
    _CameraBodyTracker,
    _grid_in_polygon,
    _match_sigma,
    _noise_sigma,
)
from jointwear.errors import BadInputError


# ---------------------------------------------------------------------------------------------
@dataclass
class _BodyState:
    spec: BodySpec
    left: _CameraBodyTracker
    right: _CameraBodyTracker | None
    ref3d: np.ndarray  # (N, 3) reference points (world) or (N, 2) pixels (mono)
    sigma_px: np.ndarray
    point_of_interest: np.ndarray
    rows: dict[str, list] = field(default_factory=dict)
    ref_cov: np.ndarray | None = None  # (N, 3, 3) covariance of ref3d (stereo) [m^2]

    def point_cov(self, cov: np.ndarray | None) -> np.ndarray:
        """Covariance of the current points: the triangulated ``cov`` (stereo) or, with one
        camera (``cov`` None), the isotropic match uncertainty ``sigma_px`` [pixel^2]."""
        if cov is not None:
            return cov
        d = self.ref3d.shape[1]
        return np.square(self.sigma_px)[:, None, None] * np.eye(d)


def _body_point(spec: BodySpec, ref: np.ndarray, cfg: TrackConfig) -> np.ndarray:
    """The body's point of interest in the frame of ``ref`` (world [m] in stereo, left-image
    pixels with one camera); refuses a point given in the other frame."""
    d = ref.shape[1]
    where = f"bodies.{spec.name}"
    if d == 2 and spec.centroid_mechanism is not None:
        raise BadInputError(
            f"{where}.centroid_mechanism is a point of the mechanism frame [m], which one "
            "camera does not measure (positions are in pixels of the left image): give "
            f"{where}.centroid = [x, y] in pixels of the left reference image, or track with "
            "two cameras (--right and --calibration)"
        )
    if spec.centroid is not None:
        point = np.asarray(spec.centroid, dtype=float)
        if point.shape != (d,) or not np.isfinite(point).all():
            raise BadInputError(
                f"{where}.centroid = {list(spec.centroid)}: "
                + (
                    "with one camera positions are in pixels of the left reference image: "
                    "give centroid = [x, y] in pixels (a world point [x, y, z] in metres needs "
                    "two cameras and a calibration)"
                    if d == 2
                    else "expected [x, y, z] in metres of the calibration's world frame"
                )
            )
        return point
    if spec.centroid_mechanism is not None:
        return np.asarray(spec.centroid_mechanism, dtype=float) - np.asarray(cfg.world_origin)
    return np.nanmean(ref, axis=0)


def _setup_states(L, R, bodies, calibration, cfg, ref_l, ref_r) -> list[_BodyState]:
    """Subsets of every body, stereo correspondence and reference 3D points."""
    # the right image's features are computed in a thread beside the left work
    pool = ThreadPoolExecutor(max_workers=1) if R is not None else None
    try:
        return _setup_bodies(L, R, bodies, calibration, cfg, ref_l, ref_r, pool)
    finally:
        if pool is not None:
            pool.shutdown(cancel_futures=True)


def _setup_bodies(L, R, bodies, calibration, cfg, ref_l, ref_r, pool) -> list[_BodyState]:
    half = cfg.subset_size // 2
    w, h = L.size
    gate = sift_epipolar_px(cfg)
    right_features = None
    if R is not None:
        polys = [np.asarray(b.polygon, dtype=float) for b in bodies]
        band = epipolar_band(calibration, polys, ref_r.shape, gate)
        right_features = pool.submit(_sift_features, ref_r, mask=band)
    noise = _noise_sigma(ref_l)
    states: list[_BodyState] = []
    for spec in bodies:
        poly = np.asarray(spec.polygon, dtype=float)
        if np.any(poly < 0) or np.any(poly[:, 0] > w - 1) or np.any(poly[:, 1] > h - 1):
            raise BadInputError(
                f"region of interest of body '{spec.name}' reaches outside the {w}x{h} image "
                f"(x {poly[:, 0].min():.0f}..{poly[:, 0].max():.0f}, y {poly[:, 1].min():.0f}.."
                f"{poly[:, 1].max():.0f}); fix its polygon in the TOML file (pixels of the left "
                "reference image, x = column, y = row)"
            )
        pts = _grid_in_polygon(poly, half, cfg.step)
        if len(pts) < cfg.min_points:
            raise BadInputError(
                f"region of interest of body '{spec.name}' holds only {len(pts)} subsets of "
                f"{cfg.subset_size} px at a {cfg.step} px step (at least {cfg.min_points} needed); "
                "enlarge the polygon or reduce track.subset_size/step"
            )
        lt = _CameraBodyTracker(ref_l, pts, cfg, f"left/{spec.name}")
        sig = (
            np.full(len(pts), cfg.sigma_px)
            if cfg.sigma_px > 0
            else _match_sigma(ref_l, pts, half, noise)
        )
        if R is not None:
            report = MatchReport()
            H = _sift_homography(
                _sift_features(ref_l, poly),
                right_features.result(),
                calibration=calibration,
                max_epipolar_px=gate,
                report=report,
            )
            if H is None:
                if report.measured_epipolar_px is None:
                    # the band may miss the region when the calibration is far off: measure
                    # the offset on the whole right image
                    _sift_homography(
                        _sift_features(ref_l, poly), _sift_features(ref_r),
                        calibration=calibration, max_epipolar_px=gate, report=report,
                    )  # fmt: skip
                raise BadInputError(_no_stereo_match_message(spec.name, report, gate))
            guess = _homography_guess(H, pts)
            pos_r, zn, good = lt.track(ref_r, point_guess=guess)
            epi = epipolar_distance(calibration, pts, np.where(np.isfinite(pos_r), pos_r, 0.0))
            correlated = good.copy()
            good &= epi < cfg.max_epipolar_px
            if good.sum() < cfg.min_points:
                off = float(np.median(epi[correlated])) if correlated.any() else float("nan")
                hint = (
                    f"; the {correlated.sum()} subsets that correlated lie a median {off:.1f} px "
                    "from the calibration's epipolar lines: recalibrate, or accept the "
                    f"calibration with max_epipolar_px = {np.ceil(1.5 * off):g} ([track] in the "
                    "bodies TOML, CLI --max-epipolar-px)"
                    if correlated.sum() >= cfg.min_points and off > cfg.max_epipolar_px
                    else "; check the calibration and the ROI"
                )
                raise BadInputError(
                    f"body '{spec.name}': only {good.sum()} of {len(pts)} subsets matched between "
                    f"the left and right reference images (ZNCC >= {cfg.zncc_min}, epipolar "
                    f"distance < {cfg.max_epipolar_px} px){hint}"
                )
            pts, pos_r, sig = pts[good], pos_r[good], sig[good]
            lt = _CameraBodyTracker(ref_l, pts, cfg, f"left/{spec.name}")
            rt = _CameraBodyTracker(ref_r, pos_r, cfg, f"right/{spec.name}")
            X, ref_cov, _ = triangulate(calibration, pts, pos_r, sigma_px=sig)
            ref = X
        else:
            rt = None
            ref = pts.copy()
            ref_cov = None
        lt.polygon = poly
        states.append(
            _BodyState(spec, lt, rt, ref, sig, _body_point(spec, ref, cfg), ref_cov=ref_cov)
        )
    return states


def sift_epipolar_px(cfg: TrackConfig) -> float:
    """Epipolar gate of the SIFT matches that start stereo tracking [pixel]: the subsets'
    ``max_epipolar_px``, but at least 3 px (feature positions are coarser than subsets')."""
    return max(3.0, float(cfg.max_epipolar_px))


def _no_stereo_match_message(name: str, report: MatchReport, gate: float) -> str:
    what = (
        f"body '{name}': its region could not be found in the right reference image "
        f"({report.features_ref} features in the region, {report.features_target} in the right "
        f"image's epipolar band, {report.matches} descriptor matches, {report.epipolar_inliers} "
        f"within {gate:g} px of their epipolar lines)"
    )
    off = report.measured_epipolar_px
    if off is not None and off > gate:
        return (
            f"{what}; the matches one homography explains lie a median {off:.1f} px from the "
            "calibration's epipolar lines: the calibration does not fit these images "
            "(recalibrate, or check that it belongs to this rig and resolution), or accept it "
            f"with max_epipolar_px = {np.ceil(1.5 * off):g} ([track] in the bodies TOML, CLI "
            "--max-epipolar-px)"
        )
    return (
        f"{what}; check that both cameras see the speckle pattern and that the calibration "
        "belongs to this rig"
    )


def _is_duplicate(img: np.ndarray, prev: np.ndarray, cfg: TrackConfig) -> bool:
    """Mean absolute difference on every 8th pixel of every 8th row (20 000 samples in a
    megapixel frame) below the threshold."""
    a = img[::8, ::8].astype(np.float32)
    return float(np.mean(np.abs(a - prev[::8, ::8]))) < cfg.duplicate_threshold


def _run_frames(states, frames, cfg, calibration, pool, *, first=0, reinit_first=False):
    """Track every body through ``frames`` (index, time, left, right); yields ``(index,
    time, flag, duplicate)`` per frame, the rows appended to each state.

    Pipelined over two frames: the left trackers of frame k + 1 run while the right trackers
    of frame k and the main thread's poses of frame k do. Each left tracker predicts from its
    own matches (extrapolation, phase correlation, probe subsets); each right tracker starts
    from the left matches of the same frame carried to the right image at the depths of the
    previous frame's triangulated points, a fraction of a pixel off. If frame k needs a
    re-initialisation (tracking lost), frame k + 1's left tracking, already started, is
    discarded and done again from the repaired history.
    """
    pending = None
    prev_img = None
    it = iter(frames)
    while True:
        try:
            i, t, img_l, img_r = next(it)
        except StopIteration:
            break
        except BaseException:
            # an unreadable frame: the frame tracked before it is still finished and kept
            if pending is not None:
                pending["results"] = _wait(pending)
                flag, _ = _finish_frame(states, pending, cfg, calibration, None)
                yield pending["i"], pending["t"], flag, pending["dup"]
            raise
        if i < first:
            prev_img = img_l
            continue
        dup = prev_img is not None and _is_duplicate(img_l, prev_img, cfg)
        prev_img = img_l
        reinit = reinit_first and i == first
        cur = {"i": i, "t": t, "img_l": img_l, "img_r": img_r, "dup": dup, "reinit": reinit}
        track = not dup and not reinit
        cur["left"] = _start_left(states, cur, pool, pending) if track else None
        cur["right"] = None
        if pending is not None:
            pending["results"] = _wait(pending)
            flag, rolled_back = _finish_frame(states, pending, cfg, calibration, cur)
            if rolled_back and track:
                cur["left"] = _start_left(states, cur, pool, None)
            yield pending["i"], pending["t"], flag, pending["dup"]
        if track:
            cur["right"] = _start_right(states, cur, pool, calibration)
        pending = cur
    if pending is not None:
        pending["results"] = _wait(pending)
        flag, _ = _finish_frame(states, pending, cfg, calibration, None)
        yield pending["i"], pending["t"], flag, pending["dup"]


def _start_left(states, fr, pool, prev):
    """Submit every body's left tracking (with commit) of one frame, each after the same
    tracker's job for the previous frame ``prev`` (still running perhaps: it predicts from
    it)."""
    run = pool.submit if pool is not None else _Immediate
    before = prev["left"] if prev is not None and prev["left"] is not None else [None] * len(states)
    return [
        run(_after, dep, st.left.track_and_commit, fr["img_l"], fr["t"])
        for st, dep in zip(states, before, strict=True)
    ]


def _after(dep, fn, *args):
    """``fn(*args)`` once the future ``dep`` (an earlier job, or None) is done."""
    if dep is not None:
        dep.result()
    return fn(*args)


def _start_right(states, fr, pool, calibration):
    """Submit every body's right tracking of one frame, each after its left tracking."""
    run = pool.submit if pool is not None else _Immediate
    jobs = []
    for st, left in zip(states, fr["left"], strict=True):
        if st.right is None:
            jobs.append(None)
            continue
        last = st.rows.get("points") or []
        X_prev = last[-2:] if len(last) >= 2 else None
        jobs.append(run(_track_right, st, fr["img_r"], fr["t"], left, X_prev, calibration))
    return jobs


def _track_right(st, img_r, t, left, X_prev, calibration):
    """The right camera's tracking, started from the left matches of the same frame."""
    pred = None
    if X_prev is not None and calibration is not None:
        pred = _stereo_prediction(calibration, left.result()[0], X_prev)
    return st.right.track_and_commit(img_r, t, predicted=pred)


def _stereo_prediction(calibration, uv_left: np.ndarray, X_prev: np.ndarray) -> np.ndarray:
    """Right-image positions (N, 2) of left-image matches ``uv_left`` (N, 2) assumed at the
    depths (left camera) of the previous frame's points ``X_prev`` (N, 3) [m]; NaN where
    either is unknown. A body moving Δz between frames shifts the prediction along the
    epipolar line by f B Δz / Z² (a fraction of a pixel at tens of frames per second)."""
    L, R = calibration.left, calibration.right
    X2, X1 = (np.asarray(X, dtype=float) for X in X_prev)
    z1 = X1 @ L.rotation[2] + L.translation[2]
    z = 2.0 * z1 - (X2 @ L.rotation[2] + L.translation[2])  # linear in time
    xn = L.pixels_to_normalized(np.asarray(uv_left, dtype=float))
    Xc = np.column_stack([xn * z[:, None], z])
    return R.project((Xc - L.translation) @ L.rotation)


def _wait(fr):
    """The (left, right) tracking results of a frame (None when it was not tracked)."""
    if fr["left"] is None:
        return None
    rights = fr["right"] or [None] * len(fr["left"])
    return [
        (jl.result(), jr.result() if jr is not None else None)
        for jl, jr in zip(fr["left"], rights, strict=True)
    ]


def _finish_frame(states, fr, cfg, calibration, speculative) -> tuple[int, bool]:
    """Poses of one tracked frame (appending to each state's rows); the frame's flag and
    whether the ``speculative`` next frame's tracking had to be discarded."""
    t, img_l, img_r = fr["t"], fr["img_l"], fr["img_r"]
    dup, reinit, tracked = fr["dup"], fr["reinit"], fr["results"]
    flag = FRAME_FLAGS["duplicated"] if dup else 0
    features: dict[str, Any] = {}
    rolled_back = False

    def feats(name: str, img: np.ndarray):
        if name not in features:
            features[name] = _sift_features(img)
        return features[name]

    for k, st in enumerate(states):
        d = st.ref3d.shape[1]
        n = len(st.ref3d)
        if dup:
            # a repeated image carries no new information (and a wrong time)
            _append_row(
                st,
                np.full((d, d), np.nan),
                np.full(d, np.nan),
                np.full(d, np.nan),
                0,
                np.nan,
                np.full((n, d), np.nan, np.float32),
                np.full((n, d), np.nan, np.float32),
                np.full(n, np.nan, np.float32),
            )
            continue
        res = None
        if not reinit:
            res = _body_pose(st, *tracked[k], cfg, calibration)
        lost = not reinit and (res is None or not res[0])
        n_reinit = int(sum(st.rows.get("reinit", ())))
        retry = reinit or (lost and n_reinit < cfg.max_reinit)
        if retry:
            # chunk start or lost: initialise from SIFT features of the reference images
            if speculative is not None and speculative["left"] is not None and not rolled_back:
                _wait(speculative)  # the next frame's left tracking started from this one
                for other in states:
                    for tr in (other.left, other.right):
                        if tr is not None:
                            tr.forget_after(t)
                rolled_back = True
            gl_guess = st.left.reinit_guess(img_l, feats("left", img_l))
            gr_guess = (
                st.right.reinit_guess(img_r, feats("right", img_r))
                if st.right is not None
                else None
            )
            if gl_guess is not None and (st.right is None or gr_guess is not None):
                res = _track_body(st, img_l, img_r, t, cfg, calibration, gl_guess, gr_guess)
                if res[0]:
                    st.left.commit(np.where(res[3][:, None], res[7], np.nan), t)
                    if st.right is not None:
                        st.right.commit(np.where(res[3][:, None], res[8], np.nan), t)
        if res is None:  # lost, and no SIFT guess either
            res = _failed_pose(d, n)
        ok_pose, Rm, tv, inl, rms, cur, cov, pl, pr, zn = res
        if not ok_pose:
            flag |= FRAME_FLAGS["tracking_failed"]
            for tr in (st.left, st.right):  # predict the next frame from the last good ones
                if tr is not None:
                    tr.history = [h for h in tr.history if h[0] != t]
        poi = Rm @ st.point_of_interest + tv
        n_in = int(np.sum(inl))
        if cov is not None:
            pu = np.sqrt(np.einsum("nii->ni", cov))
        else:
            pu = np.full((n, d), st.sigma_px[:, None] if d == 2 else np.nan)
        if ok_pose:
            # the pose's uncertainty (rotation and translation, from the points' covariances
            # or the fit's residuals, whichever is larger) carried to the point of interest:
            # a point away from the subsets moves with the rotation's uncertainty times its
            # lever arm, which the centroid's uncertainty alone misses. At least the fit's
            # scatter on every axis (stereo: shared by the three axes; the in-plane residuals
            # are far below it, while the in-plane errors are not)
            cov_q = st.point_cov(cov)
            u = pose_point_uncertainty(st.ref3d, cur, Rm, tv, inl, st.point_of_interest, cov_q)
            scatter = rms**2 / (3 if st.right is not None else 1) / max(n_in - 1, 1)
            u = np.sqrt(np.maximum(np.square(u), scatter))
        else:
            u = np.full(d, rms / np.sqrt(max(n_in - 1, 1)))
        _append_row(
            st,
            Rm,
            poi,
            u,
            n_in,
            rms,
            cur.astype(np.float32),
            pu.astype(np.float32),
            zn.astype(np.float32),
            int(lost and retry),
        )
    return flag, rolled_back


def _failed_pose(d: int, n: int) -> tuple:
    """What :func:`_body_pose` gives for a body that could not be tracked."""
    nan = np.full(d, np.nan)
    return (False, np.full((d, d), np.nan), nan, np.zeros(n, bool), np.nan,
            np.full((n, d), np.nan), None, None, None, np.full(n, np.nan))  # fmt: skip


def _append_row(st, Rm, poi, u, n_in, rms, cur, cur_u, zncc, reinit=0) -> None:
    row = st.rows
    for key, val in (
        ("reinit", reinit),
        ("R", Rm),
        ("poi", poi),
        ("poi_u", u),
        ("n", n_in),
        ("rms", rms),
        ("points", cur),
        ("points_u", cur_u),
        ("zncc", zncc),
    ):
        row.setdefault(key, []).append(val)


class _Immediate:
    """Runs a call at once; ``result()`` as for a future (tracking without a thread pool)."""

    def __init__(self, fn, *args) -> None:
        self._value = fn(*args)

    def result(self):
        return self._value


def _track_body(st, img_l, img_r, t, cfg, calibration, guess_l=None, guess_r=None):
    """Correlate one body in both cameras, triangulate and fit its pose."""
    left = st.left.track(img_l, point_guess=guess_l, t=t)
    right = st.right.track(img_r, point_guess=guess_r, t=t) if st.right is not None else None
    return _body_pose(st, left, right, cfg, calibration)


def _body_pose(st, left, right, cfg, calibration):
    """Triangulate the body's tracked subsets (stereo) and fit its rigid pose."""
    pl, zl, gl = left
    pr, cov = None, None
    zn = zl
    if right is not None:
        pr, zr, gr = right
        good = gl & gr
        zn = np.fmin(zl, zr)
        pl2 = np.where(good[:, None], pl, np.nan)
        pr2 = np.where(good[:, None], pr, np.nan)
        cur, cov, _ = triangulate(calibration, pl2, pr2, sigma_px=st.sigma_px)
    else:
        good = gl
        cur = np.where(good[:, None], pl, np.nan)
    d = st.ref3d.shape[1]
    cov_q = st.point_cov(cov)
    cov_p = cov_q if cov is None else st.ref_cov  # one camera: the reference pixels alike
    try:
        # an outlier lies beyond the fit's MAD limit and beyond its own uncertainty: ordinary
        # points stay in, so the inlier set (and the pose) does not flip with sub-noise
        # changes of the matches
        Rm, tv, inl, rms = fit_rigid_robust(
            st.ref3d, cur, min_points=cfg.min_points, cov_p=cov_p, cov_q=cov_q
        )
    except BadInputError:
        nan = np.full(d, np.nan)
        return False, np.full((d, d), np.nan), nan, good & False, np.nan, cur, cov, pl, pr, zn
    return True, Rm, tv, inl, rms, cur, cov, pl, pr, zn
