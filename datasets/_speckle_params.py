"""The parameters of a synthetic speckle data set, one source for the library and ``jointwear
datasets speckle`` (light: the CLI reads these defaults and limits without importing numpy).

:class:`SpeckleParams` is public as ``jointwear.datasets.speckle.SpeckleParams``,
:class:`SpeckleMotion` and :data:`FIELDS` as ``jointwear.datasets.speckle_set.…``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal, get_args

from jointwear.errors import ParameterError

if TYPE_CHECKING:
    from jointwear.datasets.speckle import Field

__all__ = [
    "BIT_DEPTH_MAX",
    "CONTRAST_RANGE",
    "DEFAULT_FRAMES",
    "DENSITY_RANGE",
    "DEFAULT_SEED",
    "FIELDS",
    "MIN_FRAMES",
    "PNG_BIT_DEPTH_MIN",
    "SPECKLE_SIZE_RANGE",
    "SpeckleMotion",
    "SpeckleParams",
    "closed_interval",
    "open_interval",
]

#: Deepest grey scale of an image [bit]; a PNG needs at least PNG_BIT_DEPTH_MIN (0, floating
#: point grey levels, is an array only).
BIT_DEPTH_MAX = 16
PNG_BIT_DEPTH_MIN = 1

#: What :class:`SpeckleParams` accepts, as its errors and ``datasets speckle --help`` say it:
#: speckle diameter [pixel] from..to (both included); area fraction and contrast in (0, max].
SPECKLE_SIZE_RANGE = (1.0, 200.0)
DENSITY_RANGE = (0.0, 5.0)
CONTRAST_RANGE = (0.0, 1.0)

#: Displacement fields of a speckle data set.
FieldName = Literal["rigid", "affine", "rotation", "sinusoidal"]
FIELDS = get_args(FieldName)

#: Deformed frames of a data set: the default and the fewest.
DEFAULT_FRAMES = MIN_FRAMES = 1
#: Seed of the pattern and the noise.
DEFAULT_SEED = 0


def closed_interval(bounds: tuple[float, float]) -> str:
    """``"1 to 200"``: the interval of a speckle size (both ends included), as the errors and
    the CLI help write it."""
    return f"{bounds[0]:g} to {bounds[1]:g}"


def open_interval(bounds: tuple[float, float]) -> str:
    """``"in (lo, hi]"``: the interval of a density or contrast, as the errors and the CLI
    help write it."""
    return f"in ({bounds[0]:g}, {bounds[1]:g}]"


@dataclass(frozen=True)
class SpeckleParams:
    """Pattern and camera parameters of a synthetic speckle image.

    Parameters
    ----------
    speckle_size : float
        Nominal speckle diameter [pixel]; each blob is a Gaussian of standard deviation
        ``speckle_size / 4``.
    density : float
        Expected fraction of the area covered by speckles (number of blobs = ``density * area /
        (pi * (speckle_size / 2)**2)``), in (0, 5].
    contrast : float
        Difference between the brightest and darkest intensity as a fraction of full scale,
        in (0, 1].
    bit_depth : int
        Bits per pixel of the output (1..16); 0 returns floating point grey levels unrounded.
    noise_std : float
        Standard deviation of additive Gaussian noise [grey levels of the output scale].
    blur_std : float
        Standard deviation of a Gaussian point-spread function in the image plane [pixel].
    dark_speckles : bool
        Dark speckles on a bright background (default False: bright on dark).
    """

    speckle_size: float = 5.0
    density: float = 0.6
    contrast: float = 0.8
    bit_depth: int = 8
    noise_std: float = 0.0
    blur_std: float = 0.0
    dark_speckles: bool = False

    def __post_init__(self) -> None:
        size_min, size_max = SPECKLE_SIZE_RANGE
        checks = [
            (
                "speckle_size",
                size_min <= self.speckle_size <= size_max,
                f"{closed_interval(SPECKLE_SIZE_RANGE)} pixel",
            ),
            (
                "density",
                DENSITY_RANGE[0] < self.density <= DENSITY_RANGE[1],
                open_interval(DENSITY_RANGE),
            ),
            (
                "contrast",
                CONTRAST_RANGE[0] < self.contrast <= CONTRAST_RANGE[1],
                open_interval(CONTRAST_RANGE),
            ),
            (
                "bit_depth",
                0 <= int(self.bit_depth) <= BIT_DEPTH_MAX,
                f"0 (float) or 1..{BIT_DEPTH_MAX}",
            ),
            ("noise_std", self.noise_std >= 0.0, ">= 0 grey levels"),
            ("blur_std", self.blur_std >= 0.0, ">= 0 pixel"),
        ]
        for name, ok, expected in checks:
            if not ok:
                raise ParameterError(
                    f"speckle parameter {name}={getattr(self, name)!r} is out of range; expected "
                    f"{expected}"
                )

    @property
    def full_scale(self) -> float:
        """Largest grey level (``2**bit_depth - 1``, or 1.0 for floating point output)."""
        return float(2 ** int(self.bit_depth) - 1) if self.bit_depth else 1.0


@dataclass(frozen=True)
class SpeckleMotion:
    """The displacement field of the last frame of a speckle data set (pixel units).

    ``rigid``: translation (``u``, ``v``) and rotation ``theta_deg`` about the image centre;
    ``rotation``: the rotation alone; ``affine``: normal strain exx = ``strain``,
    eyy = -strain/2 with that rotation and translation; ``sinusoidal``: u of ``amplitude``
    varying along x with ``wavelength``.

    Parameters
    ----------
    field : str
        rigid, affine, rotation or sinusoidal.
    u : float
        Translation along x [pixel].
    v : float
        Translation along y [pixel].
    theta_deg : float
        Rotation [degree], +x towards +y.
    strain : float
        Affine: normal strain exx = -eyy/2.
    amplitude : float
        Sinusoidal: amplitude of u [pixel].
    wavelength : float
        Sinusoidal: wavelength [pixel].
    """

    field: FieldName = "rigid"
    u: float = 1.5
    v: float = -0.7
    theta_deg: float = 0.0
    strain: float = 0.01
    amplitude: float = 2.0
    wavelength: float = 128.0

    def __post_init__(self) -> None:
        if self.field not in FIELDS:
            raise ParameterError(f"field {self.field!r}: expected one of {', '.join(FIELDS)}")

    def at(self, shape: tuple[int, int], scale: float = 1.0) -> Field:
        """The field on a reference image of ``shape`` (height, width), its amplitudes scaled
        by ``scale`` (the sinusoid's wavelength is not)."""
        from jointwear.datasets import speckle as sp

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
