"""``jointwear import``: bring motion and wear maps from other simulators and instruments in."""

from __future__ import annotations

from enum import StrEnum
from pathlib import Path
from typing import Annotated

import typer

from jointwear import _import_defaults as D
from jointwear._cli import AngleDirection, AngleZero, Overwrite

app = typer.Typer(
    help="Import your own data (CSV or CF netCDF from other simulators and instruments).",
    no_args_is_help=True,
)


class Origin(StrEnum):
    """What the numbers of an imported file are."""

    simulated = "simulated"
    measured = "measured"
    synthetic = "synthetic"


# options of every import command
_Out = Annotated[Path, typer.Option("--out", "-o", help="The jointwear netCDF file to write.")]
_Origin = Annotated[
    Origin | None,
    typer.Option(
        "--origin",
        help="What the numbers are: simulated, measured or synthetic (required for CSV).",
    ),
]
_Tool = Annotated[
    str | None, typer.Option("--tool", help="The program that wrote the file, e.g. 'Adams 2024'.")
]

_CF_SUFFIXES = (".nc", ".nc4", ".cdf")
"""File endings read as CF netCDF; any other file is read as a CSV table."""


def _names(text: str, option: str, count: tuple[int, int]) -> list[str]:
    from jointwear.errors import ParameterError

    names = [n.strip() for n in text.split(",") if n.strip()]
    if not count[0] <= len(names) <= count[1]:
        raise ParameterError(
            f"{option}: expected {count[0]}-{count[1]} comma-separated names, got {text!r}"
        )
    return names


def _from_cf(file: Path, variable: str, **options):
    """A CF netCDF file read by :func:`jointwear.external.import_cf` with ``options``; refused
    when it does not hold ``variable``."""
    from jointwear import external
    from jointwear.errors import ParameterError

    ds = external.import_cf(file, **options)
    if variable not in ds:
        raise ParameterError(f"'{file}' has no variable '{variable}'")
    return ds


def _needed(table: str, never: str, *given: tuple[str, str | None]) -> list[str]:
    """The values of ``given`` (``(flag, value)`` pairs), which a CSV ``table`` needs: it
    states neither its units nor its conventions, and jointwear ``never`` guesses them; a
    missing one is refused, naming every missing flag."""
    from jointwear.errors import ParameterError

    missing = [flag for flag, value in given if value is None]
    if missing:
        raise ParameterError(f"{table} needs {', '.join(missing)}: jointwear never guesses {never}")
    return [value for _, value in given if value is not None]


def _save(ds, out: Path, source: Path) -> None:
    from jointwear import io

    io.save(ds, out, inputs=[source], parameters={"external": True, **ds.attrs})
    typer.echo(f"wrote {out} ({ds.attrs['data_origin']}, from {source.name})")


@app.command("motion")
def motion(
    file: Annotated[Path, typer.Argument(help="CSV table (header row) or CF netCDF file.")],
    out: _Out,
    overwrite: Overwrite = False,
    origin: _Origin = None,
    velocity_unit: Annotated[
        str | None, typer.Option("--velocity-unit", help="Unit of the velocity columns, e.g. mm/s.")
    ] = None,
    time_unit: Annotated[
        str, typer.Option("--time-unit", help="Unit of the time column.")
    ] = D.TIME_UNIT,
    time_column: Annotated[
        str, typer.Option("--time-column", help="Name of the time column.")
    ] = D.TIME_COLUMN,
    velocity_columns: Annotated[
        str,
        typer.Option("--velocity-columns", help="Velocity column names x,y[,z] (bearing frame)."),
    ] = ",".join(D.VELOCITY_COLUMNS),
    tool: _Tool = None,
) -> None:
    """Import a follower motion history: time and velocity columns with stated units."""
    from jointwear import external

    data_origin = origin.value if origin else None
    if file.suffix.lower() in _CF_SUFFIXES:
        ds = _from_cf(file, "follower_velocity", data_origin=data_origin, tool=tool)
    else:
        csv_origin, unit = _needed(
            "a CSV motion table",
            "units or what the numbers are (simulated, measured or synthetic)",
            ("--origin", data_origin),
            ("--velocity-unit", velocity_unit),
        )
        ds = external.import_motion(
            file,
            velocity_unit=unit,
            time_unit=time_unit,
            time_column=time_column,
            velocity_columns=_names(velocity_columns, "--velocity-columns", (2, 3)),
            data_origin=csv_origin,
            tool=tool,
        )
    _save(ds, out, file)


@app.command("wearmap")
def wearmap(
    file: Annotated[Path, typer.Argument(help="CSV table (theta, z, depth per row) or CF netCDF.")],
    out: _Out,
    overwrite: Overwrite = False,
    origin: _Origin = None,
    angle_zero: AngleZero = None,
    angle_direction: AngleDirection = None,
    theta_unit: Annotated[str | None, typer.Option("--theta-unit", help="deg or rad.")] = None,
    z_unit: Annotated[str | None, typer.Option("--z-unit", help="Unit of z, e.g. mm.")] = None,
    depth_unit: Annotated[
        str | None, typer.Option("--depth-unit", help="Unit of depth, e.g. um.")
    ] = None,
    columns: Annotated[
        str, typer.Option("--columns", help="Names of the theta, z and depth columns.")
    ] = ",".join(D.WEAR_MAP_COLUMNS),
    z_mid_width: Annotated[
        float,
        typer.Option("--z-mid-width", help="z of the bearing mid-width in the file [z unit]."),
    ] = D.Z_MID_WIDTH,
    cycles: Annotated[
        float | None, typer.Option("--cycles", help="Crank cycles the map belongs to.")
    ] = None,
    tool: _Tool = None,
) -> None:
    """Import a wear map (depth positive where material was removed) with stated units and angle convention."""
    from jointwear import external

    data_origin = origin.value if origin else None
    if file.suffix.lower() in _CF_SUFFIXES:
        ds = _from_cf(
            file,
            "wear_depth",
            data_origin=data_origin,
            angle_zero=angle_zero,
            angle_direction=angle_direction,
            tool=tool,
        )
    else:
        csv_origin, zero, direction, theta_u, z_u, depth_u = _needed(
            "a CSV wear map",
            "units or where theta = 0 is",
            ("--origin", data_origin),
            ("--angle-zero", angle_zero),
            ("--angle-direction", angle_direction),
            ("--theta-unit", theta_unit),
            ("--z-unit", z_unit),
            ("--depth-unit", depth_unit),
        )
        ds = external.import_wear_map(
            file,
            theta_unit=theta_u,
            z_unit=z_u,
            depth_unit=depth_u,
            angle_zero=zero,
            angle_direction=direction,
            data_origin=csv_origin,
            columns=_names(columns, "--columns", (3, 3)),
            z_mid_width=z_mid_width,
            cycles=cycles,
            tool=tool,
        )
    _save(ds, out, file)


@app.command("reported")
def reported(
    file: Annotated[Path, typer.Argument(help="Reported-measurement TOML file (schema in docs).")],
    out: _Out,
    overwrite: Overwrite = False,
) -> None:
    """Import reported measurements (a lab sheet's or a paper's numbers) from a TOML file."""
    from jointwear import io
    from jointwear.params import read_toml
    from jointwear.reported import reported_dataset

    data = read_toml(file)
    ds = reported_dataset(data, file)
    io.save(ds, out, inputs=[file], parameters={"reported": data})
    typer.echo(f"wrote {out} ({ds.attrs['data_origin']}, {len(ds.data_vars) // 2} quantities)")
