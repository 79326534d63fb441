"""Footage to body motion: stereo (or single-camera) tracking of rigid bodies in rig videos.

Pipeline (``track_footage``)
---------------------------
1. The first frame of each camera is the reference. Each body's region of interest (a polygon
   in the left reference image, from a small TOML file) is filled with a grid of subsets.
2. Stereo correspondence at the reference: SIFT features of the region are matched (FLANN,
   guided by the epipolar lines, :mod:`jointwear.dic.footage._features`) with the right image's
   features in the regions' epipolar band, kept within the epipolar gate
   (``max(3, max_epipolar_px)`` px), and a RANSAC homography gives every subset an initial guess (position and affine gradients); the
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
   Savitzky–Golay differentiator on the actual frame times (window 9, order 5 by default);
   their uncertainty includes the differentiator's truncation error and the calibration's.
5. Frames are decoded ahead in a background thread and processed in order (bounded memory:
   the reference images, a few frames per camera and the per-frame results are held); the
   trackers run in two threads, the left ones of frame k + 1 beside the right ones and the
   poses of frame k. The result is written after each chunk when an output path is given, so an
   interrupted run keeps what was computed; ``workers > 1`` runs chunks in processes instead
   (threads inside a daemonic process such as a dask worker; tasks on a dask cluster with
   ``scheduler``).

Modules: :mod:`~jointwear.dic.footage._config` (options, bodies, flags),
:mod:`~jointwear.dic.footage._features` (SIFT, matching, homography),
:mod:`~jointwear.dic.footage._tracker` (one body in one camera),
:mod:`~jointwear.dic.footage._frames` (set-up and per-frame pipeline),
:mod:`~jointwear.dic.footage._result` (the dataset, its file, resuming), and this one.
"""

from __future__ import annotations

import contextlib
import os
import time as _time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import xarray as xr

from jointwear._workers import connect_scheduler
from jointwear.dic.calibration import StereoCalibration
from jointwear.dic.footage._config import FRAME_FLAGS, BodySpec, TrackConfig, read_bodies
from jointwear.dic.footage._features import (  # noqa: F401 (re-exported)
    _as_uint8,
    _homography_guess,
    _sift_features,
    _sift_homography,
)
from jointwear.dic.footage._frames import (  # noqa: F401 (re-exported)
    _BodyState,
    _run_frames,
    _setup_states,
    _stereo_prediction,
)
from jointwear.dic.footage._result import (  # noqa: F401 (re-exported)
    _RESUMABLE_CHANGES,
    _assemble,
    _load_partial,
    _parameters,
    _restore_rows,
    _write,
)
from jointwear.dic.footage._tracker import (  # noqa: F401 (re-exported)
    _affine_fit,
    _CameraBodyTracker,
    _grid_in_polygon,
    _match_sigma,
    _noise_sigma,
)
from jointwear.dic.footage._video import (
    FrameSource,
    check_frame_names,
    check_stereo_pair,
    list_image_sequence,
    open_frames,
    prefetch,
)
from jointwear.errors import BadInputError

__all__ = [
    "BodySpec",
    "TrackConfig",
    "read_bodies",
    "track_footage",
    "FRAME_FLAGS",
]


def _open_footage(source: str | Path | FrameSource, fps: float | None, what: str) -> FrameSource:
    """Open one camera's footage. A folder whose images are not all named like its frames (a
    mask, a stray image) is refused naming the odd files, as ``dic correlate`` and ``dic field``
    refuse it (:func:`jointwear.dic.subset._sequence.check_frame_names`): otherwise the odd file would
    be tracked as one more frame."""
    if isinstance(source, FrameSource):
        return source
    if Path(source).is_dir():
        files, _ = list_image_sequence(source, what=what)
        check_frame_names(files, f"{what} folder '{source}'")
    return open_frames(source, fps=fps, what=what)


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
    scheduler: str | None = None,
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
    scheduler : str, optional
        Address of a ``dask.distributed`` scheduler (``tcp://host:8786``): the chunks run as
        tasks on its workers (which must see the footage at the same paths), as with
        ``workers > 1``. Inside a daemonic process (a dask worker, which may not start
        processes), ``workers > 1`` runs the chunks in threads instead.

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
    L, R = _open_cameras(left, right, fps, calibration)
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

    save = _Checkpoint(
        out, inputs, bodies, (states, times, flags, duplicates, L, R, cfg, calibration)
    )
    # one process: the cameras' and bodies' trackers of a frame run in threads (their
    # kernels release the GIL); several processes: one thread each
    n_threads = min(2, os.cpu_count() or 1) if cfg.workers <= 1 and scheduler is None else 1
    pool = ThreadPoolExecutor(max_workers=n_threads) if n_threads > 1 else None
    try:
        with progress_bar("tracking frames", n_total, enabled=progress) as bar:
            task = bar.tasks[0].id
            bar.update(task, advance=start)
            if cfg.workers <= 1 and scheduler is None:
                # decoding overlaps; a resumed run starts one frame early for the duplicate check
                frames = prefetch(_paired_frames(L, R, max(start - 1, 0), n_total))
                tracked = _run_frames(
                    states, frames, cfg, calibration, pool, first=start, reinit_first=start > 0
                )
                for _ in _recorded(tracked, times, flags, duplicates):
                    bar.update(task, advance=1)
                    if len(times) % cfg.chunk_size == 0:
                        save("partial")
            else:
                for part in _chunk_results(
                    L, R, bodies, calibration, cfg, scheduler, start, n_total
                ):
                    for st in states:
                        for key, vals in part["rows"][st.spec.name].items():
                            st.rows.setdefault(key, []).extend(vals)
                    times.extend(part["times"])
                    flags.extend(part["flags"])
                    duplicates.extend(part["duplicates"])
                    bar.update(task, advance=len(part["times"]))
                    if part["error"]:
                        raise BadInputError(part["error"])
                    save("partial")
    except (BadInputError, KeyboardInterrupt) as exc:
        if isinstance(pool, ThreadPoolExecutor):
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
        if isinstance(pool, ThreadPoolExecutor):
            pool.shutdown()
    return _finish_result(
        states, times, flags, duplicates, L, R, cfg, calibration, out, inputs, bodies, t_start
    )


def _open_cameras(left, right, fps, calibration) -> tuple[FrameSource, FrameSource | None]:
    """Both cameras' footage (``R`` None: one camera), checked against each other and the
    calibration's image sizes."""
    L = _open_footage(left, fps, "left footage")
    if right is None:
        return L, None
    R = _open_footage(right, fps, "right footage")
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
    return L, R


def _recorded(tracked, times: list, flags: list, duplicates: list):
    """Record every tracked frame's time, flag and (when a duplicate) index; yields after
    each frame."""
    for i, t, flag, dup in tracked:
        flags.append(flag)
        times.append(t)
        if dup:
            duplicates.append(i)
        yield i


def _chunk_results(L, R, bodies, calibration, cfg, scheduler, start: int, stop: int):
    """Track the frames ``start <= i < stop`` in independent chunks (processes, threads or
    dask tasks, :func:`_chunk_executor`); yields each chunk's result in order. The chunks not
    started yet are cancelled when one stops with an error."""
    ranges = [(a, min(a + cfg.chunk_size, stop)) for a in range(start, stop, cfg.chunk_size)]
    with _chunk_executor(cfg.workers, scheduler) as chunks:
        futures = [
            chunks.submit(_run_chunk, L, R, bodies, calibration, cfg, a, b) for a, b in ranges
        ]
        for fut in futures:
            part = fut.result()
            if part["error"]:
                for other in futures:
                    other.cancel()  # chunks not started yet
            yield part


class _Checkpoint:
    """Write the partial result to ``out`` after a chunk. Partial results are rewritten whole,
    so on a long recording each write costs more; a chunk's write is skipped while the
    previous write took more than 1/_CHECKPOINT_OVERHEAD of the time since, keeping the
    writes' share of the run bounded."""

    def __init__(self, out, inputs, bodies, assemble_args: tuple) -> None:
        self.out, self.inputs, self.bodies = out, inputs, bodies
        self.args = assemble_args  # (states, times, flags, duplicates, L, R, cfg, calibration)
        self.end, self.cost = _time.perf_counter(), 0.0

    def __call__(self, status: str, *, force: bool = False) -> None:
        times = self.args[1]
        if self.out is None or not times:
            return
        now = _time.perf_counter()
        if not force and (now - self.end) * _CHECKPOINT_OVERHEAD < self.cost:
            return
        ds = _assemble(*self.args, status)
        _write(ds, self.out, self.inputs, self.args[6], self.bodies)
        self.end = _time.perf_counter()
        self.cost = self.end - now


def _finish_result(
    states, times, flags, duplicates, L, R, cfg, calibration, out, inputs, bodies, t_start
) -> xr.Dataset:
    result = _assemble(states, times, flags, duplicates, L, R, cfg, calibration, "complete")
    result.attrs["wall_time_s"] = _time.perf_counter() - t_start
    result.attrs["workers"] = cfg.workers
    if out is not None:
        _write(result, out, inputs, cfg, bodies)
    return result


#: largest share of a tracking run spent writing partial results (see _Checkpoint)
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


def _run_chunk(L, R, bodies, calibration, cfg, start: int, stop: int) -> dict:
    """Worker: track frames ``start <= i < stop`` independently (SIFT start, own references)."""
    (_, _, ref_l), ref_r = _reference_frames(L, R)
    states = _setup_states(L, R, bodies, calibration, cfg, ref_l, ref_r)
    times, flags, duplicates = [], [], []
    error = ""
    try:
        frames = _paired_frames(L, R, max(start - 1, 0), stop)
        # the frame before the chunk serves only the duplicate check
        tracked = _run_frames(
            states, frames, cfg, calibration, None, first=start, reinit_first=start > 0
        )
        for _ in _recorded(tracked, times, flags, duplicates):
            pass
    except BadInputError as exc:
        error = str(exc)
    return {
        "times": times,
        "flags": flags,
        "duplicates": duplicates,
        "rows": {st.spec.name: st.rows for st in states},
        "error": error,
    }


@contextlib.contextmanager
def _chunk_executor(workers: int, scheduler: str | None):
    """Where independent chunks run: a dask.distributed cluster (``scheduler`` address),
    threads inside a daemonic process (a dask or multiprocessing worker may not start
    processes: "daemonic processes are not allowed to have children"), otherwise ``workers``
    spawned processes. Yields an object with ``submit(fn, *args)`` returning futures."""
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    if scheduler is not None:
        client = connect_scheduler(scheduler, timeout="20s")
        try:
            yield _DaskSubmitter(client)
        finally:
            client.close()
        return
    if multiprocessing.current_process().daemon:
        with ThreadPoolExecutor(max_workers=workers) as pool:
            yield pool
        return
    # spawn: forking a process that already runs OpenMP/numba threads is unsafe
    ctx = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(max_workers=workers, mp_context=ctx) as pool:
        yield pool


class _DaskSubmitter:
    """``submit`` on a dask client, each chunk a pure task (the same chunk gives the same
    result whichever worker runs it)."""

    def __init__(self, client) -> None:
        self.client = client

    def submit(self, fn, *args):
        return self.client.submit(fn, *args, pure=False)
