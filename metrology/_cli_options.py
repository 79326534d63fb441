"""Options of the metrology commands, declared once as ``Annotated`` aliases.

The choices come from the library's own constants (:data:`~.readers.scan.LAYOUTS`,
:data:`~.readers.meaning.ANGLE_UNITS`, :data:`~.form.REFERENCES`, ...), so the command line
offers exactly what the library accepts. Options shared with other folders' commands
(``--angle-zero``, ``--angle-direction``, ``--overwrite``) live in :mod:`jointwear._cli`.
"""

# (no ``from __future__ import annotations``: the option declarations are evaluated once, here,
# not compiled again from strings when ``options_from`` reads them at every start of the CLI)
from dataclasses import dataclass
from enum import StrEnum
from pathlib import Path
from typing import Annotated, Any

import typer

from jointwear.metrology.choices import (
    ANGLE_UNITS,
    ARCS,
    LAYOUTS,
    PRESETS,
    READERS,
    REFERENCES,
    VALUE_KINDS,
    WEAR_SHAPES,
    Z_SOURCES,
)
from jointwear.metrology.choices import PLAUSIBILITY as _LIM


def choices(name: str, values, doc: str) -> type[StrEnum]:
    """A ``StrEnum`` of ``values`` (strings, or (member name, value) pairs) for a choice option."""
    members = [v if isinstance(v, tuple) else (v, v) for v in values]
    enum = StrEnum(name, members)
    enum.__doc__ = doc
    return enum


AngleUnit = choices("AngleUnit", ANGLE_UNITS, "Unit of the angle column.")
Arc = choices("Arc", ARCS, "Angular span of each layer.")
Preset = choices("Preset", PRESETS, "Reader preset.")
Layout = choices("Layout", LAYOUTS, "Multi-layer layout.")
Decimal = choices("Decimal", [("point", "."), ("comma", ",")], "Decimal separator.")
FilterKind = choices("FilterKind", [("gaussian", "gaussian"), ("rc2", "2rc")], "Profile filter.")
Shape = choices("Shape", WEAR_SHAPES, "Unworn reference shape.")
Reference = choices("Reference", tuple(REFERENCES), "ISO reference.")
ValueKind = choices("ValueKind", ("auto", *VALUE_KINDS), "Meaning of the value column(s).")


def _length_unit(value: str | None) -> str | None:
    """Validate a length-unit option at parse time (a bad value is a usage error, exit 2)."""
    if value is None:
        return None
    from jointwear.errors import BadInputError
    from jointwear.metrology.readers.table import unit_factor

    try:
        unit_factor(value)
    except BadInputError:
        raise typer.BadParameter(
            f"unit {value!r} is not known; use um, mm, m, inch or uin (micro-inch)"
        ) from None
    return value


def _opt(flag: str, help: str, **kw) -> typer.models.OptionInfo:
    return typer.Option(flag, help=help, **kw)


# --- import ---------------------------------------------------------------------------------
ScanPaths = Annotated[
    list[Path],
    typer.Argument(
        help="Scan(s): a text export, a folder of per-layer files, or (with --batch) "
        "folders holding many scans."
    ),
]
ImportOut = Annotated[
    Path, typer.Option("--out", "-o", help="Output .nc (one scan) or folder (several scans).")
]
PresetOpt = Annotated[
    Preset,
    _opt("--preset", "; ".join(f"{k}: {doc}" for k, (_, doc) in READERS.items()) + "."),
]
Units = Annotated[
    str | None,
    _opt(
        "--units",
        "Length unit of files that do not state it: um, mm, m, inch or uin (micro-inch); a "
        "unit the file contradicts is an error, one it names but nobody knows is replaced.",
        callback=_length_unit,
    ),
]
Batch = Annotated[bool, _opt("--batch", "Each entry of each PATH folder is a separate scan.")]


def _si(value: float | None, scale: float) -> float | None:
    """An option given in mm/nm in SI (None stays None)."""
    return value * scale if value is not None else None


def _z_list(z_mm: str | None) -> tuple[float, ...] | None:
    """``--z-mm 0,1.5,4`` as heights in metres (None when not given)."""
    if z_mm is None:
        return None
    try:
        return tuple(float(v) * 1e-3 for v in z_mm.replace(" ", "").split(",") if v)
    except ValueError:
        raise typer.BadParameter(
            f"--z-mm {z_mm!r}: expected comma-separated numbers in mm, e.g. 0,1.5,4"
        ) from None


def _text(value: Any) -> str | None:
    """A choice option's value as the library's string (None stays None)."""
    return str(value) if value is not None else None


@dataclass(frozen=True)
class ScanFlags:
    """How ``metrology import`` reads a scan: the reader's options as given (None: not given,
    sniffed), an option group (``@options_from("reading", ScanFlags)``); :meth:`keywords` gives
    them as the reader's keywords (:class:`~jointwear.metrology.readers.scan.ScanReading`'s
    fields) in SI."""

    layout: Annotated[Layout, _opt("--layout", f"{', '.join(LAYOUTS)}.")] = Layout.auto
    units: Units = None
    delimiter: Annotated[
        str | None, _opt("--delimiter", "tab, semicolon, comma or whitespace.")
    ] = None
    decimal: Annotated[Decimal | None, _opt("--decimal", "Decimal separator: '.' or ','.")] = None
    header_lines: Annotated[
        int | None, _opt("--header-lines", "Lines before the numeric table.")
    ] = None
    columns: Annotated[
        str | None,
        _opt(
            "--columns",
            "Comma-separated column meanings: angle_deg, angle_rad, index, x, y, z, radius, "
            "deviation, ignore.",
        ),
    ] = None
    value: Annotated[
        ValueKind,
        typer.Option(
            "--value-kind",
            "--value",
            help="Values are radius or deviation (auto: from the column name, else from "
            "unambiguous numbers, else refused).",
        ),
    ] = ValueKind.auto
    angle_unit: Annotated[
        AngleUnit | None,
        _opt(
            "--angle-unit",
            "Unit of the angle column when the file does not state it: deg, rad, index (point "
            "number over one turn) or grad.",
        ),
    ] = None
    arc: Annotated[
        Arc | None,
        _opt(
            "--arc",
            "Each layer is one full turn or a partial arc (settles an ambiguous angle unit; "
            "'full' is needed for files without an angle column).",
        ),
    ] = None
    z_units: Annotated[
        str | None,
        _opt("--z-units", "Unit of z (column, header, file names) when not stated: mm, um, m."),
    ] = None
    sheet: Annotated[
        str | None, _opt("--sheet", "Worksheet of an Excel workbook with several sheets.")
    ] = None
    layer_spacing_mm: Annotated[float | None, _opt("--layer-spacing-mm", "Layer spacing [mm].")] = (
        None
    )
    z_mid_mm: Annotated[
        float | None,
        _opt(
            "--z-mid-mm",
            "Instrument height of the bearing mid-width [mm] (default: middle of the layers).",
        ),
    ] = None
    expected_points: Annotated[
        int | None, _opt("--expected-points", "Points every layer must have.")
    ] = None
    allow_partial: Annotated[bool, _opt("--allow-partial", "Accept incomplete layers (NaN).")] = (
        False
    )
    resample: Annotated[bool, _opt("--resample", "Interpolate layers onto one uniform grid.")] = (
        False
    )
    pattern: Annotated[
        str, _opt("--pattern", "Glob of the per-layer files in a folder, e.g. '*.txt'.")
    ] = "*"
    instrument: Annotated[str | None, _opt("--instrument", "Instrument name for 'source'.")] = None
    ignore_header: Annotated[
        list[str] | None,
        _opt(
            "--ignore-header",
            "A header claim known to be wrong (repeat): units, nominal_radius, points, filter, "
            "layers, z_extent, layer_spacing, z.",
        ),
    ] = None
    z_source: Annotated[
        str,
        _opt(
            "--z-source",
            f"Where z comes from: {', '.join(Z_SOURCES)} (auto refuses when two sources disagree).",
        ),
    ] = "auto"
    thousands: Annotated[
        str | None, _opt("--thousands", "Thousands separator of the numbers: , . ' or space.")
    ] = None
    radius_range_mm: Annotated[
        tuple[float, float] | None,
        _opt(
            "--radius-range-mm",
            f"Plausible bore radius MIN MAX [mm] (default {_LIM['radius_min'] * 1e3:g} "
            f"{_LIM['radius_max'] * 1e3:g}).",
        ),
    ] = None
    max_deviation_mm: Annotated[
        float | None,
        _opt(
            "--max-deviation-mm",
            f"Largest plausible |deviation| [mm] (default {_LIM['max_deviation'] * 1e3:g}).",
        ),
    ] = None
    nominal_tolerance: Annotated[
        float | None,
        _opt(
            "--nominal-tolerance",
            "Relative tolerance of the radius against the header's nominal (default "
            f"{_LIM['nominal_tolerance']:g}).",
        ),
    ] = None
    min_form_nm: Annotated[
        float | None,
        _opt(
            "--min-form-nm",
            f"Smallest plausible peak-to-valley of deviations [nm] ({_LIM['min_form'] * 1e9:g}).",
        ),
    ] = None
    form_fraction: Annotated[
        float | None,
        _opt(
            "--form-fraction",
            "Largest plausible peak-to-valley of deviations relative to the header's nominal "
            f"radius (default {_LIM['form_fraction']:g}).",
        ),
    ] = None
    max_missing: Annotated[
        float | None,
        _opt(
            "--max-missing",
            "Largest share of a layer's points that may be missing ('---', 'NaN', empty cells) "
            f"(default {_LIM['max_missing']:g}).",
        ),
    ] = None
    heights: Annotated[
        Path | None,
        _opt(
            "--heights",
            "File of layer file, height lines (any delimiter; unit in its first line, e.g. "
            "'file,height_mm', else --z-units); a folder's manifest/heights/index.csv is found "
            "without it.",
        ),
    ] = None
    z_mm: Annotated[
        str | None,
        _opt(
            "--z-mm",
            "Height of each layer [mm], comma-separated in file/column order, e.g. 0,1.5,4 (uneven "
            "z; overrides every other source).",
        ),
    ] = None

    def keywords(self) -> dict[str, Any]:
        """The reader's keywords (SI; ``instrument`` and ``units`` only when given, so that a
        preset's own default stands)."""
        options = dict(
            layout=str(self.layout),
            delimiter=self.delimiter,
            decimal=_text(self.decimal),
            header_lines=self.header_lines,
            columns=tuple(c.strip() for c in self.columns.split(",")) if self.columns else None,
            value=str(self.value),
            angle_unit=_text(self.angle_unit),
            arc=_text(self.arc),
            z_units=self.z_units,
            sheet=self.sheet,
            layer_spacing=_si(self.layer_spacing_mm, 1e-3),
            z_mid=self.z_mid_mm * 1e-3 if self.z_mid_mm is not None else "centre",
            expected_points=self.expected_points,
            allow_partial=self.allow_partial,
            resample=self.resample,
            pattern=self.pattern,
            ignore_header=tuple(self.ignore_header or ()),
            z_source=self.z_source,
            thousands=self.thousands,
            radius_range=tuple(v * 1e-3 for v in self.radius_range_mm)
            if self.radius_range_mm
            else None,
            max_deviation=_si(self.max_deviation_mm, 1e-3),
            nominal_tolerance=self.nominal_tolerance,
            min_form=_si(self.min_form_nm, 1e-9),
            form_fraction=self.form_fraction,
            max_missing=self.max_missing,
            heights=str(self.heights) if self.heights is not None else None,
            z=_z_list(self.z_mm),
        )
        if self.instrument is not None:
            options["instrument"] = self.instrument
        if self.units is not None:
            options["units"] = self.units
        return options


# --- assess ---------------------------------------------------------------------------------
AssessScans = Annotated[
    list[Path],
    typer.Argument(
        help="Imported scan(s) (.nc), or text/Excel files of x, y (and z) points, which get an "
        "exact least-squares circle per layer (need not surround the origin)."
    ),
]
FilterUpr = Annotated[
    float | None,
    _opt("--filter", "Filter cut-off in UPR (undulations per revolution), e.g. 15, 50, 150, 500."),
]
FilterKindOpt = Annotated[FilterKind, _opt("--filter-kind", "gaussian or 2rc.")]
ReferenceOpt = Annotated[
    list[Reference] | None,
    typer.Option("--reference", "-r", help=f"{', '.join(REFERENCES)} (repeat; default: all four)."),
]
Outliers = Annotated[
    float | None, _opt("--outliers", "Remove spikes beyond this many robust std devs.")
]
Exact = Annotated[
    bool,
    _opt(
        "--exact",
        "Also the exact geometric LS circle per layer (and cylinder for several layers).",
    ),
]
NominalRadiusMm = Annotated[
    float | None,
    _opt(
        "--nominal-radius-mm",
        "Bore radius in mm for the centring check and --exact on deviation data (default: the "
        "mean radius, or the file's nominal radius).",
    ),
]
