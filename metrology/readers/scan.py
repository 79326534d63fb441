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
from dataclasses import asdict, replace
from pathlib import Path

import xarray as xr

from jointwear.conventions import (
    AngleConvention,
)
from jointwear.errors import BadInputError
from jointwear.metrology.readers.advice import plausibility
from jointwear.metrology.readers.claims import check_layers
from jointwear.metrology.readers.dataset import _as_convention, _assemble
from jointwear.metrology.readers.layers import _Layer, _layers_from_file
from jointwear.metrology.readers.table import TextFormat, parse_blocks
from jointwear.metrology.readers.zsource import assign_z, layer_numbers_from_meta

__all__ = ["read_text", "read_scan"]


def _natural_key(p: Path) -> list:
    return [int(t) if t.isdigit() else t.lower() for t in re.split(r"(\d+)", p.name)]


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
    layout: str = "auto",
    fmt: TextFormat | None = None,
    delimiter: str | None = None,
    decimal: str | None = None,
    header_lines: int | None = None,
    columns: Sequence[str] | None = None,
    units: str | None = None,
    value: str = "auto",
    angle_unit: str | None = None,
    arc: str | None = None,
    z_units: str | None = None,
    sheet: str | None = None,
    z: Sequence[float] | None = None,
    layer_spacing: float | None = None,
    z_mid: float | str = "centre",
    expected_points: int | None = None,
    allow_partial: bool = False,
    resample: bool = False,
    pattern: str = "*",
    instrument: str | None = None,
    ignore_header: Sequence[str] = (),
    z_source: str = "auto",
    thousands: str | None = None,
    radius_range: tuple[float, float] | None = None,
    max_deviation: float | None = None,
    nominal_tolerance: float | None = None,
    min_form: float | None = None,
) -> xr.Dataset:
    """Read a roundness / cylindricity scan from text exports into a contract Dataset.

    Parameters
    ----------
    paths : path, folder or list of paths
        One file (single trace, long or wide layout), a folder of per-layer files, or a list of
        per-layer files.
    convention : AngleConvention or (zero, direction)
        The instrument's angle convention in the bearing frame. Required: never guessed.
    layout : {"auto", "single", "folder", "long", "wide"}
        Multi-layer layout (``auto``: a folder/list -> folder; a z column -> long; several
        value columns -> wide; else single).
    fmt : TextFormat, optional
        Format overrides (or give ``delimiter``, ``decimal``, ``header_lines``, ``columns``,
        ``units`` directly).
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
    sheet : str, optional
        Worksheet of an Excel workbook with several sheets of data.
    z : sequence of float, optional
        Instrument height of each layer [m], in file/column order (overrides everything else).
    layer_spacing : float, optional
        Distance between consecutive layers [m] when the files do not say.
    z_mid : float or "centre"
        Instrument height of the bearing mid-width [m]; ``"centre"`` = middle of the layers.
    expected_points : int, optional
        Points each layer must have (e.g. 18000); a shorter layer is an error.
    allow_partial : bool
        Accept layers with fewer points (missing points become NaN).
    resample : bool
        Interpolate layers with different angle samples onto one uniform grid.
    pattern : str
        Glob pattern of the per-layer files in a folder (manifest files are skipped).
    instrument : str, optional
        Instrument name for ``source`` (default: from the header, else ``"roundness instrument"``).
    ignore_header : sequence of str
        Header claims known to be wrong, dropped before reading (``units``, ``nominal_radius``,
        ``points``, ``filter``, ``layers``, ``z_extent``, ``layer_spacing``, ``z``); recorded.
    z_source : str
        Where z comes from (:data:`~.zsource.Z_SOURCES`; ``auto``: the one source there is,
        refused when two disagree).
    thousands : str, optional
        Thousands separator of the numbers (sniffed only where unambiguous).
    radius_range : (float, float), optional
        Plausible bore radius [m] (default 0.5 mm to 2 m): a unit that puts the radii outside
        is refused.
    max_deviation : float, optional
        Largest plausible |radial deviation| [m] (default 1 mm).
    nominal_tolerance : float, optional
        Relative tolerance of the measured radius against a stated nominal (default 0.05).
    min_form : float, optional
        Smallest plausible peak-to-valley of a deviation trace [m] (default 10 nm).

    Returns
    -------
    Dataset
        ``radius`` or ``radial_deviation`` [m] over (``z`` [m], ``theta`` [degree, canonical]);
        attrs record the instrument convention, files, every guess of the reader and the header
        metadata.

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
    if value not in ("auto", "radius", "deviation"):
        raise BadInputError(f"value must be 'auto', 'radius' or 'deviation', got {value!r}")
    if layout not in ("auto", "single", "folder", "long", "wide", "blocks"):
        raise BadInputError(
            f"layout {layout!r} is not known; use auto, single, folder, long, wide or blocks"
        )
    base = fmt or TextFormat()
    over = {
        k: v
        for k, v in dict(
            delimiter=delimiter,
            decimal=decimal,
            header_lines=header_lines,
            columns=tuple(columns) if columns is not None else None,
            units=units,
            z_units=z_units,
            sheet=sheet,
            ignore_header=tuple(ignore_header) if ignore_header else None,
            thousands=thousands,
        ).items()
        if v is not None
    }
    base = replace(base, **over) if over else base
    # collect files
    if isinstance(paths, (str, Path)):
        p = Path(paths)
        if p.is_dir():
            files = sorted(
                (
                    f
                    for f in p.glob(pattern)
                    if f.is_file()
                    and not f.name.startswith(".")
                    and f.stem.lower() not in ("manifest", "layers")
                ),
                key=_natural_key,
            )
            if not files:
                raise BadInputError(f"folder '{p}' holds no files matching {pattern!r}")
            folder = p
        else:
            if not p.exists():
                raise BadInputError(f"'{p}' does not exist")
            files = [p]
            folder = None
    else:
        files = [Path(f) for f in paths]
        if not files:
            raise BadInputError("no input files given")
        folder = files[0].parent if len(files) > 1 else None
    if layout == "folder" and len(files) < 1:
        raise BadInputError("layout='folder' needs a folder or several files")
    value_kind = None if value == "auto" else value
    limits = plausibility(
        radius_min=None if radius_range is None else radius_range[0],
        radius_max=None if radius_range is None else radius_range[1],
        max_deviation=max_deviation,
        nominal_tolerance=nominal_tolerance,
        min_form=min_form,
    )
    parsed = [pf for f in files for pf in parse_blocks(f, base)]
    blocks = len(files) == 1 and len(parsed) > 1
    layers: list[_Layer] = []
    metadata: dict = {}
    notes: dict = {}
    for pf in parsed:
        decided: dict[str, str] = {}
        ls = _layers_from_file(
            pf,
            None if allow_partial else expected_points,
            value_kind=value_kind,
            angle_unit=angle_unit,
            arc=arc or pf.arc,
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
            num = layer_numbers_from_meta(pf)
            ls[0].index = num
        layers.extend(ls)
        if not metadata:
            metadata = dict(pf.metadata)
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
    if layout == "auto":
        if blocks:
            layout_used = "blocks"
        elif len(parsed) > 1:
            layout_used = "folder"
        elif any(c in ("z", "layer") for c in parsed[0].columns):
            layout_used = "long"
        elif len(layers) > 1:
            layout_used = "wide"
        else:
            layout_used = "single"
    else:
        layout_used = layout
        if layout == "single" and len(layers) != 1:
            raise BadInputError(
                f"layout='single' but '{files[0]}' holds {len(layers)} layers; use layout='long' "
                "or 'wide'"
            )
    zsrc = assign_z(
        layers,
        parsed,
        layout_used,
        folder,
        z=None if z is None else list(z),
        layer_spacing=layer_spacing,
        z_units=z_units,
        z_source=z_source,
        where=f"'{folder or files[0]}'",
    )
    unconfirmed = check_layers(
        layers, metadata, zsrc, limits, f"'{files[0] if len(files) == 1 else folder}'"
    )
    notes["z_from"] = zsrc
    if instrument is None:
        instrument = next(
            (
                v
                for k, v in metadata.items()
                if k.lower() in ("instrument", "machine", "model", "gauge", "device")
            ),
            "roundness instrument",
        )
    ds = _assemble(
        layers,
        convention=conv,
        z_mid=z_mid,
        instrument=instrument,
        fmt_notes=notes,
        metadata=metadata,
        files=[str(f) for f in files],
        layout=layout_used,
        allow_partial=allow_partial,
        resample=resample,
    )
    ds.attrs["reader_format"] = {
        k: v for k, v in asdict(parsed[0].fmt).items() if v is not None and k != "columns"
    }
    # the meaning every column was finally read with (placeholders resolved)
    first = notes.get(Path(parsed[0].path).name, {})
    resolve = {
        "angle": first.get("angle_column", "angle"),
        "value": first.get("value_column", "value"),
    }
    ds.attrs["reader_columns"] = [resolve.get(c, c) for c in parsed[0].columns]
    if parsed[0].units:
        ds.attrs["instrument_units"] = parsed[0].units
    if unconfirmed:
        ds.attrs["z_unconfirmed"] = unconfirmed
    return ds
