"""``jointwear datasets speckle``: synthetic speckle images with exact ground truth."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Literal

import typer

from jointwear._cli import Overwrite

FIELDS = ("rigid", "affine", "rotation", "sinusoidal")


def register(app: typer.Typer) -> None:
    """Add ``speckle`` to the ``jointwear datasets`` group."""

    @app.command("speckle")
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
        import cv2
        import numpy as np
        import xarray as xr

        from jointwear._version import __version__
        from jointwear.datasets import speckle as sp
        from jointwear.errors import BadInputError, ParameterError
        from jointwear.io import atomic_path, save

        try:
            w, h = (int(s) for s in size.lower().split("x"))
        except ValueError:
            raise BadInputError(f"--size {size!r}: expected WIDTHxHEIGHT, e.g. 512x512") from None
        if field not in FIELDS:
            raise ParameterError(f"--field {field!r}: expected one of {', '.join(FIELDS)}")
        if frames < 1:
            raise ParameterError(f"--frames {frames}: expected >= 1")
        if not 1 <= bit_depth <= 16:
            raise ParameterError(f"--bit-depth {bit_depth}: expected 1..16 (PNG output)")
        centre = ((w - 1) / 2, (h - 1) / 2)

        def make(scale: float) -> sp.Field:
            if field == "rigid":
                return sp.RigidField((u * scale, v * scale), theta_deg * scale, centre)
            if field == "rotation":
                return sp.rotation(theta_deg * scale, centre)
            if field == "affine":
                return sp.AffineField.from_strain(
                    exx=strain * scale,
                    eyy=-0.5 * strain * scale,
                    rotation_deg=theta_deg * scale,
                    translation=(u * scale, v * scale),
                    center=centre,
                )
            return sp.SinusoidalField((amplitude * scale, 0.0), wavelength)

        params = sp.SpeckleParams(
            speckle_size=speckle_size,
            density=density,
            contrast=contrast,
            bit_depth=bit_depth,
            noise_std=noise,
            blur_std=blur,
        )
        fields = [make((k + 1) / frames) for k in range(frames)]
        images = sp.speckle_sequence((h, w), [None, *fields], params=params, seed=seed)
        out.mkdir(parents=True, exist_ok=True)
        names = (
            ["reference.png", "deformed.png"]
            if frames == 1
            else [f"frame_{k:04d}.png" for k in range(frames + 1)]
        )
        for name, img in zip(names, images, strict=True):
            with atomic_path(out / name) as tmp:
                ok, buf = cv2.imencode(".png", img)
                if not ok:
                    raise BadInputError(f"could not encode {name} as PNG")
                tmp.write_bytes(buf.tobytes())
        truths = [sp.truth_dataset(f, (h, w)) for f in fields]
        zero = xr.zeros_like(truths[0])
        truth = xr.concat([zero, *truths], dim="time") if frames > 1 else truths[0]
        if frames > 1:
            truth = truth.assign_coords(
                time=(
                    "time",
                    np.arange(frames + 1, dtype=float),
                    {"units": "s", "long_name": "frame index (1 frame per second)"},
                )
            )
        truth.attrs.update(
            {
                "title": "synthetic speckle ground truth (Lagrangian displacement of reference pixels)",
                "field_kind": field,
                "images": ", ".join(names),
            }
        )
        save(
            truth,
            out / "truth.nc",
            parameters={
                "speckle": params,
                "field": field,
                "u": u,
                "v": v,
                "theta_deg": theta_deg,
                "strain": strain,
                "amplitude": amplitude,
                "wavelength": wavelength,
                "frames": frames,
                "seed": seed,
            },
            source=f"jointwear {__version__} (datasets.speckle)",
        )
        typer.echo(f"{out}: {', '.join(names)} and truth.nc ({w}x{h} pixels, field {field})")
