"""Calibrate a stereo pair from board image files or videos and save it, in one call (what
``jointwear dic calibrate`` runs)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from jointwear.dic.calibration._board import CalibrationBoard, calibrate_stereo
from jointwear.dic.calibration._camera import StereoCalibration
from jointwear.dic.calibration._defaults import VIDEO_EVERY

__all__ = ["board_views", "calibrate_files", "rejected_path"]


def _video_frames(path: Path, every: int, what: str) -> list:
    from jointwear.dic.footage import open_frames

    src = open_frames(path, what=what)
    return [img for i, _, img in src.frames() if i % every == 0]


def board_views(left: Path, right: Path, every: int = VIDEO_EVERY):
    """(left images, right images, view names or None) of two folders / patterns or videos
    (videos: every ``every``-th frame, named ``<video>#<frame>``)."""
    from jointwear.dic.footage import is_image_sequence, list_image_sequence

    if is_image_sequence(left):  # a folder, or a pattern like 'cal/*_0.tif'
        lefts = list_image_sequence(left, what="left calibration")[0]
        rights = list_image_sequence(right, what="right calibration")[0]
        return lefts, rights, None
    lefts = _video_frames(left, every, "left calibration video")
    rights = _video_frames(right, every, "right calibration video")
    names = [f"{left.name}#{i * every} / {right.name}#{i * every}" for i in range(len(lefts))]
    names = names[: len(rights)]
    return lefts, rights, names if lefts and len(names) == len(lefts) == len(rights) else None


def rejected_path(out: Path) -> Path:
    """Where a calibration that fails the gate is kept: ``<out>.rejected.nc``."""
    return out.with_name(out.stem + ".rejected" + (out.suffix or ".nc"))


def calibrate_files(
    left: str | Path,
    right: str | Path,
    out: str | Path,
    board: CalibrationBoard,
    *,
    every: int = VIDEO_EVERY,
    parameters: dict[str, Any] | None = None,
    progress_label: str = "finding the board",
    **options,
) -> StereoCalibration:
    """Calibrate from board views in files and save the calibration to ``out``.

    Parameters
    ----------
    left, right : path
        The cameras' board images: folders or patterns ('cal/*_0.tif'), or videos.
    out : path
        Calibration file (.nc). A calibration that fails the sanity gate is saved to
        :func:`rejected_path` instead and :class:`PoorCalibration` is raised.
    board : CalibrationBoard
        The target.
    every : int
        Videos: use every N-th frame.
    parameters : dict, optional
        Recorded in the file's provenance.
    **options
        Passed to :func:`calibrate_stereo` (``min_views``, ``world_view``, ``max_rms``, ...).
    """
    from jointwear import io
    from jointwear.dic.calibration._gate import PoorCalibration
    from jointwear.progress import progress_bar

    left, right, out = Path(left), Path(right), Path(out)
    io.check_writable(out)
    lefts, rights, names = board_views(left, right, every)
    try:
        with progress_bar(progress_label, total=min(len(lefts), len(rights))) as bar:
            task = bar.tasks[0].id
            cal = calibrate_stereo(
                lefts,
                rights,
                board,
                view_names=names,
                progress=lambda done, total: bar.update(task, completed=done),
                **options,
            )
    except PoorCalibration as exc:
        exc.calibration.save(rejected_path(out), inputs=[left, right], parameters=parameters)
        raise
    cal.save(out, inputs=[left, right], parameters=parameters)
    return cal
