"""Length units: names, factors to metres, and the unit a file states (never guessed)."""

from __future__ import annotations

import re
from collections.abc import Sequence

from jointwear.errors import BadInputError

__all__ = ["UNITS", "unit_factor"]


#: Length units -> factor to metres.
UNITS: dict[str, float] = {
    "m": 1.0,
    "mm": 1e-3,
    "um": 1e-6,
    "µm": 1e-6,
    "μm": 1e-6,
    "micron": 1e-6,
    "microns": 1e-6,
    "micrometre": 1e-6,
    "micrometer": 1e-6,
    "micrometres": 1e-6,
    "micrometers": 1e-6,
    "millimetre": 1e-3,
    "millimeter": 1e-3,
    "millimetres": 1e-3,
    "millimeters": 1e-3,
    "metre": 1.0,
    "meter": 1.0,
    "metres": 1.0,
    "meters": 1.0,
    "nm": 1e-9,
    "in": 0.0254,
    "inch": 0.0254,
    "inches": 0.0254,
    '"': 0.0254,
}


_UNIT_CANON = {
    1.0: "m",
    1e-3: "mm",
    1e-6: "um",
    1e-9: "nm",
    0.0254: "inch",
}


def unit_factor(unit: str, *, where: str = "units") -> float:
    """Factor from a length unit name to metres; a clear error for unknown units."""
    key = str(unit).strip().strip(".").replace(" ", "")
    low = key.lower()
    for k in (key, low):
        if k in UNITS:
            return UNITS[k]
    raise BadInputError(
        f"{where}: unit {unit!r} is not known; use one of um (micrometre), mm, m, inch "
        "(pass units=... to override what the file says)"
    )


_UNIT_KEYS = re.compile(r"^(units?|length[ _]?units?|einheit|unit of measure|scale units?)$", re.I)


def _units_from_meta(meta: dict[str, str]) -> str | None:
    for k, v in meta.items():
        if _UNIT_KEYS.match(k.strip()):
            return v.strip()
    return None


_LENGTH_KINDS = ("radius", "deviation", "value", "x", "y")


def _file_units(
    path: str,
    header: Sequence[str],
    meta: dict[str, str],
    cols: Sequence[str],
    name_units: dict[str, str],
    option: str | None,
    guessed: dict[str, str],
) -> str | None:
    """The length unit of the values: stated by the file (header keyword, column names) or by
    the user; a user's unit that contradicts the file is an error, never an override."""
    stated: list[tuple[str, str]] = []
    head_unit = _units_from_meta(meta)
    if head_unit is not None:
        ln_no = next((i + 1 for i, ln in enumerate(header) if head_unit in ln), max(len(header), 1))
        unit_factor(head_unit, where=f"'{path}' line {ln_no}")
        stated.append((head_unit, f"line {ln_no} (header)"))
    for i, c in enumerate(cols):
        if c in _LENGTH_KINDS and str(i) in name_units:
            u = name_units[str(i)]
            unit_factor(u, where=f"'{path}' column {i + 1} name")
            stated.append((u, f"the name of column {i + 1}"))
    factors = {unit_factor(u) for u, _ in stated}
    if len(factors) > 1:
        raise BadInputError(
            f"'{path}': the file states different length units: "
            + ", ".join(f"{u!r} in {w}" for u, w in stated)
            + "; correct the file"
        )
    if option is not None:
        if stated and unit_factor(option) not in factors:
            u, w = stated[0]
            raise BadInputError(
                f"'{path}': units={option!r} (--units {option}) contradicts the file, which says "
                f"{u!r} in {w}; a {unit_factor(u) / unit_factor(option):g}x error - drop the "
                "option (the file states its unit), or correct the file if it is wrong"
            )
        return option
    if stated:
        guessed["units"] = f"{stated[0][0]} (stated in {stated[0][1]})"
        return stated[0][0]
    return None
