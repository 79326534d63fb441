"""Track the bodies of rig footage files and save the motion, in one call (what
``jointwear dic track`` runs)."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import xarray as xr

from jointwear.dic.footage._config import BodySpec, TrackConfig

__all__ = ["track_files", "with_overrides"]


def with_overrides(config: TrackConfig, **overrides) -> TrackConfig:
    """``config`` with the options given (None values ignored) replaced: the command line's
    overrides of a regions-of-interest file's ``[track]`` table."""
    given = {k: v for k, v in overrides.items() if v is not None}
    return dataclasses.replace(config, **given) if given else config


def track_files(
    left: str | Path,
    right: str | Path | None,
    out: str | Path,
    *,
    bodies: str | Path,
    config: TrackConfig,
    specs: list[BodySpec],
    calibration: str | Path | None = None,
    plot: str | Path | None = None,
    **options,
) -> xr.Dataset:
    """Track the bodies through the footage and write the motion to ``out`` chunk by chunk.

    Parameters
    ----------
    left, right : path
        Footage of the left (and right) camera; ``right`` None: one camera.
    out : path
        Body motion (.nc), written after every chunk of frames.
    bodies : path
        The regions-of-interest TOML file (recorded as an input).
    config, specs
        Its options and bodies (:func:`read_bodies`, :func:`with_overrides`).
    calibration : path, optional
        Stereo calibration (two cameras).
    plot : path, optional
        Also write the velocity/displacement plot.
    **options
        Passed to :func:`track_footage` (``fps``, ``max_frames``, ``resume``, ``scheduler``).
    """
    from jointwear.dic.calibration import read_calibration
    from jointwear.dic.footage._track import track_footage

    cal = read_calibration(calibration) if calibration is not None else None
    inputs = [p for p in (left, right, bodies, calibration) if p is not None]
    ds = track_footage(
        left,
        right,
        bodies=specs,
        calibration=cal,
        config=config,
        out=out,
        progress=True,
        inputs=tuple(inputs),
        **options,
    )
    if plot is not None:
        from jointwear.dic.footage._plot import plot_body_motion

        plot_body_motion(ds, path=plot)
    return ds
