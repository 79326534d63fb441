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

import io
import json
import re
from collections.abc import Iterable, Sequence
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path

import numpy as np
import pandas as pd
import xarray as xr

from jointwear.conventions import (
    CANONICAL,
    AngleConvention,
    convert_theta,
    theta_coord,
    z_coord,
)
from jointwear.errors import BadInputError, ConventionError

__all__ = [
    "COLUMN_KINDS",
    "UNITS",
    "TextFormat",
    "ParsedFile",
    "sniff",
    "parse_file",
    "read_text",
    "read_scan",
]

#: Column meanings understood by the reader.
COLUMN_KINDS = (
    "angle_deg",
    "angle_rad",
    "index",
    "x",
    "y",
    "z",
    "radius",
    "deviation",
    "ignore",
)

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

_DELIMS = {"\t": "tab", ";": "semicolon", ",": "comma", " ": "whitespace"}
_NUM = r"[-+]?(?:\d+(?:[.,]\d*)?|[.,]\d+)(?:[eE][-+]?\d+)?"
_NUM_RE = re.compile(rf"^\s*{_NUM}\s*$")
_KV_RE = re.compile(r"^\s*([A-Za-zµμ_#][^:=\t]{0,60}?)\s*(?::|=|\t)\s*(.*?)\s*$")
_UNIT_IN_NAME = re.compile(r"[\[(]\s*([^\])]+?)\s*[\])]")


@dataclass(frozen=True)
class TextFormat:
    """How to read one text export. ``None`` means: sniff it (and record the guess).

    Parameters
    ----------
    delimiter : {"\\t", ";", ",", " "}, optional
        Field separator (``" "`` = any run of whitespace).
    decimal : {".", ","}, optional
        Decimal separator.
    header_lines : int, optional
        Number of lines before the numeric table (metadata and column names).
    columns : tuple of str, optional
        Meaning of each column, from :data:`COLUMN_KINDS`; for a wide file the value columns
        are all ``"radius"`` or ``"deviation"``.
    units : str, optional
        Unit of the length columns: ``"um"``, ``"mm"``, ``"m"``, ``"inch"`` (overrides the header).
    encoding : str, optional
        Text encoding (default: UTF-8, falling back to Latin-1).
    """

    delimiter: str | None = None
    decimal: str | None = None
    header_lines: int | None = None
    columns: tuple[str, ...] | None = None
    units: str | None = None
    encoding: str | None = None

    def __post_init__(self) -> None:
        if self.delimiter is not None and self.delimiter not in _DELIMS:
            names = {"tab": "\t", "semicolon": ";", "comma": ",", "whitespace": " ", "space": " "}
            if self.delimiter in names:
                object.__setattr__(self, "delimiter", names[self.delimiter])
            else:
                raise BadInputError(
                    f"delimiter {self.delimiter!r} is not supported; use tab, ';', ',' or ' ' "
                    "(whitespace)"
                )
        if self.decimal not in (None, ".", ","):
            raise BadInputError(f"decimal {self.decimal!r} must be '.' or ','")
        if self.columns is not None:
            cols = tuple(str(c).strip().lower() for c in self.columns)
            bad = [c for c in cols if c not in COLUMN_KINDS]
            if bad:
                raise BadInputError(
                    f"column meaning(s) {', '.join(map(repr, bad))} not understood; use "
                    + ", ".join(COLUMN_KINDS)
                )
            object.__setattr__(self, "columns", cols)
        if self.units is not None:
            unit_factor(self.units, where="option units")
        if self.header_lines is not None and self.header_lines < 0:
            raise BadInputError(f"header_lines must be >= 0, got {self.header_lines}")


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


@dataclass
class ParsedFile:
    """A sniffed and parsed text file: the numeric table plus everything that was guessed."""

    path: str
    data: np.ndarray  # (n_rows, n_cols) float
    line_numbers: np.ndarray  # 1-based line number of each row
    columns: tuple[str, ...]
    column_names: tuple[str, ...]
    units: str | None
    metadata: dict[str, str] = field(default_factory=dict)
    fmt: TextFormat = field(default_factory=TextFormat)
    guessed: dict[str, str] = field(default_factory=dict)
    n_lines: int = 0
    column_units: dict[str, str] = field(default_factory=dict)


# ------------------------------------------------------------------------------------------
# sniffing
# ------------------------------------------------------------------------------------------


def _read_text(path: Path, encoding: str | None) -> str:
    try:
        raw = path.read_bytes()
    except FileNotFoundError:
        raise BadInputError(f"'{path}' does not exist") from None
    except IsADirectoryError:
        raise BadInputError(
            f"'{path}' is a folder; use layout='folder' to read per-layer files"
        ) from None
    if not raw.strip():
        raise BadInputError(
            f"'{path}' is empty (line 1): expected a text export of a roundness trace; "
            "re-export the measurement"
        )
    head = raw[:8192]
    ctrl = sum(1 for b in head if b < 32 and b not in (9, 10, 13, 12))
    if b"\x00" in head or ctrl > 0.01 * len(head):
        raise BadInputError(
            f"'{path}' looks like a binary file (line 1 holds control bytes), not a text "
            "export; export the trace as text (ASCII/CSV) from the instrument software"
        )
    if encoding:
        try:
            return raw.decode(encoding)
        except (UnicodeDecodeError, LookupError) as exc:
            raise BadInputError(f"'{path}': cannot decode as {encoding!r} ({exc})") from None
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        return raw.decode("latin-1")


def _split(line: str, delim: str) -> list[str]:
    if delim == " ":
        return line.split()
    return [t.strip() for t in line.strip().split(delim)]


def _is_num(tok: str, dec: str) -> bool:
    if not tok:
        return False
    if dec == ".":
        if "," in tok:
            return False
    elif "." in tok:
        return False
    return bool(_NUM_RE.match(tok))


def _score(lines: Sequence[str], delim: str, dec: str) -> tuple[int, float] | None:
    """(modal number of columns, fraction of sample lines that are that many numbers)."""
    if delim == dec:
        return None
    counts: dict[int, int] = {}
    for ln in lines:
        toks = _split(ln, delim)
        if delim != " " and toks and toks[-1] == "":
            toks = toks[:-1]  # trailing delimiter
        if toks and all(_is_num(t, dec) for t in toks):
            counts[len(toks)] = counts.get(len(toks), 0) + 1
    if not counts:
        return None
    n, c = max(counts.items(), key=lambda kv: (kv[1], kv[0]))
    frac = c / len(lines)
    return (n, frac) if frac >= 0.75 else None


def _numeric_line(line: str) -> bool:
    s = line.strip()
    if not s:
        return False
    return bool(re.match(r"^[-+]?(?:\d|[.,]\d)", s)) and not re.search(r"[A-DF-Za-df-z]", s)


def sniff(
    text: str, fmt: TextFormat = TextFormat(), *, path: str = "<text>"
) -> tuple[TextFormat, dict]:
    """Guess the format of a text export. Returns (completed format, notes on what was guessed)."""
    lines = text.splitlines()
    guessed: dict[str, str] = {}
    # header: the numeric table is the last run of numeric lines; header = everything before
    if fmt.header_lines is None:
        start = None
        # first numeric line of which at least half the next 10 non-blank lines are numeric
        for i, ln in enumerate(lines):
            if not _numeric_line(ln):
                continue
            nxt = []
            for j in range(i + 1, min(len(lines), i + 40)):
                if lines[j].strip():
                    nxt.append(j)
                if len(nxt) == 10:
                    break
            if not nxt or sum(_numeric_line(lines[j]) for j in nxt) >= 0.5 * len(nxt):
                start = i
                break
        if start is None:
            raise BadInputError(
                f"'{path}': no table of numbers found (expected lines like '0.02\\t1.234'); "
                "is this a roundness export? Pass header_lines=... if the table starts later"
            )
        header_lines = start
        guessed["header_lines"] = str(start)
    else:
        header_lines = fmt.header_lines
    data_sample = [ln for ln in lines[header_lines : header_lines + 400] if ln.strip()][:50]
    if not data_sample:
        raise BadInputError(
            f"'{path}': no data lines after the {header_lines} header line(s) (line "
            f"{header_lines + 1}); the file looks truncated - re-export it"
        )
    delim, dec = fmt.delimiter, fmt.decimal
    if delim is None or dec is None:
        best = None
        for d in [delim] if delim else ["\t", ";", ",", " "]:
            for c in [dec] if dec else [".", ","]:
                sc = _score(data_sample, d, c)
                if sc is None:
                    continue
                # lines that all parse first, then more columns, then an explicit delimiter
                key = (sc[1] >= 0.95, sc[0], sc[1], d != " ")
                # a comma that only ever separates integers with leading zeros is a decimal comma
                if d == "," and c == ".":
                    toks = [_split(ln, ",") for ln in data_sample]
                    ints = all(all(re.fullmatch(r"[-+]?\d+", t) for t in row) for row in toks)
                    lead0 = any(
                        len(row) > 1 and any(t.startswith("0") and len(t) > 1 for t in row[1:])
                        for row in toks
                    )
                    # two integer fields whose second always has the same width (>= 2 digits):
                    # fixed decimals with a decimal comma, not two integer columns
                    fixed = all(len(row) == 2 for row in toks) and (
                        len({len(row[1]) for row in toks}) == 1 and len(toks[0][1]) >= 2
                    )
                    if ints and (lead0 or (fixed and len(toks) >= 3)):
                        continue
                if best is None or key > best[0]:
                    best = (key, d, c)
        if best is None:
            bad = data_sample[0]
            line_no = lines.index(bad) + 1 if bad in lines else header_lines + 1
            raise BadInputError(
                f"'{path}' line {line_no}: cannot split {bad.strip()[:60]!r} into numbers with "
                "any delimiter (tab, ';', ',', whitespace) and decimal separator ('.', ','); "
                "pass delimiter=... and decimal=..., or fix the line"
            )
        _, d, c = best
        if delim is None:
            guessed["delimiter"] = _DELIMS[d]
            delim = d
        if dec is None:
            guessed["decimal"] = c
            dec = c
    return replace(fmt, delimiter=delim, decimal=dec, header_lines=header_lines), guessed


def _parse_header(lines: Sequence[str], delim: str, ncols: int) -> tuple[dict[str, str], list[str]]:
    """Keyword/value metadata, and the column names (the last header line, if it has one field
    per column)."""
    meta: dict[str, str] = {}
    names: list[str] = []
    cleaned = [ln.strip().lstrip("#;%/!*").strip() for ln in lines]
    nonblank = [i for i, s in enumerate(cleaned) if s]
    last = nonblank[-1] if nonblank else -1
    for i in nonblank:
        s = cleaned[i]
        toks = _split(s, delim)
        if delim != " " and toks and toks[-1] == "":
            toks = toks[:-1]
        if i == last:
            kv = _KV_RE.match(s)
            kv_like = bool(kv and kv.group(2) and re.search(r"[:=]", s))
            wide_split = [t for t in re.split(r"\s{2,}|\t", s) if t]
            if delim == " " and ncols > 1 and len(wide_split) == ncols:
                cand, ok = wide_split, True  # names separated by 2+ spaces may contain spaces
            elif delim == " ":
                cand, ok = toks, not kv_like
            else:
                cand, ok = toks, ncols > 1 or not kv
            if ok and len(cand) == ncols and not all(_NUM_RE.match(t) for t in cand):
                names = cand
                continue
        m = _KV_RE.match(s)
        if m and m.group(2):
            meta[m.group(1).strip()] = m.group(2).strip()
        elif delim != " " and len(toks) >= 2 and toks[0]:
            meta[toks[0]] = delim.join(toks[1:]).strip()
    return meta, names


_NAME_RULES: list[tuple[str, str]] = [
    (r"^(x|x[ _-]?coord.*|cart.*x)$", "x"),
    (r"^(y|y[ _-]?coord.*|cart.*y)$", "y"),
    (r"(rad|radian)s?$|^(theta|angle|phi|φ|θ|winkel)[ _]*\(?rad", "angle_rad"),
    (r"^(theta|angle|phi|φ|θ|winkel|ang|deg|degrees?)\b", "angle_deg"),
    (r"^(index|point|pt|no\.?|n|#|sample|idx|nr\.?)$", "index"),
    (r"^(z|height|level|layer|position|pos|zpos|h)\b", "z"),
    (r"^(radius|r|rad\.?)$|radius", "radius"),
    (r"dev|displac|profile|value|ampl|form|error|runout|signal|data|reading|μ|µ", "deviation"),
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
    if re.match(r"^(z|h|height|layer|level|plane)\s*[=:_]?\s*[-+]?\d", low):
        return None, None  # a per-layer value column of a wide file, named by its z
    if low_base.startswith("layer") and unit is None:
        return "z", None
    for pat, kind in _NAME_RULES:
        if re.search(pat, low_base):
            return kind, unit
    return None, unit


def _guess_angle_kind(col: np.ndarray) -> str:
    c = col[np.isfinite(col)]
    if c.size < 2:
        return "angle_deg"
    span = float(np.max(c) - np.min(c))
    if (
        np.all(np.abs(c - np.round(c)) < 1e-9)
        and np.min(c) >= 0
        and span == c.size - 1
        and c.size != 360
    ):
        return "index"
    if np.max(np.abs(c)) <= 2 * np.pi + 1e-6 and c.size > 8:
        return "angle_rad"
    return "angle_deg"


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


def _value_kind(v: np.ndarray) -> str:
    f = v[np.isfinite(v)]
    if f.size == 0:
        return "deviation"
    mean = float(np.mean(f))
    ptp = float(np.ptp(f))
    return "radius" if mean > 0 and mean > 20 * max(ptp, 1e-300) else "deviation"


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
        return (kinds[0] or _value_kind(data[:, 0]),), units
    if ncol == 2:
        a, b = data[:, 0], data[:, 1]
        if kinds[0] is None and _runs(a):
            kinds[0] = "z"  # (z, value): a long file without an angle column
        if kinds[0] is None:
            if _looks_monotonic(a):
                kinds[0] = _guess_angle_kind(a)
            elif _xy_like(a, b):
                kinds[0], kinds[1] = "x", "y"
            else:  # two value columns: a wide file of two layers without an angle column
                kinds[0] = _value_kind(data)
        if kinds[1] is None:
            kinds[1] = "y" if kinds[0] == "x" else _value_kind(b)
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
                kinds = ["z", _guess_angle_kind(first[:, 1]), _value_kind(data[:, 2])]
        elif np.unique(c2[np.isfinite(c2)]).size <= max(2, data.shape[0] // 8):
            kinds = ["x", "y", "z"]
        elif (
            _looks_monotonic(c0)
            and np.all(np.abs(c0 - np.round(c0)) < 1e-9)
            and _looks_monotonic(data[:, 1])
        ):
            kinds = ["index", _guess_angle_kind(data[:, 1]), _value_kind(data[:, 2])]
        elif _looks_monotonic(c0):
            kinds = [_guess_angle_kind(c0), _value_kind(data[:, 1]), _value_kind(data[:, 2])]
        else:  # three value columns: a wide file without an angle column
            vk3 = _value_kind(data)
            kinds = [vk3, vk3, vk3]
        return tuple(kinds), units  # type: ignore[arg-type]
    # wide: angle + one value column per layer
    if kinds[0] is None and _looks_monotonic(c0):
        kinds[0] = _guess_angle_kind(c0)
    start = 0 if kinds[0] is None else 1  # no angle column: every column is a layer
    vk = next((k for k in kinds[start:] if k in ("radius", "deviation")), None) or _value_kind(
        data[:, start:]
    )
    for i in range(ncol):
        if kinds[i] is None:
            kinds[i] = vk
    return tuple(kinds), units  # type: ignore[arg-type]


_UNIT_KEYS = re.compile(r"^(units?|length[ _]?units?|einheit|unit of measure|scale units?)$", re.I)


def _units_from_meta(meta: dict[str, str]) -> str | None:
    for k, v in meta.items():
        if _UNIT_KEYS.match(k.strip()):
            return v.strip()
    return None


def _bad_line(
    path: str, lines: Sequence[str], line_numbers: np.ndarray, fmt: TextFormat, ncol: int
):
    """Find the first line whose fields are not ncol numbers, and raise a clear error."""
    for ln_no in line_numbers:
        s = lines[ln_no - 1]
        toks = _split(s, fmt.delimiter or " ")
        if fmt.delimiter != " " and toks and toks[-1] == "":
            toks = toks[:-1]
        if len(toks) != ncol:
            more = " (the file looks truncated - re-export it)" if ln_no == line_numbers[-1] else ""
            raise BadInputError(
                f"'{path}' line {ln_no}: expected {ncol} fields, found {len(toks)} in "
                f"{s.strip()[:60]!r}{more}; fix or delete the line"
            )
        for t in toks:
            if not _is_num(t, fmt.decimal or "."):
                if t.lower() in ("nan", "-nan", "inf", "-inf", "+inf", "na", "n/a"):
                    raise BadInputError(
                        f"'{path}' line {ln_no}: {t!r} is not a measured value; remove the line "
                        "or re-export without missing points"
                    )
                raise BadInputError(
                    f"'{path}' line {ln_no}: {t!r} is not a number (expected decimal "
                    f"separator {fmt.decimal!r}, delimiter {_DELIMS.get(fmt.delimiter or ' ')}); "
                    "fix the line or pass delimiter=/decimal="
                )
    raise BadInputError(f"'{path}': the table could not be parsed; pass delimiter= and decimal=")


def parse_file(path: str | Path, fmt: TextFormat = TextFormat()) -> ParsedFile:
    """Sniff and parse one text export into a numeric table (no interpretation of layers yet).

    Raises
    ------
    BadInputError
        Empty or binary file, no numeric table, a line that is not numbers (named with its line
        number), inconsistent field counts, NaN values, unknown units.
    """
    path = Path(path)
    text = _read_text(path, fmt.encoding)
    fmt, guessed = sniff(text, fmt, path=str(path))
    lines = text.splitlines()
    hl = fmt.header_lines or 0
    tail = lines[hl:]
    if any(not ln.strip() for ln in tail):
        body_idx = [i for i in range(hl, len(lines)) if lines[i].strip()]
    else:
        body_idx = range(hl, len(lines))
    line_numbers = np.asarray(body_idx, dtype=np.int64) + 1
    first = _split(lines[body_idx[0]], fmt.delimiter or " ")
    if fmt.delimiter != " " and first and first[-1] == "":
        first = first[:-1]
    ncol = len(first)
    body = "\n".join(tail) if isinstance(body_idx, range) else "\n".join(lines[i] for i in body_idx)
    sep = r"\s+" if fmt.delimiter == " " else fmt.delimiter
    try:
        df = pd.read_csv(
            io.StringIO(body),
            sep=sep,
            decimal=fmt.decimal or ".",
            header=None,
            engine="c",
            dtype=float,
            skip_blank_lines=False,
            na_filter=True,
            keep_default_na=True,
            usecols=range(ncol),
            skipinitialspace=True,
        )
        data = df.to_numpy(dtype=float)
    except (ValueError, pd.errors.ParserError):
        _bad_line(str(path), lines, line_numbers, fmt, ncol)
        raise  # pragma: no cover - _bad_line always raises
    if data.shape[0] != len(body_idx) or not np.all(np.isfinite(data)):
        bad = (
            np.flatnonzero(~np.all(np.isfinite(data), axis=1))
            if data.shape[0] == len(body_idx)
            else []
        )
        if len(bad):
            _bad_line(str(path), lines, line_numbers[bad[0] :], fmt, ncol)
        _bad_line(str(path), lines, line_numbers, fmt, ncol)
    # a short last line is read as NaN-padded by pandas; caught above. Extra fields:
    last = _split(lines[body_idx[-1]], fmt.delimiter or " ")
    if fmt.delimiter != " " and last and last[-1] == "":
        last = last[:-1]
    if len(last) != ncol:
        _bad_line(str(path), lines, line_numbers[-1:], fmt, ncol)
    meta, names = _parse_header(lines[:hl], fmt.delimiter or " ", ncol)
    if fmt.columns is not None:
        cols = fmt.columns
        if len(cols) != ncol:
            raise BadInputError(
                f"'{path}': columns={list(cols)} names {len(cols)} columns but the table has "
                f"{ncol}; give one meaning per column"
            )
        name_units: dict[str, str] = {}
        for i, nm in enumerate(names if len(names) == ncol else []):
            _, u = _kind_from_name(nm)
            if u:
                name_units[str(i)] = u
    else:
        cols, name_units = _guess_columns(data, names)
        guessed["columns"] = ",".join(cols)
    units = fmt.units
    if units is None:
        units = _units_from_meta(meta)
        if units is None:
            for i, c in enumerate(cols):
                if c in ("radius", "deviation", "x", "y", "z") and str(i) in name_units:
                    units = name_units[str(i)]
                    break
        if units is not None:
            guessed["units"] = f"{units} (from the header)"
            ln_no = next((i + 1 for i, ln in enumerate(lines[:hl]) if units in ln), max(hl, 1))
            unit_factor(units, where=f"'{path}' line {ln_no}")
    return ParsedFile(
        path=str(path),
        data=data,
        line_numbers=line_numbers,
        columns=tuple(cols),
        column_names=tuple(names),
        units=units,
        metadata=meta,
        fmt=fmt,
        guessed=guessed,
        n_lines=len(lines),
        column_units=name_units,
    )


# ------------------------------------------------------------------------------------------
# from tables to layers
# ------------------------------------------------------------------------------------------


@dataclass
class _Layer:
    theta_deg: np.ndarray  # instrument convention, ascending in instrument angle
    value: np.ndarray  # [m]
    kind: str  # "radius" or "deviation"
    z: float | None
    source: str


def _angles(
    pf: ParsedFile, col: int, kind: str, n: int, rows: np.ndarray, where: str
) -> np.ndarray:
    a = pf.data[rows, col]
    if kind == "angle_rad":
        return np.degrees(a)
    if kind == "index":
        return a * 360.0 / n
    return a


def _check_angles(theta: np.ndarray, pf: ParsedFile, rows: np.ndarray, where: str) -> np.ndarray:
    """Angles of one layer must increase (or decrease) strictly; one wrap through 360 allowed."""
    th = np.asarray(theta, dtype=float)
    if th.size < 3:
        return th
    d = np.diff(th)
    sgn = 1.0 if np.sum(d > 0) >= np.sum(d < 0) else -1.0
    d = d * sgn
    # allow one wrap of about -360
    wraps = np.flatnonzero(d < -180.0)
    if wraps.size == 1:
        th = th.copy()
        th[wraps[0] + 1 :] += sgn * 360.0
        d = np.diff(th) * sgn
    dup = np.flatnonzero(d == 0)
    if dup.size:
        i = dup[0] + 1
        raise BadInputError(
            f"{where} line {pf.line_numbers[rows[i]]}: angle {theta[i]:g} repeats the previous "
            "point (duplicate angle); delete the duplicate or re-export"
        )
    back = np.flatnonzero(d < 0)
    if back.size:
        i = back[0] + 1
        raise BadInputError(
            f"{where} line {pf.line_numbers[rows[i]]}: angle {theta[i]:g} goes back after "
            f"{theta[i - 1]:g} (angles must increase monotonically within a layer); sort the "
            "points or check the column meaning (columns=...)"
        )
    if abs(th[-1] - th[0]) >= 360.0:
        i = int(np.argmax(np.abs(th - th[0]) >= 360.0))
        raise BadInputError(
            f"{where} line {pf.line_numbers[rows[i]]}: the angles span more than one revolution "
            f"({th[0]:g} to {th[-1]:g} degree); check the angle unit (columns=... angle_deg / "
            "angle_rad / index)"
        )
    return th


def _layers_from_file(pf: ParsedFile, expected_points: int | None, layer_kind: str) -> list[_Layer]:
    """Cut a parsed table into layers according to its column meanings."""
    cols = pf.columns
    where = f"'{pf.path}'"
    if pf.units is None and any(c in ("radius", "deviation", "x", "y") for c in cols):
        raise BadInputError(
            f"{where}: the length unit is not stated in the header; pass units='um' (or 'mm', "
            "'m', 'inch') - jointwear does not guess units"
        )
    f = unit_factor(pf.units, where=where) if pf.units else 1.0
    zf = f
    zc_idx = [i for i, c in enumerate(cols) if c == "z"]
    if zc_idx and str(zc_idx[0]) in pf.column_units:
        zf = unit_factor(pf.column_units[str(zc_idx[0])], where=f"{where} column {zc_idx[0] + 1}")
    elif zc_idx and pf.units is None:
        raise BadInputError(
            f"{where}: the unit of the z column is not stated; pass units=... (the z column is "
            "read in the same unit as the values unless its name says otherwise, e.g. 'z [mm]')"
        )
    n = pf.data.shape[0]
    value_cols = [i for i, c in enumerate(cols) if c in ("radius", "deviation")]
    angle_cols = [i for i, c in enumerate(cols) if c in ("angle_deg", "angle_rad", "index")]
    has_xy = "x" in cols and "y" in cols
    zcols = [i for i, c in enumerate(cols) if c == "z"]
    out: list[_Layer] = []

    def make(rows: np.ndarray, vcol: int | None, zval: float | None) -> _Layer:
        m = rows.size
        if has_xy:
            x = pf.data[rows, cols.index("x")] * f
            y = pf.data[rows, cols.index("y")] * f
            th = np.degrees(np.arctan2(y, x)) % 360.0
            val = np.hypot(x, y)
            order = np.argsort(th, kind="stable")
            th, val, rws = th[order], val[order], rows[order]
            if np.any(np.diff(th) == 0):
                i = int(np.flatnonzero(np.diff(th) == 0)[0]) + 1
                raise BadInputError(
                    f"{where} line {pf.line_numbers[rws[i]]}: two points at the same angle "
                    f"({th[i]:g} degree about the origin); delete the duplicate"
                )
            return _Layer(th, val, "radius", zval, pf.path)
        assert vcol is not None
        val = pf.data[rows, vcol] * f
        if angle_cols:
            ac = angle_cols[0]
            th = _angles(pf, ac, cols[ac], m, rows, where)
            th = _check_angles(th, pf, rows, where)
        else:
            th = np.arange(m) * 360.0 / m
        return _Layer(th, val, cols[vcol] if layer_kind == "auto" else layer_kind, zval, pf.path)

    if not value_cols and not has_xy:
        raise BadInputError(
            f"{where}: no radius/deviation column among {list(cols)}; pass columns=(...) naming "
            "the value column 'radius' or 'deviation'"
        )
    if zcols and (value_cols or has_xy):
        zc = pf.data[:, zcols[0]]
        # layers = runs of constant z
        change = np.flatnonzero(np.diff(zc) != 0) + 1
        starts = np.concatenate([[0], change])
        ends = np.concatenate([change, [n]])
        zs = zc[starts]
        if np.unique(zs).size != zs.size:
            dup = next(i for i in range(len(zs)) if zs[i] in zs[:i])
            raise BadInputError(
                f"{where} line {pf.line_numbers[starts[dup]]}: layer z = {zs[dup]:g} appears "
                "twice (the rows of one layer must be contiguous); sort the file by z"
            )
        for s, e, zv in zip(starts, ends, zs, strict=True):
            out.append(make(np.arange(s, e), value_cols[0] if value_cols else None, float(zv) * zf))
    elif len(value_cols) > 1:
        for vc in value_cols:
            out.append(make(np.arange(n), vc, None))
    else:
        out.append(make(np.arange(n), value_cols[0] if value_cols else None, None))
    for k, lay in enumerate(out):
        if lay.value.size < 4:
            raise BadInputError(
                f"{where}: layer {k + 1} has only {lay.value.size} point(s); a roundness trace "
                "needs at least 4 (the file looks truncated - re-export it)"
            )
    if expected_points is not None:
        for k, lay in enumerate(out):
            if lay.value.size != expected_points:
                raise BadInputError(
                    f"{where}: expected {expected_points} points in layer {k + 1}, found "
                    f"{lay.value.size} - the file looks truncated or the layer is incomplete; "
                    "re-export it or pass expected_points=None / allow_partial=True"
                )
    return out


def _number_from_name(name: str) -> float | None:
    """z from a file name: 'z=2.5mm', 'z-1.0', 'h2,5mm', 'layer03' -> value in metres or index."""
    m = re.search(
        r"(?:^|[_\-\s.])(?:z|h|height|pos)[=_]?([-+]?\d+(?:[.,p]\d+)?)\s*(mm|um|µm|m|in)?",
        name,
        re.I,
    )
    if m:
        v = float(m.group(1).replace(",", ".").replace("p", "."))
        unit = m.group(2)
        return v * unit_factor(unit) if unit else v * 1e-3  # bare z numbers in file names: mm
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


def _z_from_meta(meta: dict[str, str], units: str | None, where: str) -> float | None:
    for k, v in meta.items():
        if _Z_KEYS.match(k.strip()):
            m = re.match(rf"^\s*({_NUM})\s*([A-Za-zµμ\"]+)?", v)
            if not m:
                continue
            val = float(m.group(1).replace(",", "."))
            unit = m.group(2) or (units if units else None)
            if unit is None:
                raise BadInputError(
                    f"{where}: header gives {k} = {v!r} without a unit; pass units=... or "
                    "layer_spacing=..."
                )
            return val * unit_factor(unit, where=where)
    return None


def _read_manifest(folder: Path) -> dict[str, float] | None:
    for name in ("manifest.csv", "manifest.txt", "manifest.json", "layers.csv", "layers.txt"):
        p = folder / name
        if not p.exists():
            continue
        if p.suffix == ".json":
            try:
                raw = json.loads(p.read_text())
                unit = raw.get("units", "m")
                return {str(k): float(v) * unit_factor(unit) for k, v in raw["layers"].items()}
            except (ValueError, KeyError, TypeError, AttributeError) as exc:
                raise BadInputError(
                    f"'{p}': expected JSON {{'units': 'mm', 'layers': {{file: z}}}} ({exc})"
                ) from None
        out: dict[str, float] = {}
        unit = "m"
        for i, ln in enumerate(p.read_text().splitlines(), start=1):
            s = ln.strip()
            if not s:
                continue
            if s.startswith("#"):
                m = re.search(r"units?\s*[:=]\s*(\S+)", s, re.I)
                if m:
                    unit = m.group(1)
                continue
            toks = [t.strip() for t in re.split(r"[,;\t]|\s+", s) if t.strip()]
            if len(toks) < 2:
                raise BadInputError(f"'{p}' line {i}: expected 'file, z', found {s!r}")
            try:
                out[toks[0]] = float(toks[1].replace(",", ".")) * unit_factor(unit, where=str(p))
            except ValueError:
                if i == 1 or not out:
                    m = re.search(r"[\[(]\s*([^\])]+)\s*[\])]", s) or re.search(
                        r"z[_ ]?(mm|um|µm|m|in|inch)\b", s, re.I
                    )
                    if m:
                        unit = m.group(1)
                    continue  # header line
                raise BadInputError(f"'{p}' line {i}: z {toks[1]!r} is not a number") from None
        return out
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
        Meaning of the value column(s) (overrides the guess).
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
    layer_kind = value if value != "auto" else "auto"
    parsed = [parse_file(f, base) for f in files]
    layers: list[_Layer] = []
    metadata: dict = {}
    notes: dict = {}
    for pf in parsed:
        if pf.guessed:
            notes[Path(pf.path).name] = pf.guessed
        ls = _layers_from_file(pf, None if allow_partial else expected_points, layer_kind)
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
        manifest = _read_manifest(folder) if folder is not None else None
        if manifest:
            for lay in layers:
                name = Path(lay.source).name
                key = name if name in manifest else Path(name).stem
                if key not in manifest:
                    raise BadInputError(
                        f"manifest in '{folder}' has no entry for '{name}'; add a line "
                        f"'{name}, <z>'"
                    )
                lay.z = manifest[key]
            zsrc = "manifest"
        else:
            zh = [_z_from_meta(pf.metadata, pf.units, f"'{pf.path}'") for pf in parsed]
            if all(v is not None for v in zh):
                for lay, v in zip(layers, zh, strict=True):
                    lay.z = v
                zsrc = "header keyword"
            else:
                zn = [_number_from_name(Path(lay.source).name) for lay in layers]
                if all(v is not None for v in zn) and len(set(zn)) == len(zn):
                    for lay, v in zip(layers, zn, strict=True):
                        lay.z = v
                    zsrc = "file names (mm unless a unit is given)"
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
        vidx = [i for i, c in enumerate(parsed[0].columns) if c in ("radius", "deviation")]
        zn = None
        if names and len(names) == len(parsed[0].columns):
            zn = []
            for i in vidx:
                m = re.search(rf"({_NUM})\s*(mm|um|µm|m|in)?", names[i])
                if not m:
                    zn = None
                    break
                u = m.group(2) or parsed[0].units
                zn.append(float(m.group(1).replace(",", ".")) * (unit_factor(u) if u else 1e-3))
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
