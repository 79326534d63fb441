"""Options of the metrology commands, declared once as ``Annotated`` aliases.

The choices come from the library's own constants (:data:`~.readers.scan.LAYOUTS`,
:data:`~.readers.meaning.ANGLE_UNITS`, :data:`~.form.REFERENCES`, ...), so the command line
offers exactly what the library accepts. Options shared with other folders' commands
(``--angle-zero``, ``--angle-direction``, ``--overwrite``) live in :mod:`jointwear._cli`.
"""

from __future__ import annotations

from enum import StrEnum
from pathlib import Path
from typing import Annotated

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


# --- import: the file and its format -----------------------------------------------------
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
LayoutOpt = Annotated[Layout, _opt("--layout", f"{', '.join(LAYOUTS)}.")]
Units = Annotated[
    str | None,
    _opt(
        "--units",
        "Length unit of files that do not state it: um, mm, m, inch or uin (micro-inch); a "
        "unit the file contradicts is an error, one it names but nobody knows is replaced.",
        callback=_length_unit,
    ),
]
Delimiter = Annotated[str | None, _opt("--delimiter", "tab, semicolon, comma or whitespace.")]
DecimalOpt = Annotated[Decimal | None, _opt("--decimal", "Decimal separator: '.' or ','.")]
HeaderLines = Annotated[int | None, _opt("--header-lines", "Lines before the numeric table.")]
Columns = Annotated[
    str | None,
    _opt(
        "--columns",
        "Comma-separated column meanings: angle_deg, angle_rad, index, x, y, z, radius, "
        "deviation, ignore.",
    ),
]
ValueKindOpt = Annotated[
    ValueKind,
    typer.Option(
        "--value-kind",
        "--value",
        help="Values are radius or deviation (auto: from the column name, else from "
        "unambiguous numbers, else refused).",
    ),
]
AngleUnitOpt = Annotated[
    AngleUnit | None,
    _opt(
        "--angle-unit",
        "Unit of the angle column when the file does not state it: deg, rad, index (point "
        "number over one turn) or grad.",
    ),
]
ArcOpt = Annotated[
    Arc | None,
    _opt(
        "--arc",
        "Each layer is one full turn or a partial arc (settles an ambiguous angle unit; "
        "'full' is needed for files without an angle column).",
    ),
]
Sheet = Annotated[
    str | None, _opt("--sheet", "Worksheet of an Excel workbook with several sheets.")
]
Thousands = Annotated[
    str | None, _opt("--thousands", "Thousands separator of the numbers: , . ' or space.")
]
IgnoreHeader = Annotated[
    list[str] | None,
    _opt(
        "--ignore-header",
        "A header claim known to be wrong (repeat): units, nominal_radius, points, filter, "
        "layers, z_extent, layer_spacing, z.",
    ),
]

# --- import: layers and z ------------------------------------------------------------------
ZUnits = Annotated[
    str | None,
    _opt("--z-units", "Unit of z (column, header, file names) when not stated: mm, um, m."),
]
LayerSpacingMm = Annotated[float | None, _opt("--layer-spacing-mm", "Layer spacing [mm].")]
ZMidMm = Annotated[
    float | None,
    _opt(
        "--z-mid-mm",
        "Instrument height of the bearing mid-width [mm] (default: middle of the layers).",
    ),
]
ZSource = Annotated[
    str,
    _opt(
        "--z-source",
        f"Where z comes from: {', '.join(Z_SOURCES)} (auto refuses when two sources disagree).",
    ),
]
Heights = Annotated[
    Path | None,
    _opt(
        "--heights",
        "File of layer file, height lines (any delimiter; unit in its first line, e.g. "
        "'file,height_mm', else --z-units); a folder's manifest/heights/index.csv is found "
        "without it.",
    ),
]
ZMm = Annotated[
    str | None,
    _opt(
        "--z-mm",
        "Height of each layer [mm], comma-separated in file/column order, e.g. 0,1.5,4 (uneven "
        "z; overrides every other source).",
    ),
]
ExpectedPoints = Annotated[int | None, _opt("--expected-points", "Points every layer must have.")]
AllowPartial = Annotated[bool, _opt("--allow-partial", "Accept incomplete layers (NaN).")]
Resample = Annotated[bool, _opt("--resample", "Interpolate layers onto one uniform grid.")]
Batch = Annotated[bool, _opt("--batch", "Each entry of each PATH folder is a separate scan.")]
Pattern = Annotated[
    str, _opt("--pattern", "Glob of the per-layer files in a folder, e.g. '*.txt'.")
]
Instrument = Annotated[str | None, _opt("--instrument", "Instrument name for 'source'.")]

# --- import: plausibility limits of the header cross-checks --------------------------------
RadiusRangeMm = Annotated[
    tuple[float, float] | None,
    _opt(
        "--radius-range-mm",
        f"Plausible bore radius MIN MAX [mm] (default {_LIM['radius_min'] * 1e3:g} "
        f"{_LIM['radius_max'] * 1e3:g}).",
    ),
]
MaxDeviationMm = Annotated[
    float | None,
    _opt(
        "--max-deviation-mm",
        f"Largest plausible |deviation| [mm] (default {_LIM['max_deviation'] * 1e3:g}).",
    ),
]
NominalTolerance = Annotated[
    float | None,
    _opt(
        "--nominal-tolerance",
        "Relative tolerance of the radius against the header's nominal (default "
        f"{_LIM['nominal_tolerance']:g}).",
    ),
]
MinFormNm = Annotated[
    float | None,
    _opt(
        "--min-form-nm",
        f"Smallest plausible peak-to-valley of deviations [nm] ({_LIM['min_form'] * 1e9:g}).",
    ),
]
FormFraction = Annotated[
    float | None,
    _opt(
        "--form-fraction",
        "Largest plausible peak-to-valley of deviations relative to the header's nominal "
        f"radius (default {_LIM['form_fraction']:g}).",
    ),
]
MaxMissing = Annotated[
    float | None,
    _opt(
        "--max-missing",
        "Largest share of a layer's points that may be missing ('---', 'NaN', empty cells) "
        f"(default {_LIM['max_missing']:g}).",
    ),
]


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
