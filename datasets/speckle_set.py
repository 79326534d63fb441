"""A speckle data set on disk: reference and deformed PNGs with their exact displacement.

:func:`write_speckle_set` renders the frames with :mod:`jointwear.datasets.speckle` for a
:class:`SpeckleMotion`, one of the :data:`FIELDS` (ramped up over the frames), and writes them with ``truth.nc``, the Lagrangian
displacement of every reference pixel; ``jointwear datasets speckle`` is its command.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import xarray as xr

from jointwear._version import source_attribute
from jointwear.datasets import speckle as sp
from jointwear.errors import BadInputError, ParameterError
from jointwear.io import atomic_path, save

__all__ = ["FIELDS", "SpeckleMotion", "write_speckle_set"]

#: Displacement fields of a speckle data set.
FIELDS = ("rigid", "affine", "rotation", "sinusoidal")


@dataclass(frozen=True)
class SpeckleMotion:
    """The displacement field of the last frame of a speckle data set (pixel units).

    ``rigid``: translation (``u``, ``v``) [pixel] and rotation ``theta_deg`` [degree] about the
    image centre (+x towards +y); ``rotation``: the rotation alone; ``affine``: normal strain
    exx = ``strain``, eyy = -strain/2 with that rotation and translation; ``sinusoidal``: u of
    ``amplitude`` [pixel] varying along x with ``wavelength`` [pixel].
    """

    field: str = "rigid"
    u: float = 1.5
    v: float = -0.7
    theta_deg: float = 0.0
    strain: float = 0.01
    amplitude: float = 2.0
    wavelength: float = 128.0

    def __post_init__(self) -> None:
        if self.field not in FIELDS:
            raise ParameterError(f"field {self.field!r}: expected one of {', '.join(FIELDS)}")

    def at(self, shape: tuple[int, int], scale: float = 1.0) -> sp.Field:
        """The field on a reference image of ``shape`` (height, width), its amplitudes scaled
        by ``scale`` (the sinusoid's wavelength is not)."""
        h, w = shape
        centre = ((w - 1) / 2, (h - 1) / 2)
        u, v, theta = self.u * scale, self.v * scale, self.theta_deg * scale
        if self.field == "rigid":
            return sp.RigidField((u, v), theta, centre)
        if self.field == "rotation":
            return sp.rotation(theta, centre)
        if self.field == "affine":
            return sp.AffineField.from_strain(
                exx=self.strain * scale,
                eyy=-0.5 * self.strain * scale,
                rotation_deg=theta,
                translation=(u, v),
                center=centre,
            )
        return sp.SinusoidalField((self.amplitude * scale, 0.0), self.wavelength)


def write_speckle_set(
    out: str | Path,
    shape: tuple[int, int],
    motion: SpeckleMotion | None = None,
    *,
    frames: int = 1,
    params: sp.SpeckleParams | None = None,
    seed: int = 0,
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
    if frames < 1:
        raise ParameterError(f"frames={frames}: expected >= 1")
    motion = SpeckleMotion() if motion is None else motion
    params = sp.SpeckleParams() if params is None else params
    if not 1 <= params.bit_depth <= 16:
        raise ParameterError(f"bit_depth={params.bit_depth}: expected 1..16 (PNG output)")
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
