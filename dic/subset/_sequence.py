"""Image sequences: frame reading and correlation with absolute or incremental reference.

``read_frames(source, *, start=0, stop=None, stride=1) -> (list of 2D arrays, frame_rate|None)``
    ``source``: a 3D array (time, rows, columns), a list of 2D arrays or image paths, a folder
    of images (in frame-number order; png, tif, tiff, bmp, jpg, jpeg, pgm) or a video file (OpenCV).
    Colour frames are converted to grey.

``correlate_sequence(frames, *, reference="absolute", points=None, roi=None, times=None,
frame_rate=None, update_zncc=0.9, update_every=None, progress=False, params=None, **options)``
    Tracks the subsets of frame 0 through the sequence. ``absolute``: every frame is correlated
    with frame 0, the guess being the previous frame's result. ``incremental``: the reference
    moves forward (to the last good frame) whenever the median ZNCC drops below ``update_zncc``
    or more than 10 % of the tracked points fail; displacements are accumulated (positions
    ``x_k = x_m + u_inc(x_m)``, gradients ``F_k = F_inc F_m``; second derivatives are not
    accumulated and are NaN in that mode). Output: the variables of
    :func:`jointwear.dic.correlate` over ``(time, point)`` or ``(time, y, x)``, plus
    ``reference_frame`` over ``time``.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from jointwear.dic.footage import check_frame_names  # noqa: F401 (re-exported)
from jointwear.dic.subset._params import UPDATE_ZNCC
from jointwear.errors import BadInputError, ParameterError

if TYPE_CHECKING:  # read_image serves `dic correlate` of a pair, which does without xarray
    import xarray as xr

__all__ = ["read_frames", "correlate_sequence"]

IMAGE_SUFFIXES = (".png", ".tif", ".tiff", ".bmp", ".jpg", ".jpeg", ".pgm", ".ppm")


def _grey(img: np.ndarray, name: str) -> np.ndarray:
    if img.ndim == 3:
        import cv2

        code = cv2.COLOR_BGR2GRAY if img.shape[2] == 3 else cv2.COLOR_BGRA2GRAY
        img = cv2.cvtColor(img, code)
    if img.ndim != 2:
        raise BadInputError(f"{name}: expected a grey or colour image, got shape {img.shape}")
    return img


def read_image(path: str | Path) -> np.ndarray:
    """Read one image file as a grey array (dtype kept: uint8, uint16 or float)."""
    import cv2

    path = Path(path)
    if not path.exists():
        raise BadInputError(f"image '{path}' does not exist")
    img = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    if img is None:
        raise BadInputError(
            f"image '{path}' could not be read by OpenCV; expected one of "
            f"{', '.join(IMAGE_SUFFIXES)}"
        )
    return _grey(img, f"image '{path}'")


def read_frames(
    source, *, start: int = 0, stop: int | None = None, stride: int = 1
) -> tuple[list[np.ndarray], float | None]:
    """Frames of a sequence as grey 2D arrays, and the frame rate [1/s] if the source has one.

    Parameters
    ----------
    source : ndarray, sequence, str or Path
        3D array ``(time, rows, columns)``, list of 2D arrays or image paths, a folder of images
        (in frame-number order), a glob pattern (``"images/*_0.tif"``) or a video file.
    start, stop, stride : int
        Frame selection (like ``range``).
    """
    if stride < 1 or start < 0:
        raise ParameterError(
            f"frame selection start={start}, stride={stride}: need start >= 0, stride >= 1"
        )
    sel = slice(start, stop, stride)
    if isinstance(source, np.ndarray):
        if source.ndim != 3:
            raise BadInputError(
                f"frames: expected a 3D array (time, rows, columns), got shape {source.shape}"
            )
        return [np.asarray(f) for f in source[sel]], None
    if isinstance(source, (str, Path)):
        from jointwear.dic.footage import is_image_sequence, list_image_sequence

        path = Path(source)
        if is_image_sequence(source):
            # sorted by the frame number in the names (frame_9 before frame_10)
            files, _ = list_image_sequence(source, what="frames source")
            return [read_image(p) for p in files[sel]], None
        if not path.exists():
            raise BadInputError(f"frames source '{path}' does not exist")
        if path.suffix.lower() in IMAGE_SUFFIXES:
            raise BadInputError(
                f"'{path}' is a single image; give a folder, a video or a list of images"
            )
        return _read_video(path, sel)
    if isinstance(source, Sequence):
        frames = []
        for i, item in enumerate(list(source)[sel]):
            if isinstance(item, (str, Path)):
                frames.append(read_image(item))
            else:
                arr = np.asarray(item)
                frames.append(_grey(arr, f"frame {i}") if arr.ndim == 3 else arr)
        return frames, None
    raise BadInputError(
        f"frames: expected an array, a list of images, a folder or a video, got {type(source).__name__}"
    )


def _read_video(path: Path, sel: slice) -> tuple[list[np.ndarray], float | None]:
    import cv2

    cap = cv2.VideoCapture(str(path))
    if not cap.isOpened():
        raise BadInputError(f"video '{path}' could not be opened by OpenCV (codec or format?)")
    fps = cap.get(cv2.CAP_PROP_FPS) or None
    frames = []
    i = 0
    stop = sel.stop
    try:
        while stop is None or i < stop:
            ok, img = cap.read()
            if not ok:
                break
            if i >= sel.start and (i - sel.start) % sel.step == 0:
                frames.append(_grey(img, f"video '{path}' frame {i}"))
            i += 1
    finally:
        cap.release()
    if not frames:
        raise BadInputError(f"video '{path}': no frames read in the selection")
    return frames, (float(fps) if fps and fps > 0 else None)


def _compose(P_inc: np.ndarray, P_ref: np.ndarray) -> np.ndarray:
    """Total parameters after an increment measured on a moved reference (first order)."""
    out = np.full_like(P_inc, np.nan)
    out[:, 0] = P_ref[:, 0] + P_inc[:, 0]
    out[:, 6] = P_ref[:, 6] + P_inc[:, 6]
    Fi = np.stack(
        [[1 + P_inc[:, 1], P_inc[:, 2]], [P_inc[:, 7], 1 + P_inc[:, 8]]], axis=0
    ).transpose(2, 0, 1)
    Fr = np.stack(
        [[1 + P_ref[:, 1], P_ref[:, 2]], [P_ref[:, 7], 1 + P_ref[:, 8]]], axis=0
    ).transpose(2, 0, 1)
    F = Fi @ Fr
    out[:, 1], out[:, 2] = F[:, 0, 0] - 1, F[:, 0, 1]
    out[:, 7], out[:, 8] = F[:, 1, 0], F[:, 1, 1] - 1
    return out


def correlate_sequence(
    frames,
    *,
    reference: str = "absolute",
    points: np.ndarray | None = None,
    roi: Sequence[float] | None = None,
    times: Sequence[float] | None = None,
    frame_rate: float | None = None,
    update_zncc: float = UPDATE_ZNCC,
    update_every: int | None = None,
    progress: bool | None = False,
    seed_points: np.ndarray | None = None,
    params=None,
    **options,
) -> xr.Dataset:
    """Track the subsets of the first frame through a sequence.

    Parameters
    ----------
    frames : array, list, folder or video
        See :func:`read_frames`; frame 0 is the reference.
    reference : {"absolute", "incremental"}
        Reference strategy (see module docstring).
    points, roi : optional
        Points of interest or grid region in frame 0 (as in :func:`jointwear.dic.correlate`).
    times : sequence of float, optional
        Time of every frame [s]. Default: ``frame index / frame_rate``.
    frame_rate : float, optional
        Frames per second [1/s]; taken from a video file if not given, else 1 (noted in the
        ``time`` attributes).
    update_zncc : float
        Incremental mode: median ZNCC below which the reference is moved forward.
    update_every : int, optional
        Incremental mode: also move the reference forward after this many frames (1: every
        frame is correlated with the previous one).
    progress : bool
        Show a progress bar on stderr.
    seed_points : ndarray (K, 2), optional
        Where the propagation starts ``(x, y)`` [pixel, frame 0] whenever a frame has to be
        searched afresh (guesses from the previous frame failed); followed to the moved
        reference in incremental mode. Seeds outside the image are refused.
    params : CorrelationParams, optional
        Correlation options; keyword arguments override its fields (``subset_size=...``).

    Returns
    -------
    Dataset
        ``u``, ``v`` [pixel] accumulated from frame 0, gradients, ``zncc``, ``iterations``,
        ``converged``, ``flag`` over ``time`` and ``point`` (or ``y``, ``x``), and
        ``reference_frame``.
    """
    from jointwear.dic.subset._correlator import SubsetCorrelator

    if update_every is not None and (not isinstance(update_every, int) or update_every < 1):
        raise ParameterError(f"update_every={update_every!r}: expected an integer >= 1 frame")
    if reference not in ("absolute", "incremental"):
        raise ParameterError(
            f"reference={reference!r}: expected 'absolute' (always frame 0) or 'incremental'"
        )
    first, frame_list, fps = _checked_frames(frames)
    t, time_note = _frame_times(times, frame_rate, fps, len(frame_list))
    base = SubsetCorrelator(first, points=points, roi=roi, params=params, **options)
    seeds0 = base.check_seeds(seed_points) if seed_points is not None else None
    tracker = _SequenceTracker(base, first, frame_list, seeds0)
    tracker.track(reference, update_zncc, update_every, progress)
    return tracker.dataset(reference, t, time_note)


def _checked_frames(frames) -> tuple[np.ndarray, list, float | None]:
    """The checked first frame, the frames (at least 2, all alike, see :func:`read_frames`)
    and the video's frame rate [1/s] (None if unknown)."""
    from jointwear.dic.subset._correlator import check_image, check_pair

    if isinstance(frames, tuple) and len(frames) == 2 and isinstance(frames[0], list):
        frame_list, fps = frames
    else:
        frame_list, fps = read_frames(frames)
    if len(frame_list) < 2:
        raise BadInputError(f"frames: need at least 2 frames, got {len(frame_list)}")
    first = check_image(frame_list[0], "frame 0")
    for k, fr in enumerate(frame_list[1:], start=1):
        check_pair(first, check_image(fr, f"frame {k}"), what=f"frame {k}")
    return first, frame_list, fps


def _frame_times(times, frame_rate, fps, n_t: int) -> tuple[np.ndarray, str | None]:
    """Time of every frame [s] (given, or from the frame rate) and a note when assumed."""
    if times is not None:
        t = np.asarray(times, dtype=float)
        if t.shape != (n_t,) or not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0):
            raise BadInputError(
                f"times: expected {n_t} finite, strictly increasing values [s], got shape {t.shape}"
            )
        return t, None
    time_note = None
    rate = frame_rate or fps
    if rate is None:
        rate = 1.0
        time_note = "frame rate unknown: time = frame index (1 frame per second assumed)"
    if not rate > 0:
        raise ParameterError(f"frame_rate={frame_rate!r}: expected > 0 frames per second")
    return np.arange(n_t) / float(rate), time_note


class _SequenceTracker:
    """The subsets of frame 0 (``base``) followed through ``frame_list``: parameters ``P``
    accumulated from frame 0, their (u, v) uncertainties ``S``, ZNCC ``Z``, iterations
    ``It``, flags ``Fl`` and the reference frame of every frame."""

    def __init__(self, base, first: np.ndarray, frame_list: list, seeds0: np.ndarray | None):
        from jointwear.dic import icgn as _icgn

        self.base, self.frame_list, self.seeds0 = base, frame_list, seeds0
        n_t, n = len(frame_list), base.n_points
        self.P = np.full((n_t, n, 12), np.nan)
        self.Z = np.full((n_t, n), np.nan)
        self.It = np.zeros((n_t, n), dtype=np.int32)
        self.Fl = np.full((n_t, n), _icgn.FLAG_NOT_REACHED, dtype=np.int8)
        self.S = np.full((n_t, n, 2), np.nan)
        self.ref_frame = np.zeros(n_t, dtype=np.int32)
        self.shape = first.shape
        r0 = base.match(first, initial_guess=np.zeros((n, 2)))
        self.P[0], self.Z[0], self.It[0], self.Fl[0] = r0.params, r0.zncc, r0.iterations, r0.flag
        self.S[0] = np.where(r0.ok[:, None], 0.0, np.nan)  # the reference against itself
        self.tracked = r0.ok.copy()

    def seeds_for(self, correlator):
        """The seeds moved with the tracked point nearest to each (incremental reference)."""
        base, seeds0 = self.base, self.seeds0
        if seeds0 is None or correlator is base:
            return seeds0
        near = np.argmin(np.hypot(*(base.centres[None, :, :] - seeds0[:, None, :]).T), axis=0)
        moved = correlator.centres[near] + (seeds0 - base.centres[near])
        h, w = self.shape
        inside = np.isfinite(moved).all(axis=1)
        inside &= (moved[:, 0] >= 0) & (moved[:, 0] <= w - 1)
        inside &= (moved[:, 1] >= 0) & (moved[:, 1] <= h - 1)
        moved = moved[inside]
        return moved if len(moved) else None

    def run(self, correlator, img, guess_inc):
        """Match ``img`` from the increments ``guess_inc``; search afresh if they were poor."""
        guess = np.where(np.isfinite(guess_inc).all(axis=1)[:, None], guess_inc, np.nan)
        res = correlator.match(img, initial_guess=guess)
        if res.ok.sum() < 0.5 * max(1, self.tracked.sum()):
            # the guesses were poor (jump between frames): search again from seeds
            known = np.isfinite(guess_inc).all(axis=1)
            centre = (
                (float(np.median(guess_inc[known, 0])), float(np.median(guess_inc[known, 6])))
                if known.any()
                else (0.0, 0.0)
            )
            res2 = correlator.match(
                img, search_centre=centre, seed_points=self.seeds_for(correlator)
            )
            if res2.ok.sum() > res.ok.sum():
                res = res2
        return res

    def move_reference(self, new_m):
        """The reference becomes frame ``new_m``: subsets centred at the tracked positions."""
        from jointwear.dic import icgn as _icgn
        from jointwear.dic.subset._correlator import SubsetCorrelator

        base = self.base
        P_new = self.P[new_m].copy()
        good = self.Fl[new_m] == _icgn.FLAG_OK
        centres = base.centres + np.column_stack([P_new[:, 0], P_new[:, 6]])
        centres[~good] = np.nan
        c = SubsetCorrelator(
            self.frame_list[new_m], points=centres, params=base.params, _graph=base.graph
        )
        return c, P_new, np.zeros((base.n_points, 12)), new_m

    def track(self, reference, update_zncc, update_every, progress) -> None:
        """Follow the subsets through every frame (see the module docstring)."""
        from jointwear.dic import icgn as _icgn
        from jointwear.progress import progress_bar

        P, S, Fl, tracked = self.P, self.S, self.Fl, self.tracked
        n_t, n = P.shape[:2]
        corr = self.base
        m = 0  # index of the current reference frame
        P_ref = np.zeros((n, 12))  # total parameters of the current reference frame
        P_prev_inc = np.zeros((n, 12))  # last increment w.r.t. the current reference
        with progress_bar("correlating frames", total=n_t - 1, enabled=progress) as bar:
            task = bar.tasks[0].id
            for k in range(1, n_t):
                img = self.frame_list[k]
                due = update_every is not None and k - m > update_every
                if reference == "incremental" and k - 1 > m and due:
                    corr, P_ref, P_prev_inc, m = self.move_reference(k - 1)
                res = self.run(corr, img, P_prev_inc)
                if reference == "incremental" and k - 1 > m:
                    okk = res.ok & tracked
                    med = np.nanmedian(res.zncc[okk]) if okk.any() else -1.0
                    if med < update_zncc or okk.sum() < 0.9 * tracked.sum():
                        corr, P_ref, P_prev_inc, m = self.move_reference(k - 1)
                        res = self.run(corr, img, P_prev_inc)
                ok = res.ok
                P_prev_inc = np.where(ok[:, None], res.params, P_prev_inc)
                if m == 0:
                    P[k] = res.params
                    S[k] = res.sigma
                else:
                    P[k] = _compose(res.params, P_ref)
                    # independent increments: variances add
                    S[k] = np.sqrt(res.sigma**2 + S[m] ** 2)
                self.Z[k], self.It[k], Fl[k] = res.zncc, res.iterations, res.flag
                lost = ~np.isfinite(corr.centres).all(axis=1)
                Fl[k][lost] = _icgn.FLAG_NOT_REACHED
                self.ref_frame[k] = m
                bar.update(task, advance=1)

    def dataset(self, reference, t, time_note) -> xr.Dataset:
        """The tracked sequence as a Dataset over ``time``."""
        import xarray as xr

        from jointwear.dic.subset._correlator import result_dataset

        base, prm, ref_frame = self.base, self.base.params, self.ref_frame
        ds = result_dataset(
            base.centres, self.P, self.Z, self.It, self.Fl, prm, base.grid, sigma=self.S,
            neighbour_images=ref_frame == 0,  # composed displacements: see _flags
        )  # fmt: skip
        if reference == "incremental":
            for name in prm.shape_function.not_incremental:
                ds[name].values[ref_frame > 0] = np.nan
        ds = ds.assign_coords(
            time=("time", t, {"units": "s", "long_name": "elapsed time since the first frame"}),
            frame=("time", np.arange(len(t)), {"long_name": "frame index"}),
        )
        if time_note:
            ds["time"].attrs["note"] = time_note
        ds["reference_frame"] = xr.DataArray(
            ref_frame,
            dims="time",
            attrs={"units": "1", "long_name": "index of the reference frame used"},
        )
        ds.attrs["title"] = "2D subset DIC displacement over an image sequence"
        ds.attrs["dic_reference_strategy"] = reference
        ds.attrs["dic_reference_updates"] = int(np.count_nonzero(np.diff(ref_frame)))
        return ds
