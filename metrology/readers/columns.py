"""Column meanings of a numeric table: from the column names, else from the values."""

from __future__ import annotations

import re
from collections.abc import Sequence

import numpy as np

__all__ = ["COLUMN_KINDS"]


#: Column meanings understood by the reader.
COLUMN_KINDS = (
    "angle",  # unit from the header, the user (angle_unit) or the values - else refused
    "angle_deg",
    "angle_rad",
    "angle_grad",  # gradians (gon): 400 per turn
    "index",
    "x",
    "y",
    "z",
    "layer",  # layer number: z = number x layer spacing
    "radius",
    "deviation",
    "value",  # radius or deviation: from the user (value_kind) or the values - else refused
    "ignore",
)


_UNIT_IN_NAME = re.compile(r"[\[(]\s*([^\])]+?)\s*[\])]")


_ANG = r"(theta|angle|phi|φ|θ|winkel|ang|azimuth)"
# Rules are tried in order; value names are matched as phrases, deviation words first, so that
# "Radius deviation (um)" is a deviation and only a plain "Radius" is a radius.
_NAME_RULES: list[tuple[str, str]] = [
    (r"^(x|x[ _-]?coord.*|cart.*x)$", "x"),
    (r"^(y|y[ _-]?coord.*|cart.*y)$", "y"),
    (rf"^{_ANG}[ _-]*(rad|radians?)$|^radians?$", "angle_rad"),
    (rf"^{_ANG}[ _-]*(deg|degrees?|°)$|^(deg|degrees?|°)$", "angle_deg"),
    (rf"^{_ANG}[ _-]*(gon|grad|gradians?)$|^(gon|gradians?)$", "angle_grad"),
    (rf"^{_ANG}\b", "angle"),  # an angle of unstated unit
    (r"^(index|point|pt|no\.?|n|#|sample|idx|nr\.?)$", "index"),
    (r"^(z|height|level|layer|position|pos|zpos|h)\b", "z"),
    (
        r"deviation|abweichung|\bdev\b|displacement|\bdispl?\b|error|runout|departure|\bform\b",
        "deviation",
    ),
    (r"^r$|\bradius\b|\bradii\b", "radius"),
    (r"profile|value|ampl|signal|data|reading|trace|μ|µ|\bum\b", "value"),
]


def _kind_from_name(name: str) -> tuple[str | None, str | None]:
    """(column kind, unit) from a column name like 'Angle (deg)' or 'Deviation [µm]'."""
    unit = None
    m = _UNIT_IN_NAME.search(name)
    low = name.strip().lower()
    if m:
        unit = m.group(1).strip()
        low_base = _UNIT_IN_NAME.sub("", low).strip()
    else:
        low_base = low
    if unit and unit.lower() in ("deg", "degree", "degrees", "°"):
        return "angle_deg", None
    if unit and unit.lower() in ("rad", "radian", "radians"):
        return "angle_rad", None
    if unit and unit.lower() in ("index", "point", "points", "#"):
        return "index", None
    if unit and unit.lower() in ("gon", "grad", "grads", "gradian", "gradians"):
        return "angle_grad", None
    if re.match(r"^(z|h|height|layer|level|plane)\s*[=:_]?\s*[-+]?\d", low):
        return None, None  # a per-layer value column of a wide file, named by its z
    if re.fullmatch(r"(layer|plane|trace)[ _]?(no\.?|nr\.?|number|#|index|idx)?", low_base):
        return ("layer", None) if unit is None else ("z", unit)
    for pat, kind in _NAME_RULES:
        if re.search(pat, low_base):
            return kind, unit
    return None, unit


def _first_run(c: np.ndarray) -> int:
    """Length of the first run of equal values."""
    change = np.flatnonzero(c[1:] != c[:-1])
    return int(change[0]) + 1 if change.size else c.size


def _runs(c: np.ndarray) -> bool:
    """True if ``c`` consists of a few long runs of equal values (a z column)."""
    n = c.size
    if n < 8:
        return False
    changes = int(np.count_nonzero(c[1:] != c[:-1]))
    return changes + 1 <= max(1, n // 8) and _first_run(c) >= 4


def _xy_like(a: np.ndarray, b: np.ndarray) -> bool:
    """Cartesian points around the origin: both coordinates change sign, similar spread."""
    if not (np.any(a < 0) and np.any(a > 0) and np.any(b < 0) and np.any(b > 0)):
        return False
    sa, sb = np.ptp(a), np.ptp(b)
    r = np.hypot(a, b)
    # points on a (nearly) round profile: the distance from the origin hardly varies
    return bool(min(sa, sb) > 0.5 * max(sa, sb) and np.ptp(r) < 0.2 * np.mean(r))


def _looks_monotonic(c: np.ndarray) -> bool:
    d = np.diff(c)
    if d.size == 0:
        return False
    return bool(np.mean(d > 0) > 0.95 or np.mean(d < 0) > 0.95)


def _guess_columns(
    data: np.ndarray, names: Sequence[str]
) -> tuple[tuple[str, ...], dict[str, str]]:
    ncol = data.shape[1]
    kinds: list[str | None] = [None] * ncol
    units: dict[str, str] = {}
    if names and len(names) == ncol:
        for i, nm in enumerate(names):
            k, u = _kind_from_name(nm)
            kinds[i] = k
            if u:
                units[str(i)] = u
    if all(k is not None for k in kinds):
        return tuple(kinds), units  # type: ignore[arg-type]
    # fill the gaps from the values
    if ncol == 1:
        return (kinds[0] or "value",), units
    if ncol == 2:
        a, b = data[:, 0], data[:, 1]
        if kinds[0] is None and _runs(a):
            kinds[0] = "z"  # (z, value): a long file without an angle column
        if kinds[0] is None:
            if _looks_monotonic(a):
                kinds[0] = "angle"
            elif _xy_like(a, b):
                kinds[0], kinds[1] = "x", "y"
            else:  # two value columns: a wide file of two layers without an angle column
                kinds[0] = "value"
        if kinds[1] is None:
            kinds[1] = "y" if kinds[0] == "x" else "value"
        return tuple(kinds), units  # type: ignore[arg-type]
    # three or more columns
    c0 = data[:, 0]
    few0 = np.unique(c0[np.isfinite(c0)]).size <= max(2, data.shape[0] // 8)
    if ncol == 3 and kinds == [None, None, None]:
        c2 = data[:, 2]
        if few0 and _runs(c0):
            first = data[: _first_run(c0)]
            if _xy_like(first[:, 1], first[:, 2]):
                kinds = ["z", "x", "y"]
            else:
                kinds = ["z", "angle", "value"]
        elif np.unique(c2[np.isfinite(c2)]).size <= max(2, data.shape[0] // 8):
            kinds = ["x", "y", "z"]
        elif (
            _looks_monotonic(c0)
            and np.all(np.abs(c0 - np.round(c0)) < 1e-9)
            and _looks_monotonic(data[:, 1])
        ):
            kinds = ["index", "angle", "value"]
        elif _looks_monotonic(c0):
            kinds = ["angle", "value", "value"]
        else:  # three value columns: a wide file without an angle column
            vk3 = "value"
            kinds = [vk3, vk3, vk3]
        return tuple(kinds), units  # type: ignore[arg-type]
    # wide: angle + one value column per layer
    if kinds[0] is None and _looks_monotonic(c0):
        kinds[0] = "angle"
    if kinds[0] in ("angle", "angle_deg", "angle_rad", "angle_grad", "index"):
        for i in range(1, ncol):  # a second angle column: another probe's trace, not a layer
            if kinds[i] is None and _looks_monotonic(data[:, i]):
                kinds[i] = "angle"
    start = 0 if kinds[0] is None else 1  # no angle column: every column is a layer
    vk = next((k for k in kinds[start:] if k in ("radius", "deviation")), None) or "value"
    for i in range(ncol):
        if kinds[i] is None:
            kinds[i] = vk
    return tuple(kinds), units  # type: ignore[arg-type]
