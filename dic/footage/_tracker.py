"""Footage tracking: one body's subsets in one camera, followed against the reference image."""

from __future__ import annotations

import numpy as np

from jointwear.dic.footage._config import TrackConfig
from jointwear.dic.footage._features import (
    _homography_guess,
    _sift_features,
    _sift_homography,
    affine_guess,
)
from jointwear.dic.icgn import prefilter_region


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
        out = affine_guess(C, new_pos, M[:, :2] @ J)
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
