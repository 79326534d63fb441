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

import glob
import json
import re
from collections.abc import Iterable, Sequence
from dataclasses import asdict, replace
from pathlib import Path

import numpy as np
import xarray as xr

from jointwear.conventions import (
    CANONICAL,
    AngleConvention,
    convert_theta,
    theta_coord,
    z_coord,
)
from jointwear.errors import BadInputError, ConventionError
from jointwear.metrology.readers.layers import _Layer, _layers_from_file
from jointwear.metrology.readers.table import _NUM, TextFormat, parse_file, unit_factor

__all__ = ["read_text", "read_scan"]


def _number_from_name(name: str, z_units: str | None) -> float | None:
    """z [m] from a file name: 'z=2.5mm', 'z-1.0', 'h2,5mm'; a bare number needs ``z_units``."""
    m = re.search(
        r"(?:^|[_\-\s.])(?:z|h|height|pos)[=_]?([-+]?\d+(?:[.,p]\d+)?)\s*(mm|um|µm|m|in)?",
        name,
        re.I,
    )
    if m:
        v = float(m.group(1).replace(",", ".").replace("p", "."))
        unit = m.group(2) or z_units
        if unit is None:
            raise BadInputError(
                f"file name '{name}' gives z = {m.group(1)} without a unit; pass z_units=... "
                "(--z-units mm) or layer_spacing=... (--layer-spacing-mm)"
            )
        return v * unit_factor(unit)
    return None


def _layer_index_from_name(name: str) -> int | None:
    m = re.search(r"(?:layer|lay|l|level|trace|plane)[_\-\s]?(\d+)", name, re.I)
    if m:
        return int(m.group(1))
    nums = re.findall(r"\d+", Path(name).stem)
    return int(nums[-1]) if nums else None


def _natural_key(p: Path) -> list:
    return [int(t) if t.isdigit() else t.lower() for t in re.split(r"(\d+)", p.name)]


_Z_KEYS = re.compile(
    r"^(z|z[ _]?position|height|level|layer[ _]?height|position|axial position|plane height|z \(mm\)|height \(mm\))$",
    re.I,
)


def _z_from_meta(meta: dict[str, str], z_units: str | None, where: str) -> float | None:
    for k, v in meta.items():
        if _Z_KEYS.match(k.strip()):
            m = re.match(rf"^\s*({_NUM})\s*([A-Za-zµμ\"]+)?", v)
            if not m:
                continue
            val = float(m.group(1).replace(",", "."))
            unit = m.group(2) or z_units
            if unit is None:
                raise BadInputError(
                    f"{where}: header gives {k} = {v!r} without a unit; pass z_units=... "
                    "(--z-units mm) or layer_spacing=... (--layer-spacing-mm)"
                )
            return val * unit_factor(unit, where=where)
    return None


_MANIFESTS = ("manifest.csv", "manifest.txt", "manifest.json", "layers.csv", "layers.txt")


def _read_manifest(folder: Path, z_units: str | None) -> tuple[Path, dict[str, float]] | None:
    """(manifest path, {file: z [m]}) of a folder, or None; every listed file must exist."""
    for name in _MANIFESTS:
        p = folder / name
        if not p.exists():
            continue
        lines_of: dict[str, int] = {}
        if p.suffix == ".json":
            try:
                raw = json.loads(p.read_text())
                unit = raw.get("units", z_units)
                vals = {str(k): float(v) for k, v in raw["layers"].items()}
            except (ValueError, KeyError, TypeError, AttributeError) as exc:
                raise BadInputError(
                    f"'{p}': expected JSON {{'units': 'mm', 'layers': {{file: z}}}} ({exc})"
                ) from None
        else:
            vals = {}
            unit = None
            for i, ln in enumerate(p.read_text().splitlines(), start=1):
                st = ln.strip()
                if not st:
                    continue
                if st.startswith("#"):
                    m = re.search(r"units?\s*[:=]\s*(\S+)", st, re.I)
                    if m:
                        unit = m.group(1)
                    continue
                toks = [t.strip() for t in re.split(r"[,;\t]|\s+", st) if t.strip()]
                if len(toks) < 2:
                    raise BadInputError(f"'{p}' line {i}: expected 'file, z', found {st!r}")
                try:
                    vals[toks[0]] = float(toks[1].replace(",", "."))
                    lines_of[toks[0]] = i
                except ValueError:
                    if not vals:
                        m = re.search(r"[\[(]\s*([^\])]+)\s*[\])]", st) or re.search(
                            r"z[_ ]?(mm|um|µm|m|in|inch)\b", st, re.I
                        )
                        if m:
                            unit = m.group(1)
                        continue  # header line
                    raise BadInputError(f"'{p}' line {i}: z {toks[1]!r} is not a number") from None
            if (
                unit is not None
                and z_units is not None
                and unit_factor(unit) != unit_factor(z_units)
            ):
                raise BadInputError(
                    f"'{p}': z_units={z_units!r} (--z-units) contradicts the manifest, which says "
                    f"{unit!r}; drop the option or correct the manifest"
                )
            unit = unit or z_units
        if unit is None:
            raise BadInputError(
                f"'{p}': the unit of z is not stated (e.g. a first line 'file,z_mm'); add it or "
                "pass z_units=... (--z-units mm)"
            )
        missing = [
            k
            for k in vals
            if not (folder / k).is_file() and not any(folder.glob(glob.escape(k) + ".*"))
        ]
        if missing:
            where = f" line {lines_of[missing[0]]}" if missing[0] in lines_of else ""
            raise BadInputError(
                f"'{p}'{where}: names '{missing[0]}'"
                + (f" (and {len(missing) - 1} more)" if len(missing) > 1 else "")
                + f", which is not in '{folder}'; restore the file or delete it from the manifest"
            )
        f = unit_factor(unit, where=str(p))
        return p, {k: v * f for k, v in vals.items()}
    return None


def _as_convention(convention) -> AngleConvention:
    if convention is None:
        raise ConventionError(
            "the instrument's angle convention is not given: say where the instrument's 0 degree "
            "points in the bearing frame and which way its angle turns, e.g. "
            "convention=('-x', 'clockwise') (CLI: --angle-zero -x --angle-direction clockwise); "
            "text exports rarely state it and jointwear never guesses it"
        )
    if isinstance(convention, AngleConvention):
        return convention
    try:
        zero, direction = convention
    except (TypeError, ValueError):
        raise ConventionError(
            f"convention {convention!r}: expected an AngleConvention or (zero, direction)"
        ) from None
    return AngleConvention(zero, direction)


def _assemble(
    layers: list[_Layer],
    *,
    convention: AngleConvention,
    z_mid: float | str,
    instrument: str,
    fmt_notes: dict,
    metadata: dict,
    files: list[str],
    layout: str,
    allow_partial: bool,
    resample: bool,
) -> xr.Dataset:
    kinds = {lay.kind for lay in layers}
    if len(kinds) > 1:
        raise BadInputError(
            f"layers mix radius and deviation values ({', '.join(sorted(kinds))}); pass "
            "columns=... so every layer has the same meaning"
        )
    kind = kinds.pop()
    counts = [lay.value.size for lay in layers]
    n = max(counts)
    if len(set(counts)) > 1 and not (allow_partial or resample):
        k = int(np.argmin(counts))
        raise BadInputError(
            f"'{layers[k].source}': layer {k + 1} has {counts[k]} points but the other layers "
            f"have {n}; the layer looks truncated - re-export it, or pass allow_partial=True "
            "(missing points become NaN) or resample=True"
        )
    # common angle grid: the first complete layer's, unless layers differ -> uniform grid
    ref = next(lay for lay in layers if lay.value.size == n)
    step = 360.0 / n
    notes = {}
    for lay in layers:  # angles written with a few decimals: snap to the exact uniform grid
        j = np.arange(lay.value.size)
        th0 = float(np.mean(lay.theta_deg - j * step))
        if lay.value.size == n and np.max(np.abs(lay.theta_deg - th0 - j * step)) < 1e-3 * step:
            lay.theta_deg = round(th0, 9) + j * step
            notes["angles_snapped"] = (
                "angles within 0.1 % of a sample step of a uniform grid were set to that grid"
            )
    grid = np.mod(ref.theta_deg, 360.0)
    same = all(
        lay.value.size == n and np.allclose(np.mod(lay.theta_deg, 360.0), grid, atol=1e-6)
        for lay in layers
    )
    if not same:
        grid = np.arange(n) * 360.0 / n
        notes["resampled"] = (
            "layers had different angle samples; every layer was interpolated (periodic, "
            f"linear) onto a uniform grid of {n} points"
        )
    values = np.full((len(layers), n), np.nan)
    for i, lay in enumerate(layers):
        th = np.mod(lay.theta_deg, 360.0)
        if same:
            values[i] = lay.value
        elif allow_partial and not resample:
            # keep the points that fall on the grid, NaN elsewhere
            idx = np.rint(th / (360.0 / n)).astype(int) % n
            values[i, idx] = lay.value
        else:
            o = np.argsort(th)
            tt, vv = th[o], lay.value[o]
            values[i] = np.interp(
                grid,
                np.concatenate([tt[-1:] - 360, tt, tt[:1] + 360]),
                np.concatenate([vv[-1:], vv, vv[:1]]),
            )
    order = np.argsort(grid)
    grid, values = grid[order], values[:, order]
    zs = np.array([lay.z if lay.z is not None else np.nan for lay in layers], dtype=float)
    if np.unique(zs).size != zs.size:
        raise BadInputError(
            f"two layers have the same z ({', '.join(f'{v:g}' for v in zs)} m); check the "
            "manifest / file names / layer_spacing"
        )
    zo = np.argsort(zs)
    zs, values = zs[zo], values[zo]
    if z_mid == "centre":
        mid = 0.5 * (zs.min() + zs.max())
        znote = (
            "z = instrument height minus the middle of the measured layers (assumed to be the "
            "bearing mid-width; pass z_mid to set it)"
        )
    else:
        mid = float(z_mid)
        znote = f"z = instrument height minus {mid:g} m (the bearing mid-width, given)"
    name = "radius" if kind == "radius" else "radial_deviation"
    da = xr.DataArray(
        values,
        dims=("z", "theta"),
        coords={"z": z_coord(zs - mid, note=znote), "theta": theta_coord(grid, convention)},
        attrs={
            "units": "m",
            "long_name": "measured bore radius"
            if kind == "radius"
            else "measured radial deviation (about the instrument's spindle axis)",
        },
    )
    ds = xr.Dataset({name: da})
    ds = convert_theta(ds, CANONICAL)
    ds["z"].attrs["instrument_height_of_z0"] = float(mid)
    origin = _data_origin(metadata)
    attrs = {
        "title": "roundness/cylindricity scan",
        "source": f"{'measurement' if origin == 'measured' else origin}: {instrument}",
        "data_origin": origin,
        "instrument": instrument,
        "instrument_angle_zero": convention.zero,
        "instrument_angle_direction": convention.direction,
        "instrument_angle_note": (
            f"the instrument's 0 degree points along {convention.zero} of the bearing frame and its "
            f"angle increases {convention.direction} seen from +z (stated by the user); theta "
            "has been converted to the canonical convention"
        ),
        "layout": layout,
        "files": files,
        "n_layers": len(layers),
        "n_points_per_layer": int(n),
        "reader_guesses": fmt_notes,
        "instrument_metadata": metadata,
        **notes,
    }
    nominal = _nominal_radius(metadata)
    if nominal is not None:
        attrs["nominal_radius"] = nominal
    ds.attrs.update(attrs)
    return ds


def _data_origin(meta: dict) -> str:
    """``data_origin`` from a ``Data origin:`` header line (generated files say "synthetic").

    An instrument export without that line is taken as measured (it came from the instrument);
    a stated origin is kept whatever it is, so an imported generated scan stays synthetic.
    """
    for k, v in meta.items():
        if str(k).strip().lower().replace("_", " ") == "data origin":
            value = str(v).strip().lower()
            if value in ("measured", "synthetic", "simulated"):
                return value
            raise BadInputError(
                f"header 'Data origin: {v}' is not one of measured, synthetic, simulated; "
                "correct the header line"
            )
    return "measured"


def _nominal_radius(meta: dict) -> float | None:
    for k, v in meta.items():
        kl = k.lower().strip()
        if kl in ("nominal radius", "radius", "nominal_radius", "diameter", "nominal diameter"):
            m = re.match(rf"^\s*({_NUM})\s*([A-Za-zµμ\"]+)?", str(v))
            if m and m.group(2):
                try:
                    val = float(m.group(1).replace(",", ".")) * unit_factor(m.group(2))
                except BadInputError:
                    return None
                return val / 2 if "diameter" in kl else val
    return None


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
    ds.attrs["reader_columns"] = list(parsed[0].columns)
    if parsed[0].units:
        ds.attrs["instrument_units"] = parsed[0].units
    return ds
