"""Generic reader for roundness / cylindricity text exports.

Roundness instruments export text in many shapes. This reader *sniffs* each file and records
every guess in the dataset's attributes; every guess can be overridden by an option:

* encoding (UTF-8, UTF-8 with BOM, else Latin-1) and binary garbage (refused);
* header lines before the numeric table: keyword/value metadata (``Units: um``,
  ``Points = 18000``, ``Height<TAB>2.0``) and an optional line of column names;
* delimiter (tab, semicolon, comma, whitespace) and decimal separator (point or comma);
* column meaning (:data:`COLUMN_KINDS`): angle in degrees / radians / sample index, Cartesian
  x / y, axial position z, radius or radial deviation -- from the column names when there are
  any, else from the number of columns and the values;
* length units (``um``, ``mm``, ``m``, ``inch``) from the header or the column names, else the
  ``units`` option -- never guessed from the numbers.

Layouts of a multi-layer scan (``layout``):

``"single"``
    one file = one layer (a roundness trace);
``"folder"``
    a folder (or list) of per-layer files; z from a manifest (``manifest.csv``/``.txt``: file name,
    z), from a keyword in each header (``z``, ``height``, ``level``, ``position``), from the file
    names (``..._z2.5mm.txt``, ``layer03``), or from ``layer_spacing``;
``"long"``
    one file with columns (z, angle, value);
``"wide"``
    one file with an angle column and one value column per layer (z from the column names or
    ``layer_spacing``).

The instrument's angle convention (where its 0 degree points in the bearing frame and which way
it turns) is never guessed: pass ``convention`` (an :class:`~jointwear.conventions.AngleConvention`
or ``(zero, direction)``). The result is expressed in the canonical convention and the
instrument's convention is recorded in the attributes. z is measured from the bearing
mid-width: by default the middle of the measured layers (``z_mid="centre"``), or the instrument
height of the mid-width given as ``z_mid`` [m].
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Sequence
from dataclasses import asdict, dataclass, fields, replace
from pathlib import Path
from typing import Any

import xarray as xr

from jointwear.conventions import (
    AngleConvention,
)
from jointwear.errors import BadInputError
from jointwear.metrology.choices import LAYOUTS, VALUE_KINDS
from jointwear.metrology.readers.advice import plausibility
from jointwear.metrology.readers.claims import check_layers
from jointwear.metrology.readers.dataset import _as_convention, _assemble
from jointwear.metrology.readers.heights import MANIFEST_STEMS
from jointwear.metrology.readers.layers import _Layer, _layers_from_file
from jointwear.metrology.readers.table import TextFormat, parse_blocks
from jointwear.metrology.readers.zsource import assign_z, layer_numbers_from_meta

__all__ = ["ScanReading", "read_text", "read_scan"]


def _natural_key(p: Path) -> list:
    return [int(t) if t.isdigit() else t.lower() for t in re.split(r"(\d+)", p.name)]


@dataclass(frozen=True)
class ScanReading:
    """How :func:`read_scan` reads a scan: every choice it would otherwise sniff, or refuse
    when the file does not settle it. The defaults sniff everything.

    Parameters
    ----------
    layout : {"auto", "single", "folder", "long", "wide", "blocks"}
        Multi-layer layout (``auto``: a folder/list -> folder; layer blocks in one file ->
        blocks; a z column -> long; several value columns -> wide; else single).
    fmt : TextFormat, optional
        Format overrides (or give ``delimiter``, ``decimal``, ``header_lines``, ``columns``,
        ``units``, ``thousands`` -- the thousands separator, sniffed only where unambiguous --
        and ``sheet`` -- of an Excel workbook with several sheets of data -- directly).
    value : {"auto", "radius", "deviation"}
        Meaning of the value column(s) when the column names do not say it (``auto``: from the
        numbers if they are unambiguous, else refused).
    angle_unit : {"deg", "rad", "index"}, optional
        Unit of the angle column when the file does not state it (``None``: the only unit that
        gives at most one turn, else refused).
    arc : {"full", "partial"}, optional
        Whether each layer covers one full turn or a partial arc; settles an ambiguous angle
        unit, and is required (``"full"``) for files without an angle column.
    z_units : str, optional
        Unit of z (long-file column, header keyword, file names, manifest) when not stated.
    z : sequence of float, optional
        Instrument height of each layer [m], in file/column order (overrides everything else).
    heights : path, optional
        A file of (layer file, z) lines in any delimiter, the unit in its first line
        (``file,height_mm``) or ``z_units``; a folder's ``manifest``, ``heights``, ``index``,
        ``layers`` (``.csv``/``.txt``/``.json``) is found without it.
    layer_spacing : float, optional
        Distance between consecutive layers [m] when the files do not say.
    z_mid : float or "centre"
        Instrument height of the bearing mid-width [m]; ``"centre"`` = middle of the layers.
    expected_points : int, optional
        Points each layer must have (e.g. 18000); a shorter layer is an error.
    allow_partial, resample : bool
        Accept layers with fewer points (missing points become NaN); interpolate layers with
        different angle samples onto one uniform grid.
    pattern : str
        Glob pattern of the per-layer files in a folder (manifest files are skipped).
    instrument : str, optional
        Instrument name for ``source`` (default: from the header, else ``"roundness instrument"``).
    ignore_header : sequence of str
        Header claims known to be wrong, dropped before reading (``units``, ``nominal_radius``,
        ``points``, ``filter``, ``layers``, ``z_extent``, ``layer_spacing``, ``z``); recorded.
    z_source : str
        Where z comes from (:data:`~jointwear.metrology.choices.Z_SOURCES`; ``auto``: the one there is).
    radius_range, max_deviation, nominal_tolerance, min_form, form_fraction : optional
        Plausibility limits of the header cross-checks (:data:`~jointwear.metrology.choices.PLAUSIBILITY`): bore
        radius (min, max) [m] (0.5 mm to 2 m), largest |radial deviation| [m] (1 mm), relative
        tolerance against a stated nominal radius (0.05), smallest peak-to-valley of a
        deviation trace [m] (10 nm), largest peak-to-valley of deviations relative to the
        stated nominal radius (0.01).
    max_missing : float, optional
        Largest share of a layer's points that may be missing (``---``, ``NaN``, empty cells:
        read as NaN points, counted in ``missing_points``); default 0.05.
    """

    layout: str = "auto"
    fmt: TextFormat | None = None
    delimiter: str | None = None
    decimal: str | None = None
    header_lines: int | None = None
    columns: Sequence[str] | str | None = None
    units: str | None = None
    value: str = "auto"
    angle_unit: str | None = None
    arc: str | None = None
    z_units: str | None = None
    sheet: str | None = None
    z: Sequence[float] | None = None
    layer_spacing: float | None = None
    z_mid: float | str = "centre"
    expected_points: int | None = None
    allow_partial: bool = False
    resample: bool = False
    pattern: str = "*"
    instrument: str | None = None
    ignore_header: Sequence[str] = ()
    z_source: str = "auto"
    thousands: str | None = None
    radius_range: tuple[float, float] | None = None
    max_deviation: float | None = None
    nominal_tolerance: float | None = None
    min_form: float | None = None
    form_fraction: float | None = None
    max_missing: float | None = None
    heights: str | Path | None = None

    def __post_init__(self) -> None:
        if self.value not in ("auto", *VALUE_KINDS):
            raise BadInputError(
                f"value must be 'auto', 'radius' or 'deviation', got {self.value!r}"
            )
        if self.layout not in LAYOUTS:
            raise BadInputError(
                f"layout {self.layout!r} is not known; use auto, single, folder, long, wide or "
                "blocks"
            )

    def given(self) -> dict[str, Any]:
        """The fields set to other than their defaults (what a preset must not override)."""
        return {
            f.name: getattr(self, f.name)
            for f in fields(self)
            if _differs(getattr(self, f.name), f.default)
        }

    def text_format(self) -> TextFormat:
        """``fmt`` (default: sniff everything) with the format options given (not None)."""
        columns = self.columns
        if columns is not None:
            columns = columns.split(",") if isinstance(columns, str) else tuple(columns)
        over = dict(
            delimiter=self.delimiter,
            decimal=self.decimal,
            header_lines=self.header_lines,
            columns=columns,
            units=self.units,
            z_units=self.z_units,
            sheet=self.sheet,
            ignore_header=tuple(self.ignore_header) if self.ignore_header else None,
            thousands=self.thousands,
        )
        base = self.fmt or TextFormat()
        over = {k: v for k, v in over.items() if v is not None}
        return replace(base, **over) if over else base

    def limits(self) -> dict[str, float]:
        """The plausibility limits with the options given."""
        rmin, rmax = (None, None) if self.radius_range is None else self.radius_range
        return plausibility(
            radius_min=rmin,
            radius_max=rmax,
            max_deviation=self.max_deviation,
            nominal_tolerance=self.nominal_tolerance,
            min_form=self.min_form,
            form_fraction=self.form_fraction,
            max_missing=self.max_missing,
        )


def _differs(value: Any, default: Any) -> bool:
    """Whether a field's value is not its default (an array of heights always is)."""
    if value is default:
        return False
    try:
        return bool(value != default)
    except (TypeError, ValueError):
        return True


def read_text(
    path: str | Path,
    *,
    convention: AngleConvention | tuple[str, str] | None = None,
    **options,
) -> xr.Dataset:
    """Read one text export (a single trace, a long file or a wide file).

    Shorthand for :func:`read_scan` with one path; see there for the options.
    """
    return read_scan(path, convention=convention, **options)


def read_scan(
    paths: str | Path | Iterable[str | Path],
    *,
    convention: AngleConvention | tuple[str, str] | None = None,
    reading: ScanReading | None = None,
    **options: Any,
) -> xr.Dataset:
    """Read a roundness / cylindricity scan from text exports into a contract Dataset.

    Parameters
    ----------
    paths : path, folder or list of paths
        One file (single trace, long, wide or blocks layout), a folder or list of layer files.
    convention : AngleConvention or (zero, direction)
        The instrument's angle convention in the bearing frame. Required: never guessed.
    reading : ScanReading, optional
        How the files are read (:class:`ScanReading`; default: every choice sniffed).
    **options
        Fields of :class:`ScanReading`, given directly (``layout="long"``, ``units="um"``):
        they replace ``reading``'s. This is how presets and refusals' suggestions pass them.

    Returns
    -------
    Dataset
        ``radius`` or ``radial_deviation`` [m] over (``z`` [m], ``theta`` [degree, canonical]);
        attrs: the instrument convention, files, every guess of the reader, header metadata.

    Examples
    --------
    A folder of per-layer text exports written by the Talyrond-style generator:

    >>> import tempfile
    >>> from jointwear.datasets.instruments import generate, write
    >>> from jointwear.metrology import read_scan
    >>> folder = tempfile.mkdtemp()
    >>> files = write(generate(n_layers=3, n_points=360, wear=None, seed=1), folder)
    >>> scan = read_scan(folder, convention=("+y", "counterclockwise"))
    >>> dict(scan.sizes), scan["radial_deviation"].attrs["units"], scan.attrs["data_origin"]
    ({'z': 3, 'theta': 360}, 'm', 'synthetic')
    """
    conv = _as_convention(convention)
    opts = replace(reading or ScanReading(), **options)
    base = opts.text_format()
    files, folder = _collect_files(paths, opts.pattern, opts.heights)
    limits = opts.limits()
    parsed = [pf for f in files for pf in parse_blocks(f, base)]
    layers, metadata, notes = _read_layers(parsed, len(files), opts, limits)
    layout_used = _layout_used(opts.layout, parsed, layers, files)
    zsrc = assign_z(
        layers,
        parsed,
        layout_used,
        folder,
        z=None if opts.z is None else list(opts.z),
        layer_spacing=opts.layer_spacing,
        z_units=opts.z_units,
        z_source=opts.z_source,
        where=f"'{folder or files[0]}'",
        heights=None if opts.heights is None else Path(opts.heights),
    )
    notes["z_from"] = zsrc
    where = f"'{files[0] if len(files) == 1 else folder}'"
    unconfirmed = check_layers(layers, metadata, zsrc, limits, where)
    ds = _assemble(
        layers,
        convention=conv,
        z_mid=opts.z_mid,
        instrument=_instrument(opts.instrument, metadata),
        fmt_notes=notes,
        metadata=metadata,
        files=[str(f) for f in files],
        layout=layout_used,
        allow_partial=opts.allow_partial,
        resample=opts.resample,
    )
    return _record_reading(ds, parsed[0], notes, unconfirmed)


def _instrument(given: str | None, metadata: dict) -> str:
    """The instrument name: given, else from the header, else "roundness instrument"."""
    if given is not None:
        return given
    keys = ("instrument", "machine", "model", "gauge", "device")
    return next((v for k, v in metadata.items() if k.lower() in keys), "roundness instrument")


def _collect_files(paths, pattern: str, heights=None) -> tuple[list[Path], Path | None]:
    """(the files to read, the folder they came from or None for one file); a folder's heights
    file (:data:`~.heights.MANIFEST_STEMS`, or ``heights``) is not a layer."""
    if not isinstance(paths, (str, Path)):
        files = [Path(f) for f in paths]
        if not files:
            raise BadInputError("no input files given")
        return files, files[0].parent if len(files) > 1 else None
    p = Path(paths)
    if not p.is_dir():
        if not p.exists():
            raise BadInputError(f"'{p}' does not exist")
        return [p], None
    files = sorted(
        (
            f
            for f in p.glob(pattern)
            if f.is_file()
            and not f.name.startswith(".")
            and f.stem.lower() not in MANIFEST_STEMS
            and (heights is None or f.resolve() != Path(heights).resolve())
        ),
        key=_natural_key,
    )
    if not files:
        raise BadInputError(f"folder '{p}' holds no files matching {pattern!r}")
    return files, p


def _read_layers(
    parsed: list, n_files: int, opts: ScanReading, limits: dict
) -> tuple[list[_Layer], dict, dict]:
    """The layers of every parsed file (or block), the first file's header metadata, and the
    guesses made per file (``reader_guesses``)."""
    expected_points, allow_partial = opts.expected_points, opts.allow_partial
    layers: list[_Layer] = []
    metadata: dict = {}
    notes: dict = {}
    for pf in parsed:
        decided: dict[str, str] = {}
        ls = _layers_from_file(
            pf,
            None if allow_partial else expected_points,
            value_kind=None if opts.value == "auto" else opts.value,
            angle_unit=opts.angle_unit,
            arc=opts.arc or pf.arc,
            notes=decided,
            limits=limits,
        )
        if pf.guessed or decided:
            key = Path(pf.path).name + (f" block {pf.block}" if pf.block else "")
            notes[key] = {**pf.guessed, **decided}
        if len(parsed) > 1 and len(ls) > 1:
            raise BadInputError(
                f"'{pf.path}' holds {len(ls)} layers"
                + (f" in block {pf.block}" if pf.block else "")
                + "; per-layer files or blocks hold one layer each"
            )
        if pf.block is not None:
            ls[0].index = layer_numbers_from_meta(pf)
        layers.extend(ls)
        if not metadata:
            metadata = dict(pf.metadata)
    blocks = n_files == 1 and len(parsed) > 1
    if blocks and any(lay.index is None for lay in layers):
        for lay in layers:
            lay.index = None
    if expected_points is not None and allow_partial:
        for k, lay in enumerate(layers):
            if lay.value.size > expected_points:
                raise BadInputError(
                    f"'{lay.source}': layer {k + 1} has {lay.value.size} points, more than the "
                    f"expected {expected_points}"
                )
    return layers, metadata, notes


def _layout_used(layout: str, parsed: list, layers: list, files: list[Path]) -> str:
    """The layout ``auto`` stands for (blocks, folder, long, wide or single), or the one given
    (checked)."""
    if layout != "auto":
        if layout == "single" and len(layers) != 1:
            raise BadInputError(
                f"layout='single' but '{files[0]}' holds {len(layers)} layers; use layout='long' "
                "or 'wide'"
            )
        return layout
    if len(files) == 1 and len(parsed) > 1:
        return "blocks"
    if len(parsed) > 1:
        return "folder"
    if any(c in ("z", "layer") for c in parsed[0].columns):
        return "long"
    return "wide" if len(layers) > 1 else "single"


def _record_reading(ds: xr.Dataset, first, notes: dict, unconfirmed: str | None) -> xr.Dataset:
    """Attributes of how the file was read: final format, resolved column meanings, the
    instrument's unit, an unconfirmed z."""
    ds.attrs["reader_format"] = {
        k: v for k, v in asdict(first.fmt).items() if v is not None and k != "columns"
    }
    # the meaning every column was finally read with (placeholders resolved)
    guessed = notes.get(Path(first.path).name, {})
    resolve = {
        "angle": guessed.get("angle_column", "angle"),
        "value": guessed.get("value_column", "value"),
    }
    ds.attrs["reader_columns"] = [resolve.get(c, c) for c in first.columns]
    if first.units:
        ds.attrs["instrument_units"] = first.units
    if unconfirmed:
        ds.attrs["z_unconfirmed"] = unconfirmed
    var = "radius" if "radius" in ds else "radial_deviation"
    ds.attrs["missing_points"] = int(ds[var].isnull().sum())  # NaN points (missing cells)
    return ds
