"""Footage to body motion: stereo (or single-camera) tracking of rigid bodies in rig videos.

Pipeline (``track_footage``)
---------------------------
1. The first frame of each camera is the reference. Each body's region of interest (a polygon
   in the left reference image, from a small TOML file) is filled with a grid of subsets.
2. Stereo correspondence at the reference: SIFT features of the region are matched into the
   right image, kept only if they satisfy the calibrated epipolar constraint (< 2 px), and a
   RANSAC homography gives every subset an initial guess (position and affine gradients); the
   2D engine (:class:`jointwear.dic.SubsetCorrelator`, affine IC-GN) refines it. Matches with an
   epipolar distance above ``max_epipolar_px`` or low ZNCC are discarded. The matched pairs are
   triangulated (undistorted) into the body's reference 3D points.
3. Temporal tracking: in every frame each camera's subsets are correlated against that camera's
   reference image (no drift), with the reference subsets preloaded once. Left camera: a
   quadratic extrapolation of the last three frames (a body-wide affine fitted to the
   extrapolated points), corrected by phase correlation of the warped reference crop and then by
   the affine map of 12 probe subsets, so fast bodies (1 m/s, 80 px per frame) are followed.
   Right camera: the left matches of the same frame carried to the right image at extrapolated
   depths (sub-pixel guesses). The B-spline coefficients are computed only around the subsets,
   in place from the stored frame.
4. Per frame and body: triangulation, robust rigid fit (3D; planar 2D without stereo) of the
   current points to the reference points -> pose; the body-fixed point of interest (follower
   centre of mass, journal cap centre) is moved with the pose. Velocities come from a
   Savitzky–Golay differentiator on the actual frame times (window 9, order 5 by default).
5. Frames are decoded ahead in a background thread and processed in order (bounded memory:
   the reference images, a few frames per camera and the per-frame results are held); the
   trackers run in two threads, the left ones of frame k + 1 beside the right ones and the
   poses of frame k. The result is written after each chunk when an output path is given, so an
   interrupted run keeps what was computed; ``workers > 1`` runs chunks in processes instead.
"""

from __future__ import annotations

import json
import os
import time as _time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, Literal

import numpy as np
import xarray as xr

from jointwear.dic._calib import StereoCalibration
from jointwear.dic._interp import prefilter_region
from jointwear.dic._rigid import fit_rigid_robust, rotation_angle_z, time_derivative
from jointwear.dic._stereo import epipolar_distance, triangulate
from jointwear.dic._video import FrameSource, check_stereo_pair, open_frames, prefetch
from jointwear.errors import BadInputError, ParameterError
from jointwear.params import from_mapping, read_toml

__all__ = [
    "BodySpec",
    "TrackConfig",
    "read_bodies",
    "track_footage",
    "FRAME_FLAGS",
]

#: Frame quality flags (bit mask) of the ``frame_flag`` output variable.
FRAME_FLAGS = {
    "ok": 0,
    "duplicated": 1,
    "after_gap": 2,
    "tracking_failed": 4,
    "crank_step_gap": 8,
}


@dataclass(frozen=True, eq=False)
class BodySpec:
    """A tracked rigid body.

    Parameters
    ----------
    name : str
        Body name (``follower``, ``journal``, ``crank``, ...).
    role : {"follower", "journal", "bearing", "crank", "other"}
        What the body is: the follower's centroid velocity, the journal's displacement and the
        crank's angle go into the contract variables; with a journal and a bearing (whose
        ``centroid`` is the bearing centre) the journal's offset in the bearing frame is given.
    polygon : list of [x, y]
        Region of interest in the left reference image [pixel] (3 or more vertices).
    centroid : [x, y, z] or None
        Body-fixed point whose motion is reported, in the world frame at the reference frame
        [m] (the follower's centre of mass). Default: the centroid of the tracked points.
    centroid_mechanism : [x, y, z] or None
        The same in the mechanism frame, used when the calibration's world frame is a board on
        the mechanism plane (the point is shifted by the board origin given in ``world_origin``).
    reference_angle_deg : float
        Crank angle at the reference frame [degree] (crank bodies).
    """

    name: str
    role: Literal["follower", "journal", "bearing", "crank", "other"] = "other"
    polygon: list[list[float]] = field(default_factory=list)
    centroid: list[float] | None = None
    centroid_mechanism: list[float] | None = None
    reference_angle_deg: float = 0.0


@dataclass(frozen=True, eq=False)
class TrackConfig:
    """Options of ``jointwear dic track`` (TOML table ``[track]``).

    Parameters
    ----------
    subset_size : int
        Subset side [pixel] (odd).
    step : int
        Grid spacing of the subsets in each region [pixel].
    chunk_size : int
        Frames per processing chunk (results are saved after each chunk).
    zncc_min : float
        Matches below this ZNCC are discarded.
    max_epipolar_px : float
        Stereo matches farther from the epipolar line are discarded [pixel].
    min_points : int
        Fewest valid points for a body's pose in a frame (fewer: the frame is flagged).
    velocity_window, velocity_order : int
        Savitzky–Golay differentiator (samples, polynomial degree).
    sigma_px : float
        Standard uncertainty of one subset match [pixel] used for the propagated uncertainty
        (0: estimated from the image noise and the subset's intensity gradients).
    duplicate_threshold : float
        Consecutive frames whose mean absolute difference is below this [grey level] are
        reported as duplicates.
    interpolation : {"cubic", "quintic"}
        B-spline interpolation of the tracked frames. Cubic is about 1.8 times faster; on the
        virtual rig both give the same velocity and out-of-plane errors (the differentiator
        and the image noise dominate), so cubic is the default for footage.
    world_origin : [x, y, z]
        Mechanism-frame position of the world origin (the calibration board's first inner
        corner), used to place ``centroid_mechanism`` [m].
    workers : int
        Processes working on chunks in parallel (1: sequential, tracking carried across
        chunks; >1: each chunk starts from SIFT features of the reference images).
    """

    subset_size: int = 21
    step: int = 10
    chunk_size: int = 50
    zncc_min: float = 0.8
    max_epipolar_px: float = 1.0
    min_points: int = 6
    velocity_window: int = 9
    velocity_order: int = 5
    sigma_px: float = 0.0
    duplicate_threshold: float = 0.05
    interpolation: Literal["cubic", "quintic"] = "cubic"
    world_origin: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])
    workers: int = 1

    def __post_init__(self) -> None:
        if self.subset_size < 7 or self.subset_size % 2 == 0:
            raise ParameterError(
                f"track.subset_size={self.subset_size}: expected an odd integer >= 7"
            )
        if self.interpolation not in ("cubic", "quintic"):
            raise ParameterError(
                f"track.interpolation={self.interpolation!r}: expected 'cubic' or 'quintic'"
            )
        if self.workers < 1:
            raise ParameterError(f"track.workers={self.workers}: expected >= 1")
        if self.step < 1 or self.chunk_size < 1 or self.min_points < 3:
            raise ParameterError("track.step and chunk_size must be >= 1, min_points >= 3")
        if self.velocity_window % 2 == 0 or self.velocity_window <= self.velocity_order:
            raise ParameterError(
                f"track.velocity_window={self.velocity_window} must be odd and larger than "
                f"velocity_order={self.velocity_order}"
            )


def read_bodies(path: str | Path) -> tuple[TrackConfig, list[BodySpec]]:
    """Read the regions-of-interest TOML file: ``[track]`` options and ``[bodies.<name>]``."""
    data = read_toml(path)
    unknown = [k for k in data if k not in ("track", "bodies")]
    if unknown:
        raise ParameterError(
            f"'{path}': unknown table(s) {unknown}; expected [track] and [bodies.<name>]"
        )
    cfg = from_mapping(TrackConfig, data.get("track", {}), where="track")
    bodies = []
    for name, spec in data.get("bodies", {}).items():
        spec = dict(spec)
        body = from_mapping(BodySpec, {"name": name, **spec}, where=f"bodies.{name}")
        if len(body.polygon) < 3:
            raise ParameterError(
                f"'{path}': bodies.{name}.polygon needs at least 3 [x, y] vertices in pixels of "
                "the left reference image"
            )
        bodies.append(body)
    if not bodies:
        raise ParameterError(f"'{path}' defines no [bodies.<name>] with a polygon")
    return cfg, bodies


# ---------------------------------------------------------------------------------------------
def _grid_in_polygon(poly: np.ndarray, half: int, step: int) -> np.ndarray:
    import cv2

    x0, y0 = np.floor(poly.min(0)).astype(int)
    x1, y1 = np.ceil(poly.max(0)).astype(int)
    xs = np.arange(x0 + half, x1 - half + 1, step, dtype=float)
    ys = np.arange(y0 + half, y1 - half + 1, step, dtype=float)
    X, Y = np.meshgrid(xs, ys)
    pts = np.column_stack([X.ravel(), Y.ravel()])
    contour = poly.astype(np.float32).reshape(-1, 1, 2)
    keep = [cv2.pointPolygonTest(contour, (float(x), float(y)), True) >= half for x, y in pts]
    return pts[np.asarray(keep, dtype=bool)] if len(pts) else pts


def _noise_sigma(img: np.ndarray) -> float:
    """Image noise standard deviation (Immerkaer's Laplacian method) [grey level]."""
    import cv2

    k = np.array([[1, -2, 1], [-2, 4, -2], [1, -2, 1]], dtype=np.float32)
    r = cv2.filter2D(img.astype(np.float32), -1, k)[1:-1, 1:-1]
    return float(np.sqrt(np.pi / 2) * np.mean(np.abs(r)) / 6.0)


def _match_sigma(img: np.ndarray, pts: np.ndarray, half: int, noise: float) -> np.ndarray:
    """Cramér–Rao-type match uncertainty per subset: sqrt(2) sigma_n / sqrt(sum grad^2) [pixel]."""
    import cv2

    gx = cv2.Sobel(img, cv2.CV_32F, 1, 0, ksize=3) / 8.0
    gy = cv2.Sobel(img, cv2.CV_32F, 0, 1, ksize=3) / 8.0
    out = np.empty(len(pts))
    for i, (x, y) in enumerate(np.rint(pts).astype(int)):
        sx = gx[y - half : y + half + 1, x - half : x + half + 1]
        sy = gy[y - half : y + half + 1, x - half : x + half + 1]
        g = min(float(np.sum(sx * sx)), float(np.sum(sy * sy)))
        out[i] = np.sqrt(2.0) * noise / np.sqrt(max(g, 1e-12))
    return out


def _sift_features(img: np.ndarray, poly: np.ndarray | None = None, margin: int = 10):
    """SIFT keypoints and descriptors of ``img`` (inside ``poly`` grown by ``margin`` px)."""
    import cv2

    if poly is None:
        return cv2.SIFT_create().detectAndCompute(_as_uint8(img), None)
    # the region's bounding box only (a mask alone still builds the whole image's pyramid)
    h, w = img.shape
    pad = margin + 16
    x0, y0 = np.clip(np.floor(poly.min(0)).astype(int) - pad, 0, None)
    x1, y1 = np.ceil(poly.max(0)).astype(int) + pad + 1
    x1, y1 = min(x1, w), min(y1, h)
    mask = np.zeros((y1 - y0, x1 - x0), np.uint8)
    cv2.fillPoly(mask, [np.rint(poly - [x0, y0]).astype(np.int32)], 255)
    mask = cv2.dilate(mask, np.ones((2 * margin + 1,) * 2, np.uint8))
    kps, desc = cv2.SIFT_create().detectAndCompute(_as_uint8(img[y0:y1, x0:x1]), mask)
    for kp in kps:
        kp.pt = (kp.pt[0] + x0, kp.pt[1] + y0)
    return kps, desc


def _as_uint8(img: np.ndarray) -> np.ndarray:
    """8-bit copy for feature detection: 8-bit as is, deeper images (12/16 bit) scaled by
    their largest value instead of clipped at 255."""
    if img.dtype == np.uint8:
        return img
    a = np.nan_to_num(np.asarray(img, dtype=np.float32))
    top = float(a.max(initial=0.0))
    if top > 255.0:
        a = a * (255.0 / top)
    return np.clip(a, 0, 255).astype(np.uint8)


def _sift_homography(ref_features, target_features, *, calibration=None) -> np.ndarray | None:
    """Homography from a reference region to a target image by SIFT matching (ratio test,
    epipolar filter when ``calibration`` is given) and RANSAC."""
    import cv2

    (k1, d1), (k2, d2) = ref_features, target_features
    if d1 is None or d2 is None or len(k1) < 8 or len(k2) < 8:
        return None
    matches = cv2.BFMatcher(cv2.NORM_L2).knnMatch(d1, d2, k=2)
    good = [m[0] for m in matches if len(m) == 2 and m[0].distance < 0.8 * m[1].distance]
    if len(good) < 8:
        return None
    p1 = np.float64([k1[m.queryIdx].pt for m in good])
    p2 = np.float64([k2[m.trainIdx].pt for m in good])
    if calibration is not None:
        ok = epipolar_distance(calibration, p1, p2) < 3.0
        p1, p2 = p1[ok], p2[ok]
        if len(p1) < 8:
            return None
    H, inl = cv2.findHomography(p1, p2, cv2.RANSAC, 2.0)
    if H is None or inl.sum() < 8:
        return None
    return H


def _homography_guess(H: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """Affine initial guesses (u, du/dx, du/dy, v, dv/dx, dv/dy) from a homography."""
    hp = np.column_stack([pts, np.ones(len(pts))]) @ H.T
    w = hp[:, 2]
    q = hp[:, :2] / w[:, None]
    # Jacobian of the homography at each point
    J = (H[None, :2, :2] - q[:, :, None] * H[None, 2:3, :2]) / w[:, None, None]
    return np.column_stack(
        [
            q[:, 0] - pts[:, 0],
            J[:, 0, 0] - 1,
            J[:, 0, 1],
            q[:, 1] - pts[:, 1],
            J[:, 1, 0],
            J[:, 1, 1] - 1,
        ]
    )


class _CameraBodyTracker:
    """Tracks one body's subsets in one camera against that camera's reference image."""

    def __init__(self, ref: np.ndarray, pts: np.ndarray, cfg: TrackConfig, what: str) -> None:
        from jointwear.dic._api2d import CorrelationParams, SubsetCorrelator

        self.what = what
        self.ref_pts = pts.astype(float)
        h, w = ref.shape
        half = cfg.subset_size // 2
        lo, hi = pts.min(0) - half, pts.max(0) + half
        centre = 0.5 * (lo + hi)
        side = int(np.ceil(np.hypot(*(hi - lo)))) + 2 * half + 16
        side += side % 2
        self.side = side
        self.origin = np.floor(centre - side / 2).astype(int)  # reference crop corner (x, y)
        self.centre = centre
        crop = _crop(ref, self.origin, side)
        self.ref_crop = crop
        params = CorrelationParams(
            subset_size=cfg.subset_size,
            zncc_min=cfg.zncc_min,
            threads=1,  # the trackers of a frame run in parallel threads instead
            search_radius=8,
            interpolation=cfg.interpolation,
        )
        self._workspace: dict = {}  # reused prefilter buffers
        self._probes = _spread_points(self.ref_pts, 12)  # correct predictions (see track)
        self.corr = SubsetCorrelator(crop, points=self.ref_pts - self.origin, params=params)
        self.corr.preload_references()  # the same subsets are matched in every frame
        self._max_shift = float(self.corr._solver_options()[5])
        self.history: list[tuple[float, np.ndarray]] = []  # (time, positions)
        import cv2

        self._fill = float(np.nanmedian(crop))
        filled = np.where(np.isnan(crop), self._fill, crop).astype(np.float32)
        # phase correlation (translation correction of the prediction) on a reduced crop of
        # at most _PC_MAX pixels: the probes and IC-GN need the start within a few pixels
        self._pc_scale = max(2, int(np.ceil(side / _PC_MAX)))
        n_pc = side // self._pc_scale
        self._pc_size = (n_pc, n_pc)
        self._ref_small = cv2.resize(filled, self._pc_size, interpolation=cv2.INTER_AREA)
        self._window = cv2.createHanningWindow(self._pc_size, cv2.CV_32F)
        self.ref_image = ref
        self.polygon = None
        self._ref_features = None

    def _predict(self, t: float) -> np.ndarray:
        """Positions (N, 2) predicted at time ``t`` by Lagrange extrapolation (degree <= 2) of
        the last frames (their real times, so gaps and duplicates are handled)."""
        hist = self.history[-3:]
        if not hist:
            return self.ref_pts.copy()
        ts = np.array([h[0] for h in hist])
        out = np.zeros_like(hist[0][1])
        for j, (tj, Xj) in enumerate(hist):
            w = 1.0
            for m, tm in enumerate(ts):
                if m != j:
                    w *= (t - tm) / (tj - tm) if tj != tm else 0.0
            out += w * Xj
        return out

    def reinit_guess(self, img: np.ndarray, features=None) -> np.ndarray | None:
        """Per-point affine guesses from SIFT features (reference -> img), for lost tracking
        and chunk starts; ``features`` of ``img`` may be passed (shared between bodies)."""
        if self._ref_features is None:
            poly = self.polygon if self.polygon is not None else _hull(self.ref_pts)
            self._ref_features = _sift_features(self.ref_image, poly)
        H = _sift_homography(self._ref_features, features or _sift_features(img))
        return None if H is None else _homography_guess(H, self.ref_pts)

    def track(
        self,
        img: np.ndarray,
        point_guess: np.ndarray | None = None,
        t: float = 0.0,
        predicted: np.ndarray | None = None,
    ):
        """Correlate the subsets in ``img`` (time ``t`` [s]); ``point_guess`` (N, 6) affine
        guesses (reference image coordinates) replace the prediction; ``predicted`` (N, 2)
        positions [pixel] known to a fraction of a pixel (the right camera's, from the left
        camera's matches; NaN where unknown) replace the extrapolation and its corrections.
        Returns positions (N, 2), ZNCC and the ok mask."""
        import cv2

        P = self.ref_pts
        identity = np.hstack([np.eye(2), np.zeros((2, 1))])
        known = None
        if point_guess is not None:
            q0 = P + point_guess[:, [0, 3]]
            A, _ = cv2.estimateAffine2D(P, q0, method=cv2.LMEDS)
            A = identity if A is None else A
        else:
            if predicted is not None:
                known = np.all(np.isfinite(predicted), axis=1)
                if known.sum() < max(3, len(P) // 2):
                    known = None  # too few: the tracker's own prediction instead
            pred = predicted if known is not None else self._predict(t)
            ok = np.all(np.isfinite(pred), axis=1)
            A = None
            if ok.sum() >= 3:
                A = _affine_fit(P[ok], pred[ok])
            A = identity if A is None else A
        # where the reference crop's centre goes, and the current crop
        c_new = A[:, :2] @ self.centre + A[:, 2]
        origin = np.floor(c_new - self.side / 2).astype(int)
        h, w = img.shape
        x0, y0 = int(origin[0]), int(origin[1])
        inside = x0 >= 0 and y0 >= 0 and x0 + self.side <= w and y0 + self.side <= h
        # a crop inside the frame is used in place (no copy); otherwise NaN-padded
        cur = img[y0 : y0 + self.side, x0 : x0 + self.side] if inside else None
        if cur is None:
            cur = _crop(img, origin, self.side)
        shift = np.zeros(2)
        if point_guess is None and known is None and self.history:
            # correct the translation by phase correlation of the warped reference crop
            # (reduced: a correction to a pixel or two is all the IC-GN needs)
            sc = self._pc_scale
            M = A.copy()
            M[:, 2] = (A[:, :2] @ self.origin + A[:, 2] - origin) / sc
            fill = self._fill
            warped = cv2.warpAffine(
                self._ref_small,
                M,
                self._pc_size,
                flags=cv2.INTER_LINEAR,
                borderMode=cv2.BORDER_CONSTANT,
                borderValue=fill,
            )
            if inside:
                b = cv2.resize(cur, self._pc_size, interpolation=cv2.INTER_AREA)
                b = b.astype(np.float32)
            else:
                b = np.where(np.isnan(cur), fill, cur)
                b = cv2.resize(b, self._pc_size, interpolation=cv2.INTER_AREA)
            (dx, dy), resp = cv2.phaseCorrelate(warped, b, self._window)
            if resp > 0.05 and sc * np.hypot(dx, dy) < self.side / 3:
                shift = sc * np.array([dx, dy])
        if point_guess is not None:
            guess = point_guess.astype(float).copy()
        else:
            q = P @ A[:, :2].T + A[:, 2] + shift
            if known is not None:
                q[known] = predicted[known]
            guess = np.column_stack(
                [
                    q[:, 0] - P[:, 0],
                    np.full(len(P), A[0, 0] - 1),
                    np.full(len(P), A[0, 1]),
                    q[:, 1] - P[:, 1],
                    np.full(len(P), A[1, 0]),
                    np.full(len(P), A[1, 1] - 1),
                ]
            )
        # displacements in crop coordinates
        off = origin - self.origin
        guess[:, 0] -= off[0]
        guess[:, 3] -= off[1]
        # the spline is needed only where the warped subsets can reach: their warped
        # half-width, the largest correction the solver may add and the spline's support
        centres = self.corr.centres + guess[:, [0, 3]]
        gx_row = np.abs(1.0 + guess[:, 1]) + np.abs(guess[:, 2])
        gy_row = np.abs(guess[:, 4]) + np.abs(1.0 + guess[:, 5])
        reach = self.corr.params.half * float(np.nanmax(np.maximum(gx_row, gy_row), initial=1.0))
        probes = point_guess is None and known is None
        radius = reach + self._max_shift + 4.0 + (_PROBE_ALLOWANCE if probes else 0.0)
        window = (x0, y0, self.side, self.side) if inside else None

        def spline(centres):
            return prefilter_region(
                img if inside else cur,
                self.corr.params.interpolation,
                centres,
                radius,
                workspace=self._workspace,
                window=window,
            )

        spl = spline(centres)
        if probes:
            guess, moved = self._probe_correction(spl, guess)
            if moved > _PROBE_ALLOWANCE:  # beyond the prefiltered margin: prefilter again
                spl = spline(self.corr.centres + guess[:, [0, 3]])
        res = self.corr.match(spl, initial_guess=guess)
        pos = np.column_stack(
            [P[:, 0] + res.params[:, 0] + off[0], P[:, 1] + res.params[:, 6] + off[1]]
        )
        good = res.ok & (res.zncc >= self.corr.params.zncc_min)
        pos[~good] = np.nan
        return pos, res.zncc, good

    def _probe_correction(self, spl, guess: np.ndarray) -> np.ndarray:
        """Correct the predicted guesses by the affine map that takes a few well-spread probe
        subsets from their guesses to their matches.

        The prediction (extrapolation plus a phase-correlation shift) is typically a few pixels
        off, mostly as a small rotation that a translation cannot fix; corrected, the other
        subsets start within a fraction of a pixel and converge in two or three iterations
        instead of five or six. Returns the guesses and the largest correction [pixel].
        """

        idx = self._probes
        if len(idx) < 4:
            return guess, 0.0
        sub = self.corr._match_some(spl, guess, idx)
        ok = sub.ok & (sub.zncc >= self.corr.params.zncc_min)
        if ok.sum() < 4:
            return guess, 0.0
        C = self.corr.centres
        g_pos = C[idx] + guess[idx][:, [0, 3]]
        r_pos = C[idx] + sub.params[:, [0, 6]]
        M = _affine_fit(g_pos[ok], r_pos[ok])
        if M is None:
            return guess, 0.0
        pos = C + guess[:, [0, 3]]
        new_pos = pos @ M[:, :2].T + M[:, 2]
        moved = float(np.nanmax(np.abs(new_pos - pos), initial=0.0))
        if not moved <= 4.0 * self._max_shift:  # not a correction: a failed fit
            return guess, 0.0
        # compose the deformation gradients: (I + grad_new) = M (I + grad_guess)
        J = np.empty((len(guess), 2, 2))
        J[:, 0, 0], J[:, 0, 1] = 1.0 + guess[:, 1], guess[:, 2]
        J[:, 1, 0], J[:, 1, 1] = guess[:, 4], 1.0 + guess[:, 5]
        Jn = M[:, :2] @ J
        out = np.column_stack(
            [
                new_pos[:, 0] - C[:, 0],
                Jn[:, 0, 0] - 1.0,
                Jn[:, 0, 1],
                new_pos[:, 1] - C[:, 1],
                Jn[:, 1, 0],
                Jn[:, 1, 1] - 1.0,
            ]
        )
        out[idx[ok]] = sub.params[ok][:, [0, 1, 2, 6, 7, 8]]  # probes start from their match
        return out, moved

    def commit(self, pos: np.ndarray, t: float) -> None:
        """Remember the positions found at time ``t`` [s] for the next prediction."""

        ok = np.all(np.isfinite(pos), axis=1)
        if ok.sum() >= 3:
            filled = pos.copy()
            A = _affine_fit(self.ref_pts[ok], pos[ok])
            if A is not None:
                filled[~ok] = self.ref_pts[~ok] @ A[:, :2].T + A[:, 2]
            # kept in time order; a frame tracked again (re-initialised) replaces its entry
            hist = [h for h in self.history if h[0] != t] + [(t, filled)]
            self.history = sorted(hist, key=lambda h: h[0])[-3:]

    def forget_after(self, t: float) -> None:
        """Drop what was committed for frames later than ``t`` [s] (a speculative frame
        tracked before an earlier one had to be re-initialised)."""
        self.history = [h for h in self.history if h[0] <= t]

    def track_and_commit(self, img: np.ndarray, t: float, predicted=None):
        """:meth:`track`, then remember the matched positions for the next prediction."""
        pos, zncc, good = self.track(img, t=t, predicted=predicted)
        self.commit(pos, t)
        return pos, zncc, good


def _affine_fit(P: np.ndarray, Q: np.ndarray) -> np.ndarray | None:
    """Affine map (2, 3) with ``Q ~ A [P; 1]``: least squares, then again without the points
    whose residual exceeds 3 times the median (and 0.5 pixel) - the rare wrong match - which
    is all these well-matched point sets need (a fraction of LMedS's cost). None when the
    points do not determine a map."""
    # normal equations on coordinates centred on P's mean (well conditioned, and a 3 x 3
    # solve is far cheaper than lstsq's SVD for these few-hundred-point sets)
    c = P.mean(axis=0)
    X = np.column_stack([P - c, np.ones(len(P))])
    keep = np.ones(len(P), dtype=bool)
    A = None
    for _ in range(2):
        if keep.sum() < 3:
            return A
        Xk = X[keep]
        N = Xk.T @ Xk
        if not abs(np.linalg.det(N)) > 1e-12 * np.trace(N) ** 3:  # collinear points
            return A
        sol = np.linalg.solve(N, Xk.T @ Q[keep])  # (3, 2)
        A = sol.T.copy()
        A[:, 2] -= A[:, :2] @ c  # back to uncentred coordinates
        res = np.hypot(*(X @ sol - Q).T)
        keep = res <= max(3.0 * float(np.median(res[keep])), 0.5)
    return A


#: side of the reduced crops of the phase correlation [pixel]
_PC_MAX = 160

#: largest correction of a prediction by the probe subsets [pixel] (prefiltered margin)
_PROBE_ALLOWANCE = 6.0


def _spread_points(pts: np.ndarray, k: int) -> np.ndarray:
    """Indices of ``k`` well-spread points (farthest-point sampling from the centroid's
    nearest); none when there are fewer than ``3 k`` points (the probes would not pay)."""
    n = len(pts)
    if n < 3 * k:
        return np.zeros(0, dtype=np.int64)
    chosen = [int(np.argmin(np.hypot(*(pts - pts.mean(0)).T)))]
    d = np.hypot(*(pts - pts[chosen[0]]).T)
    for _ in range(k - 1):
        j = int(np.argmax(d))
        chosen.append(j)
        d = np.minimum(d, np.hypot(*(pts - pts[j]).T))
    return np.asarray(chosen, dtype=np.int64)


def _hull(pts: np.ndarray) -> np.ndarray:
    import cv2

    return cv2.convexHull(pts.astype(np.float32)).reshape(-1, 2).astype(float)


def _crop(img: np.ndarray, origin: np.ndarray, side: int) -> np.ndarray:
    """``side`` x ``side`` crop at ``origin`` (x, y); outside the image is NaN."""
    h, w = img.shape
    out = np.full((side, side), np.nan, dtype=np.float32)
    x0, y0 = int(origin[0]), int(origin[1])
    sx0, sy0 = max(x0, 0), max(y0, 0)
    sx1, sy1 = min(x0 + side, w), min(y0 + side, h)
    if sx1 > sx0 and sy1 > sy0:
        out[sy0 - y0 : sy1 - y0, sx0 - x0 : sx1 - x0] = img[sy0:sy1, sx0:sx1]
    return out


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


def _body_point(spec: BodySpec, ref: np.ndarray, cfg: TrackConfig) -> np.ndarray:
    if spec.centroid is not None:
        return np.asarray(spec.centroid, dtype=float)
    if spec.centroid_mechanism is not None and ref.shape[1] == 3:
        return np.asarray(spec.centroid_mechanism, dtype=float) - np.asarray(cfg.world_origin)
    return np.nanmean(ref, axis=0)


def track_footage(
    left: str | Path | FrameSource,
    right: str | Path | FrameSource | None = None,
    *,
    bodies: list[BodySpec],
    calibration: StereoCalibration | None = None,
    config: TrackConfig | None = None,
    fps: float | None = None,
    max_frames: int | None = None,
    out: str | Path | None = None,
    progress: bool = False,
    inputs: tuple = (),
    resume: bool = False,
) -> xr.Dataset:
    """Track rigid bodies through rig footage; body poses, follower velocity, journal motion.

    Parameters
    ----------
    left, right : path or FrameSource
        Video files or image folders of the two cameras (``right`` None: single camera,
        planar motion in pixels only).
    bodies : list of BodySpec
        Regions of interest (see :func:`read_bodies`).
    calibration : StereoCalibration
        Required with two cameras; positions are in its world frame [m].
    config : TrackConfig
    fps : float, optional
        Frame rate [1/s] (image sequences; overrides a video's rate).
    max_frames : int, optional
        Process only the first frames.
    out : path, optional
        netCDF written after every chunk (atomic; a chunk's write is skipped while writes would
        take more than a tenth of the run): a run that stops keeps what was computed (``status``
        attribute says where and why it stopped).
    progress : bool
        Progress bar on stderr.
    inputs : tuple of path
        Input files recorded (with sha256) in the output's provenance.
    resume : bool
        Continue the partial result in ``out`` (a run that was interrupted or stopped): its
        frames are kept and tracking restarts at the next frame from SIFT features of the
        reference images, as a parallel chunk does. The footage, bodies and tracking options
        must be those of the partial run (``workers``/``chunk_size`` may differ); otherwise a
        :class:`~jointwear.errors.BadInputError` says what differs. A complete ``out`` is
        returned as it is.

    Returns
    -------
    Dataset
        ``follower_position``, ``follower_velocity`` (time, axis) [m, m/s] with ``_u``
        uncertainties; ``journal_position``/``journal_displacement`` (time, axis) [m];
        ``crank_angle`` (time) [rad] when a crank is tracked; per body ``<body>_position``,
        ``<body>_rotation`` and ``<body>_points``; ``frame_flag``; attrs with the duplicated and
        dropped frames found.
    """
    cfg = config or TrackConfig()
    L = left if isinstance(left, FrameSource) else open_frames(left, fps=fps, what="left footage")
    R = None
    if right is not None:
        R = (
            right
            if isinstance(right, FrameSource)
            else open_frames(right, fps=fps, what="right footage")
        )
        check_stereo_pair(L, R)
        if calibration is None:
            raise BadInputError(
                "two cameras need a stereo calibration (calibration=..., CLI --calibration)"
            )
        for name, src in (("left", L), ("right", R)):
            cam_size = calibration.cameras[name].image_size
            if tuple(src.size) != tuple(cam_size):
                raise BadInputError(
                    f"{name} footage '{src.path}' has {src.size[0]}x{src.size[1]} pixel frames but "
                    f"the calibration's {name} camera is {cam_size[0]}x{cam_size[1]}; use the "
                    "calibration made for these cameras at this resolution"
                )
    n_total = L.n_frames if max_frames is None else min(L.n_frames, max_frames)
    t_start = _time.perf_counter()
    (_, t0, ref_l), ref_r = _reference_frames(L, R)
    previous = _load_partial(out, L, R, cfg, bodies) if resume else None
    if previous is not None and previous.attrs.get("status") == "complete":
        return previous
    states = _setup_states(L, R, bodies, calibration, cfg, ref_l, ref_r)
    times: list[float] = []
    flags: list[int] = []
    duplicates: list[int] = []
    if previous is not None:
        _restore_rows(previous, states, times, flags, duplicates, R is not None, out)
    start = len(times)
    if start >= n_total:
        return _finish_result(
            states, times, flags, duplicates, L, R, cfg, calibration, out, inputs, bodies, t_start
        )
    from jointwear.progress import progress_bar

    # partial results are rewritten whole after a chunk, so on a long recording each write
    # costs more; a chunk's write is skipped while the previous write took more than
    # 1/_CHECKPOINT_OVERHEAD of the time since, keeping the writes' share of the run bounded
    last_write = {"end": _time.perf_counter(), "cost": 0.0}

    def save(status: str, *, force: bool = False) -> None:
        if out is None or not times:
            return
        now = _time.perf_counter()
        if not force and (now - last_write["end"]) * _CHECKPOINT_OVERHEAD < last_write["cost"]:
            return
        ds = _assemble(states, times, flags, duplicates, L, R, cfg, calibration, status)
        _write(ds, out, inputs, cfg, bodies)
        last_write["end"] = _time.perf_counter()
        last_write["cost"] = last_write["end"] - now

    # one process: the cameras' and bodies' trackers of a frame run in threads (their
    # kernels release the GIL); several processes: one thread each
    n_threads = min(2, os.cpu_count() or 1) if cfg.workers <= 1 else 1
    pool = ThreadPoolExecutor(max_workers=n_threads) if n_threads > 1 else None
    try:
        with progress_bar("tracking frames", n_total, enabled=progress) as bar:
            task = bar.tasks[0].id
            bar.update(task, advance=start)
            if cfg.workers <= 1:
                # decoding overlaps; a resumed run starts one frame early for the duplicate check
                frames = prefetch(_paired_frames(L, R, max(start - 1, 0), n_total))
                for i, t, flag, dup in _run_frames(
                    states, frames, cfg, calibration, pool, first=start, reinit_first=start > 0
                ):
                    flags.append(flag)
                    times.append(t)
                    if dup:
                        duplicates.append(i)
                    bar.update(task, advance=1)
                    if len(times) % cfg.chunk_size == 0:
                        save("partial")
            else:
                import multiprocessing
                from concurrent.futures import ProcessPoolExecutor

                ranges = [
                    (a, min(a + cfg.chunk_size, n_total))
                    for a in range(start, n_total, cfg.chunk_size)
                ]
                # spawn: forking a process that already runs OpenMP/numba threads is unsafe
                ctx = multiprocessing.get_context("spawn")
                with ProcessPoolExecutor(max_workers=cfg.workers, mp_context=ctx) as pool:
                    futures = [
                        pool.submit(_run_chunk, L, R, bodies, calibration, cfg, a, b)
                        for a, b in ranges
                    ]
                    for fut in futures:
                        part = fut.result()
                        for st in states:
                            for key, vals in part["rows"][st.spec.name].items():
                                st.rows.setdefault(key, []).extend(vals)
                        times.extend(part["times"])
                        flags.extend(part["flags"])
                        duplicates.extend(part["duplicates"])
                        bar.update(task, advance=len(part["times"]))
                        if part["error"]:
                            for other in futures:
                                other.cancel()  # chunks not started yet
                            raise BadInputError(part["error"])
                        save("partial")
    except (BadInputError, KeyboardInterrupt) as exc:
        if pool is not None:
            pool.shutdown(cancel_futures=True)
            pool = None
        status = f"stopped after {len(times)} frames: {exc}"
        if out is not None and times:
            save(status, force=True)
            raise BadInputError(
                f"{exc} - the {len(times)} frames processed before are saved in '{out}'"
            ) from None
        raise
    finally:
        if pool is not None:
            pool.shutdown()
    return _finish_result(
        states, times, flags, duplicates, L, R, cfg, calibration, out, inputs, bodies, t_start
    )


def _finish_result(
    states, times, flags, duplicates, L, R, cfg, calibration, out, inputs, bodies, t_start
) -> xr.Dataset:
    result = _assemble(states, times, flags, duplicates, L, R, cfg, calibration, "complete")
    result.attrs["wall_time_s"] = _time.perf_counter() - t_start
    result.attrs["workers"] = cfg.workers
    if out is not None:
        _write(result, out, inputs, cfg, bodies)
    return result


#: tracking options that may change between a partial run and its resumption
_RESUMABLE_CHANGES = ("workers", "chunk_size")


def _load_partial(out, L: FrameSource, R: FrameSource | None, cfg, bodies) -> xr.Dataset | None:
    """The partial result in ``out`` to resume, after checking it belongs to this run."""
    from jointwear import io

    if out is None:
        raise BadInputError("resume needs the output file of the interrupted run (out=..., --out)")
    out = Path(out)
    if not out.exists():
        return None  # nothing to resume: a fresh run
    prev = io.load(out)
    what = f"'{out}'"
    if prev.attrs.get("title") != "jointwear rig footage tracking":
        raise BadInputError(f"{what} is not a `jointwear dic track` result; cannot resume it")
    problems = []
    for name, src in (("left", L), ("right", R)):
        want = str(src.path) if src is not None else ""
        if str(prev.attrs.get(f"{name}_footage", "")) != want:
            problems.append(
                f"{name} footage was '{prev.attrs.get(f'{name}_footage', '')}', now '{want}'"
            )
    old = io.parse_provenance(prev).get("parameters", {})
    new = json.loads(json.dumps(_parameters(cfg, bodies)))  # as the file records them
    old_track = {k: v for k, v in old.get("track", {}).items() if k not in _RESUMABLE_CHANGES}
    new_track = {k: v for k, v in new["track"].items() if k not in _RESUMABLE_CHANGES}
    for key in sorted(set(old_track) | set(new_track)):
        if old_track.get(key) != new_track.get(key):
            problems.append(f"track.{key} was {old_track.get(key)!r}, now {new_track.get(key)!r}")
    if old.get("bodies") != new["bodies"]:
        problems.append("the bodies (regions of interest) differ")
    if problems:
        raise BadInputError(
            f"cannot resume {what}: it was made with other inputs or options ("
            + "; ".join(problems)
            + "); run again with the same ones, or without resume to start afresh"
        )
    return prev


def _restore_rows(prev: xr.Dataset, states, times, flags, duplicates, stereo: bool, out) -> None:
    """Fill the states' rows, times, flags and duplicates from a partial result."""
    img = "" if stereo else "_image"
    for st in states:
        name = st.spec.name
        pts = prev[f"{name}_points"].values
        n_ref = len(st.ref3d)
        if pts.shape[1] != n_ref or not np.allclose(
            pts[0],
            st.ref3d,
            atol=1e-6 * max(1.0, float(np.nanmax(np.abs(st.ref3d)))),
            equal_nan=True,
        ):
            raise BadInputError(
                f"cannot resume '{out}': body '{name}' has {pts.shape[1]} subsets there but "
                f"{n_ref} (or other reference positions) now; the reference frames or the "
                "calibration differ - run again without resume"
            )
        columns = {
            "R": prev[f"{name}_rotation"].values,
            "poi": prev[f"{name}{img}_position"].values,
            "poi_u": prev[f"{name}{img}_position_u"].values,
            "n": prev[f"{name}_n_points"].values,
            "rms": prev[f"{name}_fit_rms"].values,
            "points": pts,
            "points_u": prev[f"{name}_points_u"].values,
            "zncc": prev[f"{name}_zncc"].values,
        }
        st.rows = {key: list(val) for key, val in columns.items()}
    times.extend(float(t) for t in prev["time"].values)
    raw = FRAME_FLAGS["duplicated"] | FRAME_FLAGS["tracking_failed"]  # the others are derived
    flags.extend(int(f) & raw for f in prev["frame_flag"].values)
    dup = prev.attrs.get("duplicated_frames", "[]")
    duplicates.extend(int(i) for i in (json.loads(dup) if isinstance(dup, str) else dup))


#: largest share of a tracking run spent writing partial results (see track_footage's save)
_CHECKPOINT_OVERHEAD = 0.1


def _reference_frames(L: FrameSource, R: FrameSource | None):
    first_l = next(L.frames(0, 1))
    ref_r = next(R.frames(0, 1))[2] if R is not None else None
    return first_l, ref_r


def _paired_frames(L: FrameSource, R: FrameSource | None, start: int, stop: int):
    """Frames of both cameras in their stored type (regions are cropped before conversion)."""
    gen_l = L.frames(start, stop, native=True)
    if R is None:
        for i, t, img in gen_l:
            yield i, t, img, None
        return
    for (i, t, img), (_, _, img_r) in zip(gen_l, R.frames(start, stop, native=True), strict=False):
        yield i, t, img, img_r


def _is_duplicate(img: np.ndarray, prev: np.ndarray, cfg: TrackConfig) -> bool:
    """Mean absolute difference on every 8th pixel of every 8th row (20 000 samples in a
    megapixel frame) below the threshold."""
    a = img[::8, ::8].astype(np.float32)
    return float(np.mean(np.abs(a - prev[::8, ::8]))) < cfg.duplicate_threshold


def _run_chunk(L, R, bodies, calibration, cfg, start: int, stop: int) -> dict:
    """Worker: track frames ``start <= i < stop`` independently (SIFT start, own references)."""
    (_, _, ref_l), ref_r = _reference_frames(L, R)
    states = _setup_states(L, R, bodies, calibration, cfg, ref_l, ref_r)
    times, flags, duplicates = [], [], []
    error = ""
    try:
        frames = _paired_frames(L, R, max(start - 1, 0), stop)
        # the frame before the chunk serves only the duplicate check
        for i, t, flag, dup in _run_frames(
            states, frames, cfg, calibration, None, first=start, reinit_first=start > 0
        ):
            flags.append(flag)
            times.append(t)
            if dup:
                duplicates.append(i)
    except BadInputError as exc:
        error = str(exc)
    return {
        "times": times,
        "flags": flags,
        "duplicates": duplicates,
        "rows": {st.spec.name: st.rows for st in states},
        "error": error,
    }


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
    right_features = pool.submit(_sift_features, ref_r) if pool is not None else None
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
            H = _sift_homography(
                _sift_features(ref_l, poly), right_features.result(), calibration=calibration
            )
            if H is None:
                raise BadInputError(
                    f"body '{spec.name}': its region could not be found in the right reference "
                    "image (too few SIFT matches consistent with the calibration's epipolar "
                    "geometry); check that both cameras see the speckle pattern and that the "
                    "calibration belongs to this rig"
                )
            guess = _homography_guess(H, pts)
            pos_r, zn, good = lt.track(ref_r, point_guess=guess)
            epi = epipolar_distance(calibration, pts, np.where(np.isfinite(pos_r), pos_r, 0.0))
            good &= epi < cfg.max_epipolar_px
            if good.sum() < cfg.min_points:
                raise BadInputError(
                    f"body '{spec.name}': only {good.sum()} of {len(pts)} subsets matched between "
                    f"the left and right reference images (ZNCC >= {cfg.zncc_min}, epipolar "
                    f"distance < {cfg.max_epipolar_px} px); check the calibration and the ROI"
                )
            pts, pos_r, sig = pts[good], pos_r[good], sig[good]
            lt = _CameraBodyTracker(ref_l, pts, cfg, f"left/{spec.name}")
            rt = _CameraBodyTracker(ref_r, pos_r, cfg, f"right/{spec.name}")
            X, _, _ = triangulate(calibration, pts, pos_r, sigma_px=sig)
            ref = X
        else:
            rt = None
            ref = pts.copy()
        lt.polygon = poly
        states.append(_BodyState(spec, lt, rt, ref, sig, _body_point(spec, ref, cfg)))
    return states


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
        if res is None or not res[0]:
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
        if st.right is not None and ok_pose:
            # propagated: mean triangulation covariance / n, or the fit scatter if larger
            cov_mean = np.nanmean(cov[inl], axis=0) / max(n_in, 1)
            u = np.sqrt(np.maximum(np.diag(cov_mean), (rms**2 / 3) / max(n_in - 1, 1)))
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
        )
    return flag, rolled_back


def _failed_pose(d: int, n: int) -> tuple:
    """What :func:`_body_pose` gives for a body that could not be tracked."""
    nan = np.full(d, np.nan)
    return (False, np.full((d, d), np.nan), nan, np.zeros(n, bool), np.nan,
            np.full((n, d), np.nan), None, None, None, np.full(n, np.nan))  # fmt: skip


def _append_row(st, Rm, poi, u, n_in, rms, cur, cur_u, zncc) -> None:
    row = st.rows
    for key, val in (
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
    try:
        Rm, tv, inl, rms = fit_rigid_robust(st.ref3d, cur, min_points=cfg.min_points)
    except BadInputError:
        nan = np.full(d, np.nan)
        return False, np.full((d, d), np.nan), nan, good & False, np.nan, cur, cov, pl, pr, zn
    return True, Rm, tv, inl, rms, cur, cov, pl, pr, zn


def _parameters(cfg: TrackConfig, bodies) -> dict[str, Any]:
    """The parameters recorded in a tracking result's provenance (and checked on resume)."""
    return {"track": asdict(cfg), "bodies": [asdict(b) for b in bodies]}


def _write(ds: xr.Dataset, out, inputs, cfg, bodies) -> None:
    from jointwear import io

    io.save(
        ds,
        out,
        inputs=inputs,
        parameters=_parameters(cfg, bodies),
        source="jointwear (dic.track)",
    )


def _assemble(states, times, flags, duplicates, L, R, cfg, calibration, status) -> xr.Dataset:
    from jointwear import conventions as C

    t = np.asarray(times, dtype=float)
    stereo = R is not None
    unit = "m" if stereo else "pixel"
    axes = ["x", "y", "z"] if stereo else ["x", "y"]
    flag_arr = np.asarray(flags, dtype=np.int8)
    # gaps in the frame times (dropped frames)
    dt = np.diff(t)
    nominal = 1.0 / L.fps
    gaps = np.flatnonzero(dt > 1.5 * nominal) + 1
    flag_arr[gaps] |= FRAME_FLAGS["after_gap"]
    dropped = int(np.sum(np.rint(dt[dt > 1.5 * nominal] / nominal) - 1)) if len(dt) else 0
    data: dict[str, Any] = {}
    coords = {
        "time": ("time", t, {"units": "s", "long_name": C.COORDINATES["time"][1]}),
        "axis": ("axis", axes, {"long_name": "vector component"}),
    }
    valid_time = ~(flag_arr & FRAME_FLAGS["duplicated"]).astype(bool)
    attrs_extra: dict[str, float] = {}
    for st in states:
        rows = st.rows
        name = st.spec.name
        img = "" if stereo else "_image"  # one camera: pixels, not the contract's metres
        poi = np.asarray(rows["poi"], dtype=float)
        poi_u = np.asarray(rows["poi_u"], dtype=float)
        poi_v = np.where(valid_time[:, None], poi, np.nan)
        vel, gain = time_derivative(t, poi_v, window=cfg.velocity_window, order=cfg.velocity_order)
        vel_u = gain[:, None] * np.nanmedian(poi_u, axis=0)[None, :]
        data[f"{name}{img}_position"] = (
            ("time", "axis"),
            poi,
            {
                "units": unit,
                "long_name": f"position of the {name}'s point of interest (world frame)",
                "ancillary_variables": f"{name}{img}_position_u",
            },
        )
        data[f"{name}{img}_position_u"] = (
            ("time", "axis"),
            poi_u,
            {"units": unit, "long_name": f"standard uncertainty of {name}{img}_position"},
        )
        data[f"{name}{img}_velocity"] = (
            ("time", "axis"),
            vel,
            {"units": f"{unit} s-1", "long_name": f"velocity of the {name}'s point of interest"},
        )
        data[f"{name}_n_points"] = (
            "time",
            np.asarray(rows["n"]),
            {"units": "1", "long_name": f"subsets used in the {name}'s rigid fit"},
        )
        data[f"{name}_fit_rms"] = (
            "time",
            np.asarray(rows["rms"], dtype=float),
            {"units": unit, "long_name": f"RMS residual of the {name}'s rigid fit"},
        )
        d = st.ref3d.shape[1]
        data[f"{name}_rotation"] = (
            ("time", f"{name}_row", f"{name}_col"),
            np.asarray(rows["R"], dtype=float),
            {"units": "1", "long_name": f"rotation of the {name} since the reference frame"},
        )
        pts = np.asarray(rows["points"], dtype=np.float32)
        data[f"{name}_points"] = (
            ("time", f"{name}_point", f"{name}_point_axis"),
            pts,
            {
                "units": unit,
                "long_name": f"tracked subset centres of the {name} (world frame)",
                "ancillary_variables": f"{name}_points_u",
            },
        )
        data[f"{name}_points_u"] = (
            ("time", f"{name}_point", f"{name}_point_axis"),
            np.asarray(rows["points_u"], dtype=np.float32),
            {"units": unit, "long_name": f"standard uncertainty of {name}_points (propagated)"},
        )
        data[f"{name}_zncc"] = (
            ("time", f"{name}_point"),
            np.asarray(rows["zncc"], dtype=np.float32),
            {"units": "1", "long_name": f"ZNCC of the {name}'s subsets (lower of the two cameras)"},
        )
        data[f"{name}_subset_displacement"] = (
            ("time", f"{name}_point", f"{name}_point_axis"),
            pts - pts[:1],
            {
                "units": unit,
                "long_name": f"displacement of the {name}'s subsets since the reference frame",
            },
        )
        coords[f"{name}_row"] = (f"{name}_row", np.arange(d))
        coords[f"{name}_col"] = (f"{name}_col", np.arange(d))
        coords[f"{name}_point_axis"] = (f"{name}_point_axis", axes)
        sig_med = float(np.median(st.sigma_px))
        attrs_extra[f"{name}_match_sigma_px"] = sig_med
        if stereo:
            from jointwear.dic._stereo import stereo_noise_floor

            floor = stereo_noise_floor(calibration, np.nanmean(st.ref3d, axis=0), sig_med)
            attrs_extra[f"{name}_noise_floor_z_per_point_m"] = floor
            attrs_extra[f"{name}_noise_floor_z_body_m"] = floor / np.sqrt(len(st.ref3d))
        role = st.spec.role
        if role == "follower" and stereo:
            data["follower_position"] = (
                ("time", "axis"),
                poi,
                C.variable_attrs("follower_position", ancillary_variables="follower_position_u"),
            )
            data["follower_position_u"] = (
                ("time", "axis"),
                poi_u,
                {"units": unit, "long_name": "standard uncertainty of follower_position"},
            )
            data["follower_velocity"] = (
                ("time", "axis"),
                vel,
                C.variable_attrs(
                    "follower_velocity",
                    ancillary_variables="follower_velocity_u",
                    method=f"Savitzky-Golay on frame times, window {cfg.velocity_window} "
                    f"samples, order {cfg.velocity_order}",
                ),
            )
            data["follower_velocity_u"] = (
                ("time", "axis"),
                vel_u,
                {
                    "units": f"{unit} s-1",
                    "long_name": "standard uncertainty of follower_velocity (noise propagated "
                    "through the differentiator)",
                },
            )
        elif role == "journal":
            disp = poi - poi[:1]
            jname = "journal_displacement" if stereo else "journal_image_displacement"
            data[jname] = (
                ("time", "axis"),
                disp,
                {
                    "units": unit,
                    "long_name": "displacement of the journal since the reference frame (z = out of plane)",
                    "ancillary_variables": f"{jname}_u",
                },
            )
            data[f"{jname}_u"] = (
                ("time", "axis"),
                poi_u * np.sqrt(2),
                {"units": unit, "long_name": "standard uncertainty of journal_displacement"},
            )
        elif role == "crank":
            ang = np.unwrap(rotation_angle_z(np.asarray(rows["R"], dtype=float)))
            if not stereo:  # image y points down: a counter-clockwise turn looks clockwise
                ang = -ang
            ang = ang + np.deg2rad(st.spec.reference_angle_deg)
            # a crank turning at constant speed also reveals frames lost without a time gap
            # (constant-rate video containers): a step of about k >= 2 median steps
            step = np.diff(ang)
            ok = np.isfinite(step)
            if ok.sum() >= 3:
                med = np.median(step[ok])
                if abs(med) > 1e-6:
                    k = np.rint(step / med)
                    jumps = np.flatnonzero(ok & (k >= 2) & (np.abs(step / med - k) < 0.25)) + 1
                    jumps = [int(j) for j in jumps if not flag_arr[j] & FRAME_FLAGS["after_gap"]]
                    flag_arr[jumps] |= FRAME_FLAGS["crank_step_gap"]
                    attrs_extra["dropped_frames_from_crank"] = json.dumps(
                        {str(j): int(k[j - 1] - 1) for j in jumps}
                    )
            data["crank_angle"] = (
                "time",
                ang,
                C.variable_attrs(
                    "crank_angle",
                    note=f"rotation of the tracked crank about the world z axis plus reference_angle_deg = {st.spec.reference_angle_deg}",
                ),
            )
    roles = {st.spec.role: st for st in states}
    if stereo and "journal" in roles and "bearing" in roles:
        rb = np.asarray(roles["bearing"].rows["R"], dtype=float)
        pb = np.asarray(roles["bearing"].rows["poi"], dtype=float)
        pj = np.asarray(roles["journal"].rows["poi"], dtype=float)
        offset = np.einsum("nji,nj->ni", rb, pj - pb)  # R_b^T (p_j - p_b)
        data["journal_offset"] = (
            ("time", "axis"),
            offset,
            C.variable_attrs(
                "journal_offset",
                note="journal point of interest minus bearing centre, in the bearing frame "
                "(world axes at the reference frame, turning with the bearing body)",
            ),
        )
    data["frame_flag"] = (
        "time",
        flag_arr,
        {
            "units": "1",
            "long_name": "frame quality flags (bit mask)",
            "flag_masks": np.array([1, 2, 4, 8], dtype=np.int8),
            "flag_meanings": "duplicated after_gap tracking_failed crank_step_gap",
        },
    )
    ds = xr.Dataset(data, coords=coords)
    ds.attrs.update(attrs_extra)
    ds.attrs.update(
        {
            "title": "jointwear rig footage tracking",
            "status": status,
            "frames_processed": len(t),
            "duplicated_frames": json.dumps([int(i) for i in duplicates]),
            "dropped_frames_estimated": dropped,
            "gaps_after_frames": json.dumps([int(i) for i in gaps]),
            "left_footage": str(L.path),
            "right_footage": str(R.path) if R is not None else "",
            "frame_rate_hz": L.fps,
            "world_frame": calibration.world_frame
            if calibration is not None
            else "left image (pixels)",
            "velocity_method": f"Savitzky-Golay local polynomial on the frame times, window {cfg.velocity_window} samples, order {cfg.velocity_order}",
        }
    )
    return ds
