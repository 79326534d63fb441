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
from jointwear.metrology.readers.dataset import _as_convention, _assemble
from jointwear.metrology.readers.heights import (
    _layer_index_from_name,
    _number_from_name,
    _read_manifest,
    _z_from_meta,
)
from jointwear.metrology.readers.layers import _Layer, _layers_from_file
from jointwear.metrology.readers.table import _NUM, TextFormat, parse_file, unit_factor

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
    if layout not in ("auto", "single", "folder", "long", "wide"):
        raise BadInputError(
            f"layout {layout!r} is not known; use auto, single, folder, long or wide"
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
    parsed = [parse_file(f, base) for f in files]
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
        )
        if pf.guessed or decided:
            notes[Path(pf.path).name] = {**pf.guessed, **decided}
        if len(parsed) > 1 and len(ls) > 1:
            raise BadInputError(
                f"'{pf.path}' holds {len(ls)} layers; a folder layout expects one layer per file"
            )
        layers.extend(ls)
        if not metadata:
            metadata = dict(pf.metadata)
    if expected_points is not None and allow_partial:
        for k, lay in enumerate(layers):
            if lay.value.size > expected_points:
                raise BadInputError(
                    f"'{lay.source}': layer {k + 1} has {lay.value.size} points, more than the "
                    f"expected {expected_points}"
                )
    if layout == "auto":
        if len(parsed) > 1:
            layout_used = "folder"
        elif any(c == "z" for c in parsed[0].columns):
            layout_used = "long"
        elif len(layers) > 1:
            layout_used = "wide"
        else:
            layout_used = "single"
    else:
        layout_used = layout
        expected_layers = {"single": 1}
        if layout in expected_layers and len(layers) != 1:
            raise BadInputError(
                f"layout='single' but '{files[0]}' holds {len(layers)} layers; use layout='long' "
                "or 'wide'"
            )
    # z of each layer
    zsrc = ""
    if z is not None:
        zv = [float(v) for v in z]
        if len(zv) != len(layers):
            raise BadInputError(
                f"z gives {len(zv)} heights but the scan has {len(layers)} layers; give one per layer"
            )
        for lay, v in zip(layers, zv, strict=True):
            lay.z = v
        zsrc = "option z"
    elif all(lay.z is not None for lay in layers):
        zsrc = "z column"
    elif layout_used == "folder":
        found = _read_manifest(folder, z_units) if folder is not None else None
        manifest = found[1] if found else None
        if found:
            for lay in layers:
                name = Path(lay.source).name
                key = name if name in manifest else Path(name).stem
                if key not in manifest:
                    raise BadInputError(
                        f"manifest '{found[0]}' has no entry for '{name}'; add a line '{name}, <z>'"
                    )
                lay.z = manifest[key]
            zsrc = "manifest"
        else:
            zh = [_z_from_meta(pf.metadata, pf.z_units, f"'{pf.path}'") for pf in parsed]
            if all(v is not None for v in zh):
                for lay, v in zip(layers, zh, strict=True):
                    lay.z = v
                zsrc = "header keyword"
            else:
                zn = [_number_from_name(Path(lay.source).name, z_units) for lay in layers]
                if all(v is not None for v in zn) and len(set(zn)) == len(zn):
                    for lay, v in zip(layers, zn, strict=True):
                        lay.z = v
                    zsrc = "file names"
                elif layer_spacing is not None:
                    idx = [_layer_index_from_name(Path(lay.source).name) for lay in layers]
                    if any(i is None for i in idx) or len(set(idx)) != len(idx):
                        idx = list(range(len(layers)))
                    for lay, i in zip(layers, idx, strict=True):
                        lay.z = float(i) * float(layer_spacing)
                    zsrc = "layer_spacing x layer number (from the file names, else file order)"
                elif len(layers) == 1:
                    layers[0].z = 0.0
                    zsrc = "single layer"
                else:
                    raise BadInputError(
                        f"cannot tell the z of the {len(layers)} layer files in "
                        f"'{folder or files[0].parent}': no manifest.csv, no height keyword in the "
                        "headers, no z in the file names; pass layer_spacing=<m> or z=[...]"
                    )
    elif layout_used == "wide":
        names = parsed[0].column_names
        vidx = [i for i, c in enumerate(parsed[0].columns) if c in ("radius", "deviation", "value")]
        zn = None
        if names and len(names) == len(parsed[0].columns):
            zn = []
            for i in vidx:
                m = re.search(rf"({_NUM})\s*(mm|um|µm|m|in)?", names[i])
                if not m:
                    zn = None
                    break
                u = m.group(2) or parsed[0].z_units
                if u is None:
                    raise BadInputError(
                        f"'{files[0]}': column name {names[i]!r} gives z without a unit; pass "
                        "z_units=... (--z-units mm)"
                    )
                zn.append(float(m.group(1).replace(",", ".")) * unit_factor(u))
        if zn is not None and len(set(zn)) == len(zn):
            for lay, v in zip(layers, zn, strict=True):
                lay.z = v
            zsrc = "column names"
        elif layer_spacing is not None:
            for i, lay in enumerate(layers):
                lay.z = i * float(layer_spacing)
            zsrc = "layer_spacing x column order"
        else:
            raise BadInputError(
                f"'{files[0]}': wide file with {len(layers)} value columns but no z in the column "
                "names; pass layer_spacing=<m> or z=[...]"
            )
    else:
        for lay in layers:
            lay.z = 0.0
        zsrc = "single layer (z = 0)"
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
    return ds
