"""``jointwear datasets speckle``: synthetic speckle images with exact ground truth.

Every default and limit is the library's (:mod:`jointwear.datasets._speckle_params`, read
without numpy): ``SpeckleParams`` for the pattern and camera, ``SpeckleMotion`` for the field.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from jointwear._cli import Overwrite
from jointwear._cli_dataclass import Opt, options_from
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
    closed_interval,
    open_interval,
)


@options_from(
    "params",
    SpeckleParams,
    Opt(
        "speckle_size",
        help=f"Speckle diameter (pixels), {closed_interval(SPECKLE_SIZE_RANGE)}.",
    ),
    Opt("density", help=f"Area fraction covered by speckles, {open_interval(DENSITY_RANGE)}."),
    Opt("contrast", help=f"Fraction of full scale, {open_interval(CONTRAST_RANGE)}."),
    Opt("noise_std", "--noise", help="Noise std (grey levels)."),
    Opt("blur_std", "--blur", help="Gaussian PSF std (pixels)."),
    Opt(
        "bit_depth",
        help=f"8 or up to {BIT_DEPTH_MAX}.",
        min=PNG_BIT_DEPTH_MIN,
        max=BIT_DEPTH_MAX,
    ),
)
@options_from("motion", SpeckleMotion)
def speckle_cmd(
    out: Annotated[Path, typer.Argument(help="Output folder.")],
    overwrite: Overwrite = False,
    size: Annotated[str, typer.Option("--size", help="WIDTHxHEIGHT (pixels).")] = "512x512",
    motion: SpeckleMotion = SpeckleMotion(),
    frames: Annotated[
        int,
        typer.Option(
            "--frames", min=MIN_FRAMES, help="Number of deformed frames (field ramps up)."
        ),
    ] = DEFAULT_FRAMES,
    params: SpeckleParams = SpeckleParams(),
    seed: Annotated[int, typer.Option("--seed", help="Random seed.")] = DEFAULT_SEED,
) -> None:
    """Write reference/deformed speckle PNGs and the exact displacement (truth.nc)."""
    from jointwear.datasets.speckle_set import write_speckle_set
    from jointwear.errors import BadInputError

    try:
        w, h = (int(s) for s in size.lower().split("x"))
    except ValueError:
        raise BadInputError(f"--size {size!r}: expected WIDTHxHEIGHT, e.g. 512x512") from None
    names = write_speckle_set(out, (h, w), motion, frames=frames, params=params, seed=seed)
    typer.echo(f"{out}: {', '.join(names)} and truth.nc ({w}x{h} pixels, field {motion.field})")


def register(app: typer.Typer) -> None:
    """Add ``speckle`` to the ``jointwear datasets`` group."""
    app.command("speckle")(speckle_cmd)
