"""Bring a user's own data in: motion and wear maps from other simulators and instruments.

Other multibody codes (Adams, RecurDyn, Simpack, MATLAB scripts) and other measurement tools
export motion histories and wear maps as CSV or as CF netCDF. These functions turn such files into
datasets that follow the jointwear data contract (``docs/conventions.md``), so that ``compare``
and ``report`` treat them exactly like jointwear's own results.

Nothing is guessed: the units of every column and, for wear maps, the angle convention must be
stated (the functions refuse a file whose units or convention are not given), and the caller
says what the numbers are (``data_origin``: ``"simulated"``, ``"measured"`` or ``"synthetic"``).
The imported dataset records the file (with its sha256) and ``external = "yes"`` in its
provenance; its ``source`` names the tool the user gave.

Units are converted with pint, so any unit pint knows is accepted (``mm/s``, ``m s-1``, ``um``,
``µm``, ``inch``, ``deg``, ``rad``, ...); a unit of the wrong kind (a length given for a
velocity) is an error that names the option.
"""

from __future__ import annotations

import csv
import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from functools import cache
from io import StringIO
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import xarray as xr

from jointwear import _import_defaults as D
from jointwear import conventions
from jointwear.dialect import DELIMITER_NAMES, delimiter_char, sniff_separators, sniff_thousands
from jointwear.errors import BadInputError, ParameterError
from jointwear.import_uncertainty import StatedUncertainty, attach_uncertainty

__all__ = [
    "DATA_ORIGINS",
    "to_si",
    "read_table",
    "CsvReading",
    "import_motion",
    "import_wear_map",
    "import_cf",
    "load_for_comparison",
    "StatedUncertainty",
]

#: What the numbers of a file are (global attribute ``data_origin``).
DATA_ORIGINS = ("measured", "synthetic", "simulated")

#: SI unit of each kind of quantity an import converts to.
_SI = {"length": "m", "velocity": "m/s", "time": "s", "angle": "degree", "force": "N"}
_DIMENSION = {
    "length": "[length]",
    "velocity": "[length] / [time]",
    "time": "[time]",
    "angle": "",
    "force": "[force]",
}


@cache
def _registry() -> Any:
    import pint

    return pint.UnitRegistry()


def _pint_unit(unit: str) -> str:
    """Spell a UDUNITS/CF unit (``m s-1``, ``um``, ``degrees``) the way pint parses it."""
    text = unit.strip().replace("µ", "u").replace("μ", "u")
    text = re.sub(r"\bmicrons?\b", "um", text)
    text = re.sub(r"\bdegrees?(_\w+)?\b", "degree", text)
    # UDUNITS exponents: "s-1" -> "s**-1", "m2" -> "m**2"
    text = re.sub(r"([A-Za-z])(-?\d+)\b", r"\1**\2", text)
    return text


def to_si(values: Any, unit: str, *, kind: str, option: str) -> np.ndarray:
    """Convert ``values`` given in ``unit`` to the SI unit of ``kind`` (degrees for angles).

    Parameters
    ----------
    values : array_like
        Numbers in ``unit``.
    unit : str
        The unit as the user or the file states it (``"mm/s"``, ``"m s-1"``, ``"um"``, ``"deg"``).
    kind : {"length", "velocity", "time", "angle", "force"}
        What the values are; decides the target unit (m, m/s, s, degree, N).
    option : str
        The option or attribute that gave the unit, named in errors (``"--velocity-unit"``).

    Returns
    -------
    ndarray
        The values in m, m/s, s, N, or degrees for angles.
    """
    import pint

    if not isinstance(unit, str) or not unit.strip():
        raise ParameterError(f"{option}: no unit given; state the unit of the {kind} values")
    ureg = _registry()
    try:
        quantity = ureg.Quantity(1.0, _pint_unit(unit))
        factor = quantity.to(_SI[kind]).magnitude
    except pint.errors.DimensionalityError:
        raise ParameterError(
            f"{option} = {unit!r} is not a unit of {kind} (expected something convertible to "
            f"{_SI[kind]})"
        ) from None
    except (pint.errors.UndefinedUnitError, pint.errors.DefinitionSyntaxError, ValueError) as exc:
        raise ParameterError(
            f"{option} = {unit!r} is not a unit jointwear knows ({exc}); write e.g. "
            f"{'mm/s' if kind == 'velocity' else 'mm' if kind == 'length' else _SI[kind]!r}"
        ) from None
    except AssertionError:  # pint raises it for some malformed expressions
        raise ParameterError(f"{option} = {unit!r} is not a unit jointwear can parse") from None
    return np.asarray(values, dtype=float) * factor


def read_table(
    path: str | Path, *, delimiter: str | None = None, decimal: str | None = None
) -> pd.DataFrame:
    """Read a CSV/TSV/whitespace table with a header row; ``#`` starts a comment line.

    The field delimiter and the decimal mark are the metrology readers' decisions
    (:func:`jointwear.dialect.sniff_separators` on the data rows, the thousands mark
    :func:`jointwear.dialect.sniff_thousands`), so a semicolon table with
    decimal commas (``0,25;1,5``) reads as numbers; what was sniffed is in ``table.attrs``.

    Parameters
    ----------
    path : path
    delimiter : {"tab", "semicolon", "comma", "whitespace"} or the character, optional
        Field delimiter (``--delimiter``); sniffed when not given.
    decimal : {".", ","} (or "point", "comma"), optional
        Decimal mark (``--decimal``); sniffed when not given.

    Raises
    ------
    BadInputError
        The file is missing, empty, not text, or has no header row of names.
    """
    path = Path(path)
    if not path.is_file():
        raise BadInputError(f"'{path}' does not exist or is not a file")
    try:
        text = path.read_text(encoding="utf-8-sig")
    except UnicodeDecodeError:
        raise BadInputError(
            f"'{path}' is not UTF-8 text; export it as CSV (UTF-8) from the tool that wrote it"
        ) from None
    lines = [ln for ln in text.splitlines() if ln.strip() and not ln.lstrip().startswith("#")]
    sep, dec, thousands, how = _format(lines, delimiter, decimal)
    try:
        table = pd.read_csv(
            StringIO("\n".join(lines)),
            sep=sep,
            engine="python",
            decimal=dec,
            thousands=thousands,
            skipinitialspace=True,
        )
    except (pd.errors.ParserError, pd.errors.EmptyDataError, csv.Error) as exc:
        raise BadInputError(
            f"'{path}' could not be read as a table with a header row: {exc}"
        ) from None
    if table.empty or table.shape[1] < 2:
        raise BadInputError(
            f"'{path}': expected a header row of column names and at least two columns of "
            f"numbers, found {table.shape[1]} column(s) and {len(table)} row(s)"
        )
    table.columns = [str(c).strip() for c in table.columns]
    table.attrs["read_as"] = how
    return table


#: ``--decimal`` spellings -> the mark
_DECIMALS = {".": ".", "point": ".", "dot": ".", ",": ",", "comma": ","}


def _format(
    lines: list[str], delimiter: str | None, decimal: str | None
) -> tuple[str | None, str, str | None, str]:
    """(pandas ``sep``, decimal mark, thousands mark, what was read how) of a table's lines
    (the header row first): the metrology readers' sniffer (:mod:`jointwear.dialect`) on its
    data rows."""
    if decimal is not None and str(decimal).strip().lower() not in _DECIMALS:
        raise ParameterError(f"--decimal {decimal!r}: use point or comma")
    dec = None if decimal is None else _DECIMALS[str(decimal).strip().lower()]
    try:
        delim = delimiter_char(delimiter)
    except BadInputError as exc:
        raise ParameterError(f"--delimiter {delimiter!r}: {exc}") from None
    data = lines[1:51]
    sample = [ln for ln in "\n".join(data).splitlines() if ln.strip()][:50]
    found, guessed = (delim, dec), set()
    if sample and (delim is None or dec is None):
        sniffed = sniff_separators(sample, delim, dec)
        if sniffed is not None:  # else a column of text: the table is read as it was before
            guessed = {"delimiter"} if delim is None else set()
            guessed |= {"decimal"} if dec is None else set()
            found = sniffed
    delim, dec = found
    if delim is None:  # not decided: csv's sniffer (any delimiter), decimal point
        return None, dec or ".", None, "delimiter sniffed by csv, decimal point"
    thousands = None
    if dec is not None:
        thousands = sniff_thousands(data, delim)
        thousands = None if thousands == dec else thousands
    sep = r"\s+" if delim == " " else delim
    how = (
        f"delimiter {DELIMITER_NAMES[delim]} ({'sniffed' if 'delimiter' in guessed else 'given'}), "
        f"decimal {'comma' if dec == ',' else 'point'} "
        f"({'sniffed' if 'decimal' in guessed else 'given'})"
        + (f", thousands mark {thousands!r} (sniffed)" if thousands else "")
    )
    return sep, dec or ".", thousands, how


def _column(table: pd.DataFrame, name: str, path: Path, option: str) -> np.ndarray:
    """One column as floats; missing names and non-numbers are errors naming the row."""
    lookup = {c.lower(): c for c in table.columns}
    if name.lower() not in lookup:
        raise BadInputError(
            f"'{path}' has no column {name!r} (columns: {', '.join(map(repr, table.columns))}); "
            f"name the right one with {option}"
        )
    column = table[lookup[name.lower()]]
    values = pd.to_numeric(column, errors="coerce").to_numpy(dtype=float)
    bad = np.flatnonzero(~np.isfinite(values))
    if bad.size:
        row = int(bad[0])
        hint = (
            "; the file writes decimal commas: give --decimal comma (and --delimiter)"
            if "," in str(column.iloc[row])
            else ""
        )
        raise BadInputError(
            f"'{path}', column {name!r}: value {column.iloc[row]!r} in data row {row + 1} is not a "
            f"finite number ({bad.size} such value(s)); fix or remove those rows{hint}"
        )
    return values


def _check_origin(data_origin: str) -> str:
    if data_origin not in DATA_ORIGINS:
        raise ParameterError(
            f"--origin = {data_origin!r}: say what the numbers are, one of {', '.join(DATA_ORIGINS)}"
        )
    return data_origin


def _stamp(ds: xr.Dataset, path: Path, data_origin: str, tool: str | None, what: str) -> xr.Dataset:
    ds.attrs.update(
        title=f"{what} imported from {path.name}",
        source=f"external: {tool or 'unnamed tool'} ({path.name})",
        data_origin=data_origin,
        external="yes",
    )
    return ds


def _vector(
    table: pd.DataFrame, names: Sequence[str], path: Path, option: str, unit: str, kind: str
) -> np.ndarray:
    """Columns ``names`` as the components of a vector in SI units, a row per sample (``option``:
    the CLI option prefix, ``--velocity`` for ``--velocity-columns`` / ``--velocity-unit``)."""
    return np.column_stack(
        [
            to_si(
                _column(table, c, path, f"{option}-columns"),
                unit,
                kind=kind,
                option=f"{option}-unit",
            )
            for c in names
        ]
    )


@dataclass(frozen=True)
class CsvReading:
    """How an own-data CSV table is read, and the uncertainty its user states for it.

    Parameters
    ----------
    delimiter : {"tab", "semicolon", "comma", "whitespace"} or the character, optional
        Field delimiter (``--delimiter``, :func:`read_table`); sniffed when not given.
    decimal : {".", ","} (or "point", "comma"), optional
        Decimal mark (``--decimal``, :func:`read_table`); sniffed when not given.
    uncertainty : StatedUncertainty, optional
        The imported quantity's uncertainty as the user states it (``--u`` or ``--u-column``,
        in the quantity's unit unless it says its own), stored as ``<name>_u``. None: not
        stated, and V&V 20 criteria on these data are *not assessed*.
    """

    delimiter: str | None = None
    decimal: str | None = None
    uncertainty: StatedUncertainty | None = None

    def read(self, path: Path) -> pd.DataFrame:
        """The table at ``path`` read with this delimiter and decimal mark (:func:`read_table`)."""
        return read_table(path, delimiter=self.delimiter, decimal=self.decimal)


def import_motion(
    path: str | Path,
    *,
    reading: CsvReading = CsvReading(),
    velocity_unit: str,
    data_origin: str,
    time_unit: str = D.TIME_UNIT,
    time_column: str = D.TIME_COLUMN,
    velocity_columns: Sequence[str] = D.VELOCITY_COLUMNS,
    position_columns: Sequence[str] | None = None,
    position_unit: str | None = None,
    tool: str | None = None,
) -> xr.Dataset:
    """Import a follower motion history (CSV table) from another simulator or instrument.

    Parameters
    ----------
    path : path
        CSV/TSV table with a header row: a time column and one column per velocity component.
    reading : CsvReading, optional
        The table's delimiter and decimal mark (sniffed when not given) and the velocity's
        stated uncertainty (``follower_velocity_u``, one column or one per component).
    velocity_unit : str
        Unit of the velocity columns (``"mm/s"``, ``"m s-1"``, ...). Required: never guessed.
    data_origin : {"simulated", "measured", "synthetic"}
        What the numbers are.
    time_unit : str
        Unit of the time column [default s].
    time_column : str
        Name of the time column.
    velocity_columns : sequence of str
        Names of the x, y(, z) velocity columns, in the bearing frame of jointwear's rig
        (``docs/conventions.md``).
    position_columns, position_unit : optional
        Follower position columns and their unit, if the file has them.
    tool : str, optional
        The program that wrote the file (e.g. ``"Adams 2024"``), recorded in ``source``.

    Returns
    -------
    Dataset
        ``follower_velocity(time, axis)`` [m s-1] (and ``follower_position`` [m],
        ``follower_velocity_u``), ``time`` [s] from 0, ``data_origin`` and
        ``external = "yes"`` in the attributes.
    """
    path = Path(path)
    _check_origin(data_origin)
    if not 2 <= len(velocity_columns) <= 3:
        raise ParameterError(
            f"--velocity-columns: give 2 or 3 column names (x, y[, z]), got {list(velocity_columns)}"
        )
    uncertainty = reading.uncertainty
    table = reading.read(path)
    t = to_si(
        _column(table, time_column, path, "--time-column"),
        time_unit,
        kind="time",
        option="--time-unit",
    )
    steps = np.diff(t)
    if t.size < 2 or np.any(steps <= 0):
        where = int(np.flatnonzero(steps <= 0)[0]) + 2 if t.size >= 2 else 1
        raise BadInputError(
            f"'{path}', column {time_column!r}: time must increase strictly from row to row "
            f"(it does not at data row {where}); sort the rows or remove duplicates"
        )
    axes = ["x", "y", "z"][: len(velocity_columns)]
    velocity = _vector(table, velocity_columns, path, "--velocity", velocity_unit, "velocity")
    ds = xr.Dataset(coords={"time": t - t[0], "axis": axes})
    ds["follower_velocity"] = (("time", "axis"), velocity)
    if position_columns:
        if position_unit is None:
            raise ParameterError("--position-unit: give the unit of the position columns")
        if len(position_columns) != len(axes):
            raise ParameterError("--position-columns: give as many columns as --velocity-columns")
        position = _vector(table, position_columns, path, "--position", position_unit, "length")
        ds["follower_position"] = (("time", "axis"), position)
    ds = conventions.annotate(ds)
    if uncertainty is not None:
        columns = uncertainty.columns or ()
        values = None
        if columns:
            if len(columns) not in (1, len(axes)):
                raise ParameterError(
                    f"--u-column: give one column, or one per velocity component "
                    f"({len(axes)}), got {len(columns)}"
                )
            values = _vector(table, columns, path, "--u", velocity_unit, "velocity")
        ds = attach_uncertainty(
            ds, "follower_velocity", uncertainty, unit=velocity_unit, kind="velocity", values=values
        )
    ds.attrs["read_as"] = table.attrs.get("read_as", "")
    return _stamp(ds, path, data_origin, tool, "follower motion")


def import_wear_map(
    path: str | Path,
    *,
    reading: CsvReading = CsvReading(),
    theta_unit: str,
    z_unit: str,
    depth_unit: str,
    angle_zero: str,
    angle_direction: str,
    data_origin: str,
    columns: Sequence[str] = D.WEAR_MAP_COLUMNS,
    z_mid_width: float = D.Z_MID_WIDTH,
    z_reversed: bool = False,
    cycles: float | None = None,
    tool: str | None = None,
) -> xr.Dataset:
    """Import a wear map given as a long table (one row per bearing point: theta, z, depth).

    Parameters
    ----------
    path : path
        CSV/TSV with a header row. Every (z, theta) pair of a regular grid must appear exactly once.
    reading : CsvReading, optional
        The table's delimiter and decimal mark (sniffed when not given) and the depth's stated
        uncertainty (``wear_depth_u``, one value or one column).
    theta_unit, z_unit, depth_unit : str
        Units of the three columns (``"deg"``/``"rad"``, ``"mm"``, ``"um"``). Required.
    angle_zero, angle_direction : str
        The file's angle convention (see :class:`jointwear.conventions.AngleConvention`); the map
        is converted to the canonical one.
    data_origin : {"simulated", "measured", "synthetic"}
        What the numbers are.
    columns : (str, str, str)
        Names of the theta, z and depth columns. Depth is positive where material was removed.
    z_mid_width : float
        The z value of the bearing's mid-width in the file, in ``z_unit`` (the contract puts
        ``z = 0`` there) [default 0].
    z_reversed : bool
        The file's z grows along the bearing frame's -z axis (the contract's z grows along +z of
        the bearing frame, ``docs/conventions.md``).
    cycles : float, optional
        Crank cycles the map belongs to; adds a ``cycles`` dimension of length 1.
    tool : str, optional
        The program that wrote the file.

    Returns
    -------
    Dataset
        ``wear_depth(z, theta)`` [m] (and ``wear_depth_u``) on the canonical angle convention.
    """
    path = Path(path)
    _check_origin(data_origin)
    if len(columns) != 3:
        raise ParameterError(f"--columns: give three names (theta, z, depth), got {list(columns)}")
    convention = conventions.AngleConvention(angle_zero, angle_direction)
    uncertainty = reading.uncertainty
    table = reading.read(path)
    theta = to_si(
        _column(table, columns[0], path, "--columns"),
        theta_unit,
        kind="angle",
        option="--theta-unit",
    )
    z_file = _column(table, columns[1], path, "--columns") - float(z_mid_width)
    z = to_si(-z_file if z_reversed else z_file, z_unit, kind="length", option="--z-unit")
    depth = to_si(
        _column(table, columns[2], path, "--columns"),
        depth_unit,
        kind="length",
        option="--depth-unit",
    )
    theta = np.mod(theta, 360.0)
    theta_keys = np.round(theta, 9)
    z_keys = np.round(z, 12)
    frame = pd.DataFrame({"z": z_keys, "theta": theta_keys, "depth": depth})
    if uncertainty is not None and uncertainty.columns:
        if len(uncertainty.columns) != 1:
            raise ParameterError("--u-column: a wear map takes one column of uncertainties")
        frame["u"] = to_si(
            _column(table, uncertainty.columns[0], path, "--u-column"),
            depth_unit,
            kind="length",
            option="--depth-unit",
        )
    duplicated = frame.duplicated(["z", "theta"])
    if duplicated.any():
        row = int(np.flatnonzero(duplicated.to_numpy())[0])
        raise BadInputError(
            f"'{path}': the point z = {z[row]:g} m, theta = {theta[row]:g} deg appears more than once "
            f"(data row {row + 1}); a wear map has one depth per bearing point"
        )
    grid = frame.pivot(index="z", columns="theta", values="depth")
    missing = int(grid.isna().to_numpy().sum())
    if missing:
        raise BadInputError(
            f"'{path}': the points do not form a complete (z, theta) grid: {grid.shape[0]} z values "
            f"x {grid.shape[1]} angles, {missing} point(s) missing; export the map on a regular grid"
        )
    if grid.shape[0] < 1 or grid.shape[1] < 3:
        raise BadInputError(f"'{path}': a wear map needs at least 3 angles, found {grid.shape[1]}")
    ds = xr.Dataset(
        {"wear_depth": (("z", "theta"), grid.to_numpy())},
        coords={
            "z": conventions.z_coord(grid.index.to_numpy(), note=f"imported from {path.name}"),
            "theta": conventions.theta_coord(grid.columns.to_numpy(), convention),
        },
    )
    if uncertainty is not None:
        values = None
        if uncertainty.columns:
            values = frame.pivot(index="z", columns="theta", values="u").to_numpy()
        ds = attach_uncertainty(
            conventions.annotate(ds),
            "wear_depth",
            uncertainty,
            unit=depth_unit,
            kind="length",
            values=values,
        )
    ds = conventions.to_canonical(ds)
    if cycles is not None:
        ds = ds.expand_dims(cycles=[float(cycles)])
    ds = conventions.annotate(ds)
    ds.attrs["read_as"] = table.attrs.get("read_as", "")
    return _stamp(ds, path, data_origin, tool, "wear map")


def import_cf(
    path: str | Path,
    *,
    data_origin: str | None = None,
    angle_zero: str | None = None,
    angle_direction: str | None = None,
    tool: str | None = None,
) -> xr.Dataset:
    """Import a CF-style netCDF file written by another tool.

    The file's variables must use the contract's names (``wear_depth``, ``follower_velocity``,
    ``theta``, ``z``, ``time``, ...); their ``units`` attributes are converted to the contract's
    units. A ``theta`` coordinate needs its angle convention, from the file's attributes
    (``angle_zero``, ``angle_direction``) or given here; ``z`` without ``z_zero`` is taken as
    measured from the bearing's mid-width only if the caller says nothing else (it is recorded).

    Parameters
    ----------
    path : path
        The netCDF file.
    data_origin : str, optional
        What the numbers are; required unless the file states ``data_origin``.
    angle_zero, angle_direction : str, optional
        Angle convention of ``theta`` when the file does not state it (or to confirm it).
    tool : str, optional
        The program that wrote the file.
    """
    path = Path(path)
    if not path.is_file():
        raise BadInputError(f"'{path}' does not exist or is not a file")
    try:
        with xr.open_dataset(path, engine="netcdf4") as raw:
            ds = raw.load()
    except (OSError, ValueError) as exc:
        raise BadInputError(f"'{path}' could not be read as netCDF ({exc})") from None
    origin = data_origin or ds.attrs.get("data_origin")
    if origin is None:
        raise ParameterError(
            f"'{path}' does not say what its numbers are: give --origin simulated|measured|synthetic"
        )
    _check_origin(origin)
    if data_origin and ds.attrs.get("data_origin") not in (None, data_origin):
        raise BadInputError(
            f"'{path}' states data_origin = {ds.attrs['data_origin']!r} but --origin says "
            f"{data_origin!r}; drop --origin or correct the file"
        )
    known = {**conventions.COORDINATES, **conventions.VARIABLES}
    kinds = {"m": "length", "m s-1": "velocity", "s": "time", "degree": "angle", "N": "force"}
    for name in list(ds.variables):
        base = name[:-2] if name.endswith("_u") and name[:-2] in known else name
        if base not in known or known[base][0] not in kinds:
            continue
        unit = ds[name].attrs.get("units")
        if unit is None:
            raise BadInputError(
                f"'{path}': variable {name!r} has no 'units' attribute; add it (CF requires it)"
            )
        values = to_si(
            ds[name].values, str(unit), kind=kinds[known[base][0]], option=f"{name}:units"
        )
        ds[name] = ds[name].copy(data=values)
        ds[name].attrs["units"] = known[base][0]
        if base != name:  # an uncertainty of a contract variable: it says what it is
            ds[name].attrs.setdefault("long_name", f"standard uncertainty of {known[base][1]}")
    if "theta" in ds.coords:
        attrs = ds.coords["theta"].attrs
        zero = angle_zero or attrs.get("angle_zero")
        direction = angle_direction or attrs.get("angle_direction")
        if zero is None or direction is None:
            raise BadInputError(
                f"'{path}': theta does not state its angle convention; give --angle-zero and "
                "--angle-direction (where theta = 0 points and which way it increases, seen from +z)"
            )
        for key, given, stated in (
            ("angle_zero", angle_zero, attrs.get("angle_zero")),
            ("angle_direction", angle_direction, attrs.get("angle_direction")),
        ):
            if given is not None and stated is not None and str(given) != str(stated):
                raise BadInputError(
                    f"'{path}': theta states {key} = {stated!r}, the option says {given!r}"
                )
        theta = np.mod(ds["theta"].values, 360.0)
        ds = ds.assign_coords(
            theta=conventions.theta_coord(theta, conventions.AngleConvention(zero, direction))
        ).sortby("theta")
        ds = conventions.to_canonical(ds)
    if "z" in ds.coords and "z_zero" in ds["z"].attrs and "z_direction" not in ds["z"].attrs:
        ds["z"].attrs.update(
            z_direction="+z",
            z_note="the file did not state which way z grows; taken as +z of the bearing frame",
        )
    if "z" in ds.coords and "z_zero" not in ds.coords["z"].attrs:
        ds["z"].attrs.update(
            z_zero="bearing mid-width",
            z_direction="+z",
            z_note="the file did not state where z = 0 lies; taken as the bearing mid-width on import",
        )
    ds = conventions.annotate(ds)
    _check_cf_attributes(ds, path)
    ds.attrs.pop("provenance", None)
    return _stamp(ds, path, origin, tool or ds.attrs.get("source"), "dataset")


def _check_cf_attributes(ds: xr.Dataset, path: Path) -> None:
    """Every variable of a CF file states ``units`` and ``long_name`` (the data contract); a
    missing one is refused naming the file, the variable and the attribute."""
    missing = [
        (name, key)
        for name, var in ds.data_vars.items()
        for key in ("units", "long_name")
        if key not in var.attrs
    ]
    if missing:
        listed = "; ".join(f"variable {n!r} has no {k!r} attribute" for n, k in missing)
        name, key = missing[0]
        raise BadInputError(
            f"'{path}' (the input): {listed}. Add it to the file (e.g. ncatted -a "
            f"{key},{name},c,c,'...' {path.name}) or remove the variable; jointwear does not "
            "write a variable whose meaning or unit nobody stated"
        )


def load_for_comparison(
    path: str | Path,
    *,
    role: str,
    warn: Callable[[str], None] | None = None,
) -> xr.Dataset:
    """Load a file to compare: a jointwear file as it is, a foreign CF file as external data.

    A file written by jointwear (with provenance) is loaded by :func:`jointwear.io.load`. A
    netCDF file from another tool that uses the contract's variable names, ``units`` attributes
    and an angle convention on ``theta`` is converted by :func:`import_cf` and accepted with a
    warning: it is marked ``external = "yes"``, and when it does not state ``data_origin`` the
    origin is taken from its role in the comparison and recorded as assumed
    (``data_origin_stated = "no"``), which the report shows. A foreign file whose angle convention
    or units are missing is refused with the ``jointwear import`` command that settles it.

    Parameters
    ----------
    path : path
        The netCDF file.
    role : {"simulated", "measured"}
        The file's place in the comparison (simulation or measurement side).
    warn : callable, optional
        Receives the warning text for a foreign file (the CLI prints it on stderr); by default
        it is issued as a :class:`UserWarning`.
    """
    from jointwear import io

    if role not in ("simulated", "measured"):
        raise ValueError(f"role must be 'simulated' or 'measured', got {role!r}")
    path = Path(path)
    try:
        return io.load(path)
    except BadInputError:
        header = _foreign_header(path)
        if header is None:  # a jointwear file that breaks the contract, or not netCDF at all
            raise
    command = "wearmap" if role == "measured" else "wearmap|motion"
    stated, z_stated = header
    if not z_stated:
        raise BadInputError(
            f"'{path}' comes from another tool and its z coordinate does not say where z = 0 "
            "lies (attribute z_zero); the wear map's axial position would be a guess. Add "
            "z:z_zero = 'bearing mid-width' (with z measured from there), or convert it with "
            f"jointwear import wearmap {path} --z-mid-width ... (docs/tutorial-own-data.md)"
        )
    try:
        ds = import_cf(path, data_origin=None if stated else role)
    except BadInputError as exc:
        raise BadInputError(
            f"{exc}\n'{path}' comes from another tool and cannot be read unambiguously; convert "
            f"it first: jointwear import {command} {path} --origin ... (docs/tutorial-own-data.md)"
        ) from None
    ds.attrs["data_origin_stated"] = "yes" if stated else "no"
    text = (
        f"'{path}' was not written by jointwear: taken as external data "
        f"({ds.attrs['source']}), units and angle convention from its attributes"
    )
    if not stated:
        text += (
            f"; it does not state what its numbers are, so it is taken as {role!r} from its "
            f"place in the command - state it with 'jointwear import {command} {path} --origin'"
        )
    if warn is None:
        import warnings

        warnings.warn(text, UserWarning, stacklevel=2)
    else:
        warn(text)
    return ds


def _foreign_header(path: Path) -> tuple[str | None, bool] | None:
    """For a netCDF file without jointwear provenance: its stated ``data_origin`` (or None) and
    whether its z (if any) states ``z_zero``; None for a jointwear file or a non-netCDF one."""
    if not path.is_file():
        return None
    try:
        with xr.open_dataset(path, engine="netcdf4") as raw:
            if "provenance" in raw.attrs:
                return None
            origin = raw.attrs.get("data_origin")
            z_ok = "z" not in raw.coords or "z_zero" in raw.coords["z"].attrs
    except (OSError, ValueError):
        return None  # not netCDF at all: io.load's message is the right one
    return (str(origin) if origin is not None else None), z_ok
