"""``jointwear datasets instruments OUT``: write realistic roundness-instrument files with truth."""

# (no ``from __future__ import annotations``: the option declarations are evaluated once, here,
# not compiled again from strings when ``options_from`` reads them at every start of the CLI)
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Literal

import typer

from jointwear._cli import Overwrite
from jointwear._cli_dataclass import options_from
from jointwear._version import source_attribute
from jointwear.datasets import _instrument_defaults as D

#: names of the field separators the command takes
DELIMITERS = {"tab": "\t", "semicolon": ";", "comma": ",", "space": " ", "whitespace": " "}


def _shown(value: float, per_si: float) -> float:
    """A library default [SI] in the option's unit (``per_si`` units per SI unit), as typed."""
    return float(f"{value * per_si:.12g}")


def _ecc_um() -> tuple[float, float]:
    return (_shown(D.ECCENTRICITY[0], 1e6), _shown(D.ECCENTRICITY[1], 1e6))


@dataclass(frozen=True)
class _ExportFormat:
    """How the instrument's files are written (an option group of ``instruments_cmd``)."""

    layout: Annotated[
        Literal["folder", "folder-names", "folder-header", "long", "wide", "single"],
        typer.Option("--layout", help="folder, folder-names, folder-header, long, wide or single."),
    ] = D.LAYOUT
    value: Annotated[
        Literal["deviation", "radius"], typer.Option("--value", help="deviation or radius.")
    ] = D.VALUE
    units: Annotated[str, typer.Option("--units", help="um, mm, m or inch.")] = D.UNITS
    angle: Annotated[
        Literal["deg", "rad", "index", "none", "xy"],
        typer.Option("--angle", help="Angle column: deg, rad, index, none or xy."),
    ] = D.ANGLE
    delimiter: Annotated[
        str, typer.Option("--delimiter", help="tab, semicolon, comma or space.")
    ] = next(k for k, v in DELIMITERS.items() if v == D.DELIMITER)
    decimal: Annotated[str, typer.Option("--decimal", help="'.' or ','.")] = D.DECIMAL

    def keywords(self) -> dict[str, str]:
        """The keywords of :func:`jointwear.datasets.instruments.write`."""
        return {
            "layout": self.layout,
            "value": self.value,
            "units": self.units,
            "angle": self.angle,
            "delimiter": DELIMITERS.get(self.delimiter, self.delimiter),
            "decimal": self.decimal,
        }


@dataclass(frozen=True)
class _ImposedWear:
    """The wear imposed on the bore: the built-in pattern of ``--wear-um`` deep, or a simulated
    bore's (``--wear-from``, scaled and turned); an option group of ``instruments_cmd``."""

    wear_um: Annotated[
        float, typer.Option("--wear-um", help="Peak depth of the imposed wear [µm] (0: none).")
    ] = _shown(D.WEAR_DEPTH, 1e6)
    wear_from: Annotated[
        Path | None,
        typer.Option(
            "--wear-from",
            help="Take the imposed wear from a 'jointwear sim wear' result (last snapshot) "
            "instead of the built-in pattern; --wear-um is then not used.",
        ),
    ] = None
    wear_scale: Annotated[
        float,
        typer.Option("--wear-scale", help="Factor on the wear taken with --wear-from [1]."),
    ] = 1.0
    wear_rotation_deg: Annotated[
        float,
        typer.Option(
            "--wear-rotation-deg",
            help="Turn of the wear taken with --wear-from, canonical sense [degree].",
        ),
    ] = 0.0

    def pattern(self) -> tuple[object, float | None]:
        """The generator's ``wear`` ("default", None or the simulated map) and the simulated
        bore's radius [m] (None: not stated, or no simulation)."""
        if self.wear_from is None:
            return ("default" if self.wear_um > 0 else None), None
        from jointwear import io
        from jointwear.datasets.simulated_wear import wear_from_simulation

        sim = io.load(self.wear_from)
        wear = wear_from_simulation(sim, scale=self.wear_scale, rotation_deg=self.wear_rotation_deg)
        return wear, sim.attrs.get("bearing_radius_m")


@options_from("export", _ExportFormat)
@options_from("imposed", _ImposedWear)
def instruments_cmd(
    out: Annotated[Path, typer.Argument(help="Output folder (or file for long/wide/single).")],
    overwrite: Overwrite = False,
    layers: Annotated[int, typer.Option("--layers", help="Number of layers.")] = D.N_LAYERS,
    points: Annotated[int, typer.Option("--points", help="Points per layer.")] = D.N_POINTS,
    radius_mm: Annotated[
        float | None,
        typer.Option(
            "--radius-mm",
            help=f"Bore radius [mm] (default {_shown(D.RADIUS, 1e3):g}, or the simulated bore's "
            "with --wear-from).",
        ),
    ] = None,
    spacing_mm: Annotated[float, typer.Option("--spacing-mm", help="Layer spacing [mm].")] = _shown(
        D.LAYER_SPACING, 1e3
    ),
    *,
    export: _ExportFormat,
    eccentricity_um: Annotated[
        tuple[float, float], typer.Option("--eccentricity-um", help="Set-up offset x y [µm].")
    ] = _ecc_um(),
    tilt: Annotated[
        tuple[float, float], typer.Option("--tilt", help="Axis slopes dx/dz dy/dz [1].")
    ] = D.TILT,
    imposed: _ImposedWear,
    noise_um: Annotated[float, typer.Option("--noise-um", help="Probe noise [µm].")] = _shown(
        D.NOISE, 1e6
    ),
    quantisation_nm: Annotated[
        float, typer.Option("--quantisation-nm", help="Reading resolution [nm].")
    ] = _shown(D.QUANTISATION, 1e9),
    angle_zero: Annotated[
        str, typer.Option("--angle-zero", help="Instrument 0 degree in the bearing frame.")
    ] = D.CONVENTION[0],
    angle_direction: Annotated[
        str, typer.Option("--angle-direction", help="Instrument angle sense.")
    ] = D.CONVENTION[1],
    seed: Annotated[int, typer.Option("--seed", help="Random seed (form and noise).")] = D.SEED,
    noise_seed: Annotated[
        int | None,
        typer.Option("--noise-seed", help="Separate noise seed (same bore, new measurement)."),
    ] = None,
    truth: Annotated[
        Path | None,
        typer.Option("--truth", help="Also save the truth (radius, wear) as netCDF."),
    ] = None,
) -> None:
    """Generate a virtual roundness-instrument scan of a worn bore with known truth."""
    from jointwear import io
    from jointwear.datasets.instruments import generate, write

    wear, sim_radius = imposed.pattern()
    radius = D.RADIUS if radius_mm is None else radius_mm / 1e3
    if radius_mm is None and sim_radius is not None:
        radius = float(sim_radius)
    sc = generate(
        n_layers=layers,
        n_points=points,
        radius=radius,
        layer_spacing=spacing_mm / 1e3,
        eccentricity=(eccentricity_um[0] / 1e6, eccentricity_um[1] / 1e6),
        tilt=tilt,
        wear=wear,
        wear_depth=imposed.wear_um / 1e6,
        noise=noise_um / 1e6,
        quantisation=quantisation_nm / 1e9,
        convention=(angle_zero, angle_direction),
        seed=seed,
        noise_seed=noise_seed,
    )
    files = write(sc, out, **export.keywords())
    typer.echo(f"wrote {len(files)} file(s) under {out}")
    typer.echo(
        f"import with: jointwear metrology import {out} --angle-zero {angle_zero} "
        f"--angle-direction {angle_direction} --out scan.nc"
    )
    if truth is not None:
        t = sc.truth
        io.save(
            t,
            truth,
            source=source_attribute("datasets.instruments"),
            parameters={
                "layers": layers,
                "points": points,
                "seed": seed,
                "layout": export.layout,
                "wear_from": None if imposed.wear_from is None else str(imposed.wear_from),
                "wear_scale": imposed.wear_scale,
                "wear_rotation_deg": imposed.wear_rotation_deg,
            },
        )
        typer.echo(f"wrote {truth}")


def register(app: typer.Typer) -> None:
    """Add ``jointwear datasets instruments``."""
    app.command("instruments")(instruments_cmd)
