"""The height z of every layer, from the one source that states it (or a refusal).

Sources, in the order ``z_source="auto"`` tries them: the ``z`` option; a z column; layer
numbers (a ``Layer`` column, ``Layer 3`` column names, ``Layer 3`` block headers) times the layer
spacing (``layer_spacing`` or a ``Layer spacing: 1 mm`` header line); for per-layer files or
blocks a manifest, a height keyword in each header, z in the file names, the spacing times the
layer number in the file names (else the file order); for a wide file z in the column names.
A column name gives z only when it says z: a z-like word (``z``, ``h``, ``height``,
``position``) or a length unit next to the number (``2.0 mm``); ``Layer 3`` is a layer number,
``Radius1`` a probe. Two sources that disagree (z in the file names and in the headers) are
refused; an option that is given but cannot apply (a spacing when the files state z, a z unit
when nothing needs one) is an error, never ignored.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from jointwear.errors import BadInputError
from jointwear.metrology.choices import Z_SOURCES
from jointwear.metrology.readers.advice import Refusal, advise
from jointwear.metrology.readers.claims import claim
from jointwear.metrology.readers.heights import (
    _layer_index_from_name,
    _number_from_name,
    _read_manifest,
    _z_from_meta,
)
from jointwear.metrology.readers.layers import _Layer
from jointwear.metrology.readers.table import _NUM, ParsedFile
from jointwear.metrology.readers.units import unit_factor

__all__ = ["Z_SOURCES", "assign_z", "wide_name_z"]


_UNIT = r"(mm|um|µm|μm|m|in|inch)"
_Z_NAME = re.compile(
    rf"^\s*(?:z|h|height|z[ _-]?pos(?:ition)?|position|pos)\s*[=:_]?\s*({_NUM})\s*{_UNIT}?\s*$",
    re.I,
)
_UNIT_NAME = re.compile(rf"(?:^|[\s@=:(\[_])({_NUM})\s*{_UNIT}\b", re.I)
_INDEX_NAME = re.compile(r"^\s*(?:layer|plane|trace|level|section)\s*[#_:=]?\s*(\d+)\s*$", re.I)
_LAYER_KEY = re.compile(r"^(layer|plane|trace)[ _]?(number|no\.?|nr\.?|#|index)?$", re.I)


def wide_name_z(name: str) -> tuple[str, float | None, str | None]:
    """What a wide file's value-column name says: ("z", value, unit or None), ("index", n,
    None) or ("none", None, None) (a probe or anything else)."""
    m = _Z_NAME.match(name)
    if m:
        return "z", float(m.group(1).replace(",", ".")), m.group(2)
    m = _UNIT_NAME.search(name)
    if m:
        return "z", float(m.group(1).replace(",", ".")), m.group(2)
    m = _INDEX_NAME.match(name)
    if m:
        return "index", float(m.group(1)), None
    return "none", None, None


def _spacing(
    layer_spacing: float | None, meta: dict[str, str], z_units: str | None, where: str
) -> tuple[float, str] | None:
    """(spacing [m], where from) from the option or the header, else None."""
    if layer_spacing is not None:
        return float(layer_spacing), "layer_spacing"
    c = claim(meta, "layer_spacing")
    if c is None:
        return None
    m = re.match(rf"^\s*({_NUM})\s*([A-Za-zµμ\"]+)?", c[1])
    if not m:
        return None
    unit = m.group(2) or z_units
    if unit is None:
        raise Refusal(
            f"{where}: header {c[0]} = {c[1]!r} gives no unit; pass z_units=... (--z-units mm)",
            ({"z_units": "<unit>"},),
        )
    return float(m.group(1).replace(",", ".")) * unit_factor(unit), f"header {c[0]}"


def _need_spacing(where: str, what: str) -> Refusal:
    text, sugg = advise([({"layer_spacing": "<m>"}, "the distance between layers")])
    return Refusal(f"{where}: {what}; {text}, or z=[...]", sugg)


def _numbered_spacing(
    layer_spacing, meta, z_units, where: str, numbered: str, what: str = "layers"
) -> tuple[float, str]:
    """The spacing that turns layer numbers into z (option or header), else a refusal saying
    that the ``what`` are ``numbered`` (which says nothing of their height)."""
    sp = _spacing(layer_spacing, meta, z_units, where)
    if sp is None:
        raise _need_spacing(where, f"the {what} are {numbered}, which says nothing of their height")
    return sp


def assign_z(
    layers: list[_Layer],
    parsed: list[ParsedFile],
    layout: str,
    folder: Path | None,
    *,
    z: list[float] | None,
    layer_spacing: float | None,
    z_units: str | None,
    z_source: str,
    where: str,
    heights: Path | None = None,
) -> str:
    """Set ``z`` [m] of every layer; returns how (for ``reader_guesses``). ``heights``: a file
    of (layer file, z) lines, as a folder's ``manifest.csv``."""
    if z_source not in Z_SOURCES:
        raise BadInputError(f"z_source {z_source!r} is not known; use {', '.join(Z_SOURCES)}")
    meta = parsed[0].metadata
    if heights is not None and layout != "folder":
        raise BadInputError(
            f"{where}: heights='{heights}' (--heights) gives the z of per-layer files, but this "
            f"scan is one {layout} file; drop the option"
        )
    src, unit_used, spacing_used = _find_z(
        layers, parsed, layout, folder, z, layer_spacing, z_units, z_source, where, meta, heights
    )
    if layer_spacing is not None and not spacing_used and len(layers) > 1:
        zs = np.sort([lay.z for lay in layers])
        d = np.diff(zs)
        if d.size == 0 or np.max(np.abs(d - layer_spacing)) > 0.01 * layer_spacing:
            raise Refusal(
                f"{where}: layer_spacing={layer_spacing:g} m (--layer-spacing-mm) cannot apply: "
                f"the z of the layers comes from the {src}"
                + (f" (spacing {np.median(d):g} m)" if d.size else "")
                + "; drop the option (pass without layer_spacing), or pass z_source='spacing' "
                "to use it instead",
                ({"layer_spacing": None}, {"z_source": "spacing"}),
            )
    if z_units is not None and not unit_used:
        raise Refusal(
            f"{where}: z_units={z_units!r} (--z-units) cannot apply: the z of the layers comes "
            f"from the {src}, which needs no unit; drop the option",
            ({"z_units": None},),
        )
    return src


def _find_z(
    layers, parsed, layout, folder, z, layer_spacing, z_units, z_source, where, meta, heights
):
    """(source, z unit option used, spacing option used)."""
    auto = z_source == "auto"
    if z is not None or z_source == "option":
        if z is None:
            raise BadInputError(f"{where}: z_source='option' needs z=[...]")
        zv = [float(v) for v in z]
        if len(zv) != len(layers):
            raise BadInputError(
                f"z gives {len(zv)} heights but the scan has {len(layers)} layers; give one per layer"
            )
        for lay, v in zip(layers, zv, strict=True):
            lay.z = v
        return "option z", False, False
    if all(lay.z is not None for lay in layers) and (auto or z_source == "column"):
        col = [i for i, c in enumerate(parsed[0].columns) if c == "z"]
        named = bool(col) and str(col[0]) in parsed[0].column_units
        return "z column", not named and z_units is not None, False
    numbers = [lay.index for lay in layers]
    block_heights = layout == "blocks" and all(
        _z_from_meta(pf.metadata, pf.z_units, f"'{pf.path}'") is not None for pf in parsed
    )
    if all(v is not None for v in numbers) and (
        (auto and not block_heights) or z_source in ("numbers", "spacing")
    ):
        listed = ", ".join(f"{v:g}" for v in numbers[:4]) + (", ..." if len(numbers) > 4 else "")
        sp = _numbered_spacing(layer_spacing, meta, z_units, where, f"numbered ({listed})")
        for lay, v in zip(layers, numbers, strict=True):
            lay.z = float(v) * sp[0]
        return (
            f"layer numbers x spacing ({sp[1]})",
            sp[1] != "layer_spacing" and bool(z_units),
            sp[1] == "layer_spacing",
        )
    if layout in ("folder", "blocks"):
        return _z_per_part(
            layers, parsed, folder, layer_spacing, z_units, z_source, where, meta, heights
        )
    if layout == "wide":
        return _z_wide(layers, parsed[0], layer_spacing, z_units, z_source, where, meta)
    if len(layers) == 1:
        layers[0].z = 0.0
        return "single layer (z = 0)", False, False
    raise BadInputError(f"{where}: cannot tell the z of the {len(layers)} layers; pass z=[...]")


def _z_per_part(layers, parsed, folder, layer_spacing, z_units, z_source, where, meta, heights):
    """z of per-layer files (or blocks): manifest, header keyword, file names, spacing."""
    blocks = len({pf.path for pf in parsed}) == 1 and len(parsed) > 1
    if folder is None and heights is not None:
        folder = Path(parsed[0].path).parent
    if folder is not None and z_source in ("auto", "manifest"):
        found = _read_manifest(folder, z_units, heights)
        if found:
            manifest = found[1]
            for lay in layers:
                name = Path(lay.source).name
                key = name if name in manifest else Path(name).stem
                if key not in manifest:
                    raise BadInputError(
                        f"manifest '{found[0]}' has no entry for '{name}'; add a line '{name}, <z>'"
                    )
                lay.z = manifest[key]
            return f"heights file '{found[0].name}'", z_units is not None, False
        if z_source == "manifest":
            raise BadInputError(f"z_source='manifest' but '{folder}' holds no manifest.csv")
    zh = [_z_from_meta(pf.metadata, pf.z_units, f"'{pf.path}'") for pf in parsed]
    have_h = all(v is not None for v in zh)
    zn = None
    if not blocks:
        try:
            zn = [_number_from_name(Path(lay.source).name, z_units) for lay in layers]
        except BadInputError:
            if have_h and z_source in ("auto", "header"):
                zn = None  # the names give a bare number; the headers state z
            else:
                raise
    have_n = zn is not None and all(v is not None for v in zn) and len(set(zn)) == len(zn)
    if have_h and have_n and z_source == "auto" and not np.allclose(zh, zn, rtol=0, atol=1e-9):
        k = int(np.argmax(np.abs(np.subtract(zh, zn))))
        text, sugg = advise(
            [
                ({"z_source": "header"}, "if the headers are right"),
                ({"z_source": "names"}, "if the file names are right"),
            ]
        )
        raise Refusal(
            f"'{layers[k].source}': the header says z = {zh[k]:g} m but the file name says "
            f"z = {zn[k]:g} m; {text}",
            sugg,
        )
    unit_needed = z_units is not None
    if have_h and z_source in ("auto", "header"):
        for lay, v in zip(layers, zh, strict=True):
            lay.z = v
        return "header keyword" + (" (the file names agree)" if have_n else ""), unit_needed, False
    if have_n and z_source in ("auto", "names"):
        for lay, v in zip(layers, zn, strict=True):
            lay.z = v
        return "file names", unit_needed, False
    if z_source in ("header", "names"):
        raise BadInputError(f"{where}: z_source={z_source!r} but the {z_source} give no z")
    sp = _spacing(layer_spacing, meta, z_units, where)
    if sp is not None:
        idx = [_layer_index_from_name(Path(lay.source).name) for lay in layers]
        if blocks or any(i is None for i in idx) or len(set(idx)) != len(idx):
            idx = list(range(len(layers)))
        for lay, i in zip(layers, idx, strict=True):
            lay.z = float(i) * sp[0]
        return (
            f"spacing ({sp[1]}) x layer number (from the file names, else the order)",
            False,
            sp[1] == "layer_spacing",
        )
    if len(layers) == 1:
        layers[0].z = 0.0
        return "single layer", False, False
    what = "blocks" if blocks else "layer files"
    raise _need_spacing(
        where,
        f"cannot tell the z of the {len(layers)} {what}: no manifest.csv, no height keyword in "
        "the headers, no z in the file names",
    )


def _z_wide(layers, pf, layer_spacing, z_units, z_source, where, meta):
    """z of the value columns of a wide file: from names that say z, else the spacing."""
    names = pf.column_names
    vidx = [i for i, c in enumerate(pf.columns) if c in ("radius", "deviation", "value")]
    said = [wide_name_z(names[i]) for i in vidx] if names and len(names) == len(pf.columns) else []
    if said and all(k == "z" for k, _, _ in said) and z_source in ("auto", "names"):
        zs = []
        for (_, v, u), i in zip(said, vidx, strict=True):
            u = u or pf.z_units
            if u is None:
                raise Refusal(
                    f"{where}: column name {names[i]!r} gives z without a unit; pass "
                    "z_units=... (--z-units mm)",
                    ({"z_units": "<unit>"},),
                )
            zs.append(v * unit_factor(u))
        if len(set(zs)) == len(zs):
            for lay, v in zip(layers, zs, strict=True):
                lay.z = v
            unit_used = any(u is None for _, _, u in said)
            return "column names", unit_used and z_units is not None, False
    if said and all(k == "index" for k, _, _ in said) and z_source in ("auto", "numbers"):
        for lay, (_, v, _) in zip(layers, said, strict=True):
            lay.index = v
        listed = ", ".join(names[i] for i in vidx[:3]) + (", ..." if len(vidx) > 3 else "")
        sp = _numbered_spacing(
            layer_spacing, meta, z_units, where, f"numbered as layers ({listed})", "value columns"
        )
        for lay in layers:
            lay.z = float(lay.index) * sp[0]
        return (
            f"layer numbers in the column names x spacing ({sp[1]})",
            False,
            (sp[1] == "layer_spacing"),
        )
    sp = _spacing(layer_spacing, meta, z_units, where)
    if sp is not None and z_source in ("auto", "spacing"):
        for i, lay in enumerate(layers):
            lay.z = i * sp[0]
        return f"spacing ({sp[1]}) x column order", False, sp[1] == "layer_spacing"
    angle = next(
        (c for c in pf.columns if c in ("angle", "angle_deg", "angle_rad", "angle_grad", "index")),
        None,
    )
    alts = [({"layer_spacing": "<m>"}, "if the columns are layers, in order of height")]
    if angle is not None:
        first = tuple(
            c if c not in ("radius", "deviation", "value") or i == vidx[0] else "ignore"
            for i, c in enumerate(pf.columns)
        )
        alts.append(({"columns": first}, "if they are probes: read the first one"))
    text, sugg = advise(alts)
    shown = ", ".join(repr(names[i]) for i in vidx[:3]) if said else "no column names"
    raise Refusal(
        f"{where}: {len(layers)} value columns ({shown}) and nothing says they are layers or "
        f"at what height (a column name gives z only as 'z=2 mm', 'Height 2.0 mm' or '2.0 mm'); "
        f"{text}",
        sugg,
    )


def layer_numbers_from_meta(pf: ParsedFile) -> float | None:
    """A layer number stated in a (block) header: ``Layer number: 3``, ``Plane: 3``."""
    for k, v in pf.metadata.items():
        if _LAYER_KEY.match(k.strip()):
            m = re.match(r"^\s*(\d+)\s*$", str(v))
            if m:
                return float(m.group(1))
    return None
