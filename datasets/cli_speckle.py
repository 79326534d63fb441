"""``jointwear datasets speckle``: synthetic speckle images with exact ground truth."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Literal

import typer

from jointwear._cli import Overwrite


def speckle_cmd(
    out: Annotated[Path, typer.Argument(help="Output folder.")],
    overwrite: Overwrite = False,
    size: Annotated[str, typer.Option("--size", help="WIDTHxHEIGHT (pixels).")] = "512x512",
    field: Annotated[
        Literal["rigid", "affine", "rotation", "sinusoidal"],
        typer.Option("--field", help="rigid, affine, rotation or sinusoidal."),
    ] = "rigid",
    u: Annotated[float, typer.Option("--u", help="Translation along x (pixels).")] = 1.5,
    v: Annotated[float, typer.Option("--v", help="Translation along y (pixels).")] = -0.7,
    theta_deg: Annotated[
        float, typer.Option("--theta-deg", help="Rotation (degrees), +x towards +y.")
    ] = 0.0,
    strain: Annotated[
        float, typer.Option("--strain", help="Affine: normal strain exx = -eyy/2.")
    ] = 0.01,
    amplitude: Annotated[
        float, typer.Option("--amplitude", help="Sinusoidal: amplitude of u (pixels).")
    ] = 2.0,
    wavelength: Annotated[
        float, typer.Option("--wavelength", help="Sinusoidal: wavelength (pixels).")
    ] = 128.0,
    frames: Annotated[
        int, typer.Option("--frames", min=1, help="Number of deformed frames (field ramps up).")
    ] = 1,
    speckle_size: Annotated[
        float, typer.Option("--speckle-size", help="Speckle diameter (pixels).")
    ] = 5.0,
    density: Annotated[float, typer.Option("--density", help="Area fraction.")] = 0.6,
    contrast: Annotated[float, typer.Option("--contrast", help="0..1 of full scale.")] = 0.8,
    noise: Annotated[float, typer.Option("--noise", help="Noise std (grey levels).")] = 0.0,
    blur: Annotated[float, typer.Option("--blur", help="Gaussian PSF std (pixels).")] = 0.0,
    bit_depth: Annotated[
        int, typer.Option("--bit-depth", min=1, max=16, help="8 or up to 16.")
    ] = 8,
    seed: Annotated[int, typer.Option("--seed", help="Random seed.")] = 0,
) -> None:
    """Write reference/deformed speckle PNGs and the exact displacement (truth.nc)."""
    from jointwear.datasets.speckle import SpeckleParams
    from jointwear.datasets.speckle_set import SpeckleMotion, write_speckle_set
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
