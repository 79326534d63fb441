"""``jointwear datasets speckle``: synthetic speckle images with exact ground truth.

Every default and limit is the library's (:mod:`jointwear.datasets._speckle_params`, read
without numpy): ``SpeckleParams`` for the pattern and camera, ``SpeckleMotion`` for the field.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Literal

import typer

from jointwear._cli import Overwrite
from jointwear.datasets._speckle_params import (
    BIT_DEPTH_MAX,
    CONTRAST_RANGE,
    DEFAULT_FRAMES,
    DEFAULT_SEED,
    DENSITY_RANGE,
    MIN_FRAMES,
    PNG_BIT_DEPTH_MIN,
    SPECKLE_SIZE_RANGE,
    SpeckleMotion,
    SpeckleParams,
    open_interval,
)


def speckle_cmd(
    out: Annotated[Path, typer.Argument(help="Output folder.")],
    overwrite: Overwrite = False,
    size: Annotated[str, typer.Option("--size", help="WIDTHxHEIGHT (pixels).")] = "512x512",
    field: Annotated[
        Literal["rigid", "affine", "rotation", "sinusoidal"],
        typer.Option("--field", help="rigid, affine, rotation or sinusoidal."),
    ] = SpeckleMotion.field,
    u: Annotated[
        float, typer.Option("--u", help="Translation along x (pixels).")
    ] = SpeckleMotion.u,
    v: Annotated[
        float, typer.Option("--v", help="Translation along y (pixels).")
    ] = SpeckleMotion.v,
    theta_deg: Annotated[
        float, typer.Option("--theta-deg", help="Rotation (degrees), +x towards +y.")
    ] = SpeckleMotion.theta_deg,
    strain: Annotated[
        float, typer.Option("--strain", help="Affine: normal strain exx = -eyy/2.")
    ] = SpeckleMotion.strain,
    amplitude: Annotated[
        float, typer.Option("--amplitude", help="Sinusoidal: amplitude of u (pixels).")
    ] = SpeckleMotion.amplitude,
    wavelength: Annotated[
        float, typer.Option("--wavelength", help="Sinusoidal: wavelength (pixels).")
    ] = SpeckleMotion.wavelength,
    frames: Annotated[
        int,
        typer.Option(
            "--frames", min=MIN_FRAMES, help="Number of deformed frames (field ramps up)."
        ),
    ] = DEFAULT_FRAMES,
    speckle_size: Annotated[
        float,
        typer.Option(
            "--speckle-size",
            help="Speckle diameter (pixels), {:g} to {:g}.".format(*SPECKLE_SIZE_RANGE),
        ),
    ] = SpeckleParams.speckle_size,
    density: Annotated[
        float,
        typer.Option(
            "--density",
            help=f"Area fraction covered by speckles, {open_interval(DENSITY_RANGE)}.",
        ),
    ] = SpeckleParams.density,
    contrast: Annotated[
        float,
        typer.Option(
            "--contrast", help=f"Fraction of full scale, {open_interval(CONTRAST_RANGE)}."
        ),
    ] = SpeckleParams.contrast,
    noise: Annotated[
        float, typer.Option("--noise", help="Noise std (grey levels).")
    ] = SpeckleParams.noise_std,
    blur: Annotated[
        float, typer.Option("--blur", help="Gaussian PSF std (pixels).")
    ] = SpeckleParams.blur_std,
    bit_depth: Annotated[
        int,
        typer.Option(
            "--bit-depth",
            min=PNG_BIT_DEPTH_MIN,
            max=BIT_DEPTH_MAX,
            help=f"8 or up to {BIT_DEPTH_MAX}.",
        ),
    ] = SpeckleParams.bit_depth,
    seed: Annotated[int, typer.Option("--seed", help="Random seed.")] = DEFAULT_SEED,
) -> None:
    """Write reference/deformed speckle PNGs and the exact displacement (truth.nc)."""
    from jointwear.datasets.speckle_set import write_speckle_set
    from jointwear.errors import BadInputError

    try:
        w, h = (int(s) for s in size.lower().split("x"))
    except ValueError:
        raise BadInputError(f"--size {size!r}: expected WIDTHxHEIGHT, e.g. 512x512") from None
    params = SpeckleParams(
        speckle_size=speckle_size,
        density=density,
        contrast=contrast,
        bit_depth=bit_depth,
        noise_std=noise,
        blur_std=blur,
    )
    motion = SpeckleMotion(field, u, v, theta_deg, strain, amplitude, wavelength)
    names = write_speckle_set(out, (h, w), motion, frames=frames, params=params, seed=seed)
    typer.echo(f"{out}: {', '.join(names)} and truth.nc ({w}x{h} pixels, field {field})")


def register(app: typer.Typer) -> None:
    """Add ``speckle`` to the ``jointwear datasets`` group."""
    app.command("speckle")(speckle_cmd)
