"""``jointwear import``: bring motion and wear maps from other simulators and instruments in."""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum
from pathlib import Path
from typing import Annotated, Any

import typer

from jointwear import _import_defaults as D
from jointwear._cli import AngleDirection, AngleZero, Overwrite
from jointwear._cli_dataclass import options_from

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


def _stated(value: str | None, column: str | None, k: float | None, covers: str | None, count: int):
    """The uncertainty the options state (None when none is), or a refusal naming them."""
    from jointwear.import_uncertainty import StatedUncertainty

    if value is None and column is None:
        if k is not None or covers:
            from jointwear.errors import ParameterError

            raise ParameterError(
                "--u-k/--u-covers: give the uncertainty itself with --u or --u-column"
            )
        return None
    columns = None if column is None else tuple(_names(column, "--u-column", (1, count)))
    return StatedUncertainty(value=value, columns=columns, k=k, covers=covers)


@dataclass(frozen=True)
class _TableFlags:
    """A CSV table's options as given (None: not given): ``--delimiter``, ``--decimal`` and
    the stated uncertainty's ``--u``, ``--u-column``, ``--u-k``, ``--u-covers``; an option
    group (``@options_from("table", _TableFlags)``), each command's last options."""

    delimiter: Annotated[
        str | None,
        typer.Option(
            "--delimiter", help="CSV field delimiter: tab, semicolon, comma or whitespace."
        ),
    ] = None
    decimal: Annotated[
        str | None, typer.Option("--decimal", help="CSV decimal mark: point or comma.")
    ] = None
    u: Annotated[
        str | None,
        typer.Option(
            "--u",
            metavar="VALUE[unit]",
            help="Uncertainty of every point, e.g. 0.5um (default unit: the data's).",
        ),
    ] = None
    u_column: Annotated[
        str | None,
        typer.Option("--u-column", help="Column(s) of the table holding each row's uncertainty."),
    ] = None
    u_k: Annotated[
        float | None,
        typer.Option(
            "--u-k", help="Coverage factor of --u/--u-column: 1 standard, 2 expanded (95 %)."
        ),
    ] = None
    u_covers: Annotated[
        str | None,
        typer.Option("--u-covers", help="What the uncertainty covers, e.g. 'probe noise'."),
    ] = None

    def reading(self, count: int) -> Any:
        """The library's :class:`~jointwear.external.CsvReading` of these options, with at most
        ``count`` ``--u-column`` names."""
        from jointwear.external import CsvReading

        stated = _stated(self.u, self.u_column, self.u_k, self.u_covers, count)
        return CsvReading(delimiter=self.delimiter, decimal=self.decimal, uncertainty=stated)

    def csv_only(self, file: Path, name: str) -> None:
        """The --u options state a CSV table's uncertainty; a CF file states its own."""
        if any(v is not None for v in (self.u, self.u_column, self.u_k, self.u_covers)):
            from jointwear.errors import ParameterError

            raise ParameterError(
                f"--u/--u-column/--u-k/--u-covers describe a CSV table; the CF file '{file}' "
                f"states its uncertainty as the variable {name}_u (units, coverage_factor, "
                "comment): add it there, or drop those options"
            )


def _save(ds, out: Path, source: Path, name: str, example: str) -> None:
    from jointwear import io
    from jointwear.import_uncertainty import NO_UNCERTAINTY_NOTE

    io.save(ds, out, inputs=[source], parameters={"external": True, **ds.attrs})
    read_as = f"; {ds.attrs['read_as']}" if ds.attrs.get("read_as") else ""
    typer.echo(f"wrote {out} ({ds.attrs['data_origin']}, from {source.name}{read_as})")
    if f"{name}_u" not in ds:
        typer.echo("note: " + NO_UNCERTAINTY_NOTE.format(what=name, example=example), err=True)


@app.command("motion")
@options_from("table", _TableFlags)
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
    *,
    table: _TableFlags,
) -> None:
    """Import a follower motion history: time and velocity columns with stated units."""
    from jointwear import external

    data_origin = origin.value if origin else None
    if file.suffix.lower() in _CF_SUFFIXES:
        table.csv_only(file, "follower_velocity")
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
            reading=table.reading(3),
        )
    _save(ds, out, file, "follower_velocity", "2mm/s")


@app.command("wearmap")
@options_from("table", _TableFlags)
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
    *,
    table: _TableFlags,
) -> None:
    """Import a wear map (depth positive where material was removed) with stated units and angle convention."""
    from jointwear import external

    data_origin = origin.value if origin else None
    if file.suffix.lower() in _CF_SUFFIXES:
        table.csv_only(file, "wear_depth")
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
            reading=table.reading(1),
        )
    _save(ds, out, file, "wear_depth", "0.5um")


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
