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
    2.54e-8: "uin",
}


#: Lengths a roundness export may be written in [m]: a unit outside is no unit of one.
_PLAUSIBLE_UNIT = (1e-10, 1.0)


def unit_factor(unit: str, *, where: str = "units") -> float:
    """Factor from a length unit name to metres; a clear error for unknown units.

    The common names are in :data:`UNITS`; any other is parsed by pint (``uin``, ``µin``,
    ``microinch``, ``thou``, ``angstrom``...) and accepted when it is a length between
    0.1 nm and 1 m.
    """
    key = str(unit).strip().strip(".").replace(" ", "")
    low = key.lower()
    for k in (key, low):
        if k in UNITS:
            return UNITS[k]
    factor = _pint_length(key.replace("micro-", "micro").replace("μ", "µ"))
    if factor is not None:
        return factor
    raise BadInputError(
        f"{where}: unit {unit!r} is not known; use one of um (micrometre), mm, m, inch, uin "
        "(micro-inch) (pass units=... to override what the file says)"
    )


def _pint_length(name: str) -> float | None:
    """Metres per ``name`` if pint knows it as a plausible length unit, else None."""
    import pint

    try:
        q = _registry()(name)
    except Exception:  # pint's parser raises many kinds (even AssertionError) on non-units
        return None
    if not isinstance(q, pint.Quantity) or q.dimensionality != {"[length]": 1}:
        return None
    factor = float(q.to("m").magnitude)
    return factor if _PLAUSIBLE_UNIT[0] <= factor <= _PLAUSIBLE_UNIT[1] else None


def _registry():
    """One pint registry per process (loading it costs about half a CPU second)."""
    global _UREG
    if _UREG is None:
        import pint

        _UREG = pint.UnitRegistry()
    return _UREG


_UREG = None


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
    unknown: list[tuple[str, str]] = []
    head_unit = _units_from_meta(meta)
    if head_unit is not None:
        ln_no = next((i + 1 for i, ln in enumerate(header) if head_unit in ln), max(len(header), 1))
        stated.append((head_unit, f"line {ln_no} (header)"))
    for i, c in enumerate(cols):
        if c in _LENGTH_KINDS and str(i) in name_units:
            stated.append((name_units[str(i)], f"the name of column {i + 1}"))
    for u, w in list(stated):
        try:
            unit_factor(u)
        except BadInputError:
            unknown.append((u, w))
            stated.remove((u, w))
    if unknown and option is None:
        from jointwear.metrology.readers.advice import Refusal

        u, w = unknown[0]
        raise Refusal(
            f"'{path}' {w.split(' (')[0]}: unit {u!r} is not known (um, mm, m, inch, uin and other "
            "lengths pint knows are); pass units='<unit>' with the unit the values are in",
            ({"units": "<unit>"},),
        )
    if unknown:
        guessed["unknown_unit"] = (
            f"{', '.join(repr(u) for u, _ in unknown)} ({unknown[0][1]}) is no known unit: "
            f"the values are read in {option!r} (units= given)"
        )
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
