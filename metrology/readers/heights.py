"""Height z of each layer: manifests, header keywords, file names (a unit is never guessed)."""

from __future__ import annotations

import glob
import json
import re
from pathlib import Path

from jointwear.errors import BadInputError
from jointwear.metrology.readers.table import _NUM
from jointwear.metrology.readers.units import unit_factor

__all__ = []


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


#: Names (stems) of a folder's heights file: per-layer file, z (never read as a layer).
MANIFEST_STEMS = ("manifest", "layers", "heights", "height", "index", "z", "levels")
_MANIFESTS = tuple(f"{stem}.{ext}" for stem in MANIFEST_STEMS for ext in ("csv", "txt", "json"))
_Z_UNIT_IN_NAME = re.compile(
    r"(?:z|height|h|pos|position|level)[_ ]?(mm|um|µm|m|in|inch)\b|[\[(]\s*([^\])]+)\s*[\])]",
    re.I,
)


def _read_manifest(
    folder: Path, z_units: str | None, heights: Path | None = None
) -> tuple[Path, dict[str, float]] | None:
    """(heights file, {file: z [m]}): the ``heights`` file given, else the first of
    :data:`_MANIFESTS` in ``folder``, else None; every listed file must exist in ``folder``."""
    if heights is not None and not Path(heights).is_file():
        raise BadInputError(f"heights='{heights}' (--heights) is not a file")
    for p in [Path(heights)] if heights is not None else [folder / n for n in _MANIFESTS]:
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
                        m = _Z_UNIT_IN_NAME.search(st)
                        if m:
                            unit = m.group(1) or m.group(2)
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
            from jointwear.metrology.readers.advice import Refusal

            raise Refusal(
                f"'{p}': the unit of z is not stated (e.g. a first line 'file,z_mm'); add it, "
                "or pass z_units='<unit>' with the unit of the heights",
                ({"z_units": "<unit>"},),
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
