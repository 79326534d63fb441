"""A speckle data set on disk: reference and deformed PNGs with their exact displacement.

:func:`write_speckle_set` renders the frames with :mod:`jointwear.datasets.speckle` for a
:class:`SpeckleMotion`, one of the :data:`FIELDS` (ramped up over the frames), and writes them with ``truth.nc``, the Lagrangian
displacement of every reference pixel; ``jointwear datasets speckle`` is its command.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import xarray as xr

from jointwear._version import source_attribute
from jointwear.datasets import speckle as sp
from jointwear.datasets._speckle_params import (
    BIT_DEPTH_MAX,
    DEFAULT_FRAMES,
    DEFAULT_SEED,
    FIELDS,
    MIN_FRAMES,
    PNG_BIT_DEPTH_MIN,
    SpeckleMotion,
)
from jointwear.errors import BadInputError, ParameterError
from jointwear.io import atomic_path, save

__all__ = ["FIELDS", "SpeckleMotion", "write_speckle_set"]


def write_speckle_set(
    out: str | Path,
    shape: tuple[int, int],
    motion: SpeckleMotion | None = None,
    *,
    frames: int = DEFAULT_FRAMES,
    params: sp.SpeckleParams | None = None,
    seed: int = DEFAULT_SEED,
) -> list[str]:
    """Render and write a speckle data set to the folder ``out``; return the image names.

    Parameters
    ----------
    out : path
        Output folder (created): ``reference.png`` and ``deformed.png`` (one frame) or
        ``frame_0000.png`` ... (frame 0 the reference), and ``truth.nc``.
    shape : (int, int)
        Image height and width [pixel].
    motion : SpeckleMotion, optional
        The displacement of the last frame (default ``SpeckleMotion()``); frame k of ``frames``
        has it scaled by k / frames.
    frames : int
        Number of deformed frames (>= 1); with more than one, ``truth.nc`` has a ``time``
        dimension (one frame per second, the reference at 0).
    params : SpeckleParams, optional
        Pattern and camera (default ``SpeckleParams()``).
    seed : int
        Seed of the pattern and the noise.
    """
    if frames < MIN_FRAMES:
        raise ParameterError(f"frames={frames}: expected >= {MIN_FRAMES}")
    motion = SpeckleMotion() if motion is None else motion
    params = sp.SpeckleParams() if params is None else params
    if not PNG_BIT_DEPTH_MIN <= params.bit_depth <= BIT_DEPTH_MAX:
        raise ParameterError(
            f"bit_depth={params.bit_depth}: expected {PNG_BIT_DEPTH_MIN}..{BIT_DEPTH_MAX} "
            "(PNG output)"
        )
    fields = [motion.at(shape, (k + 1) / frames) for k in range(frames)]
    images = sp.speckle_sequence(shape, [None, *fields], params=params, seed=seed)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    names = (
        ["reference.png", "deformed.png"]
        if frames == 1
        else [f"frame_{k:04d}.png" for k in range(frames + 1)]
    )
    for name, img in zip(names, images, strict=True):
        _write_png(out / name, img)
    save(
        _truth(fields, shape, motion.field, names),
        out / "truth.nc",
        parameters={
            "speckle": params,
            **dataclasses.asdict(motion),
            "frames": frames,
            "seed": seed,
        },
        source=source_attribute("datasets.speckle"),
    )
    return names


def _write_png(path: Path, image: np.ndarray) -> None:
    import cv2

    with atomic_path(path) as tmp:
        ok, buf = cv2.imencode(".png", image)
        if not ok:
            raise BadInputError(f"could not encode {path.name} as PNG")
        tmp.write_bytes(buf.tobytes())


def _truth(fields: list[sp.Field], shape: tuple[int, int], kind: str, names: list[str]):
    """The displacement of every frame (zero for the reference) as one Dataset."""
    truths = [sp.truth_dataset(f, shape) for f in fields]
    truth = truths[0]
    if len(fields) > 1:
        truth = xr.concat([xr.zeros_like(truths[0]), *truths], dim="time")
        truth = truth.assign_coords(
            time=(
                "time",
                np.arange(len(fields) + 1, dtype=float),
                {"units": "s", "long_name": "frame index (1 frame per second)"},
            )
        )
    truth.attrs.update(
        {
            "title": "synthetic speckle ground truth (Lagrangian displacement of reference pixels)",
            "field_kind": kind,
            "images": ", ".join(names),
        }
    )
    return truth
