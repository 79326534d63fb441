"""Text exports to numeric tables: encoding, header, delimiter, decimal separator, units."""

from __future__ import annotations

import io
import re
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
import pandas as pd

from jointwear.dialect import DELIMITER_NAMES as _DELIMS
from jointwear.dialect import NUMBER as _NUM
from jointwear.dialect import delimiter_char, sniff_separators
from jointwear.dialect import is_number as _is_num
from jointwear.dialect import split_fields as _split
from jointwear.errors import BadInputError
from jointwear.metrology.readers.advice import Refusal
from jointwear.metrology.readers.claims import drop_ignored
from jointwear.metrology.readers.columns import COLUMN_KINDS, _guess_columns, _kind_from_name
from jointwear.metrology.readers.pretext import (
    MISSING,
    fields,
    missing_row,
    normalise,
    numeric_line,
    sniff_delimiter,
    split_blocks,
    thousands_hint,
    thousands_mark,
)
from jointwear.metrology.readers.source import _read_text
from jointwear.metrology.readers.units import _LENGTH_KINDS, UNITS, _file_units, unit_factor

__all__ = [
    "UNITS",
    "TextFormat",
    "ParsedFile",
    "unit_factor",
    "sniff",
    "parse_file",
    "parse_blocks",
]


_NUM_RE = re.compile(rf"^\s*{_NUM}\s*$")


_KV_RE = re.compile(r"^\s*([A-Za-zµμ_#][^:=\t]{0,60}?)\s*(?::|=|\t)\s*(.*?)\s*$")


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
    columns : tuple of str or str, optional
        Meaning of each column, from :data:`COLUMN_KINDS` (or one comma-joined string, as the
        command line and the refusals spell it: ``"angle_deg,deviation"``); for a wide file the value columns
        are all ``"radius"`` or ``"deviation"``.
    units : str, optional
        Unit of the length columns: ``"um"``, ``"mm"``, ``"m"``, ``"inch"``; for files that do
        not state it (a file stating another unit is refused).
    encoding : str, optional
        Text encoding (default: from a byte-order mark (UTF-8, UTF-16), else UTF-8, falling
        back to Latin-1).
    z_units : str, optional
        Unit of the z column / z in file names and headers, when the file does not state it.
    sheet : str, optional
        Worksheet of an Excel workbook (needed when it has several with data).
    ignore_header : tuple of str
        Header claims to drop (names of :data:`~.claims.CLAIMS`: ``units``, ``nominal_radius``,
        ``points``, ``filter``, ``layers``, ``layer_spacing``, ``z``) when the header is wrong.
    thousands : {"comma", "point", "apostrophe", "space"}, optional
        Thousands mark (``8,001.234``; also given as the character itself); sniffed only where
        unambiguous (:func:`~.pretext.sniff_thousands`).
    """

    delimiter: str | None = None
    decimal: str | None = None
    header_lines: int | None = None
    columns: tuple[str, ...] | None = None
    units: str | None = None
    encoding: str | None = None
    z_units: str | None = None
    sheet: str | None = None
    ignore_header: tuple[str, ...] = ()
    thousands: str | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "delimiter", delimiter_char(self.delimiter))
        if self.decimal not in (None, ".", ","):
            raise BadInputError(f"decimal {self.decimal!r} must be '.' or ','")
        if self.columns is not None:
            given = self.columns.split(",") if isinstance(self.columns, str) else self.columns
            cols = tuple(str(c).strip().lower() for c in given)
            bad = [c for c in cols if c not in COLUMN_KINDS]
            if bad:
                raise BadInputError(
                    f"column meaning(s) {', '.join(map(repr, bad))} not understood; use "
                    + ", ".join(COLUMN_KINDS)
                )
            object.__setattr__(self, "columns", cols)
        if self.units is not None:
            unit_factor(self.units, where="option units (--units)")
        if self.z_units is not None:
            unit_factor(self.z_units, where="option z_units (--z-units)")
        object.__setattr__(self, "thousands", thousands_mark(self.thousands))
        if self.thousands is not None and self.thousands == self.decimal:
            raise BadInputError("thousands and decimal separators must differ")
        object.__setattr__(self, "ignore_header", tuple(self.ignore_header))
        if self.header_lines is not None and self.header_lines < 0:
            raise BadInputError(f"header_lines must be >= 0, got {self.header_lines}")


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
    angle_unit: str | None = None  # stated in the header ("Angle unit: deg")
    z_units: str | None = None  # stated in the header ("Z unit: mm") or by the user
    arc: str | None = None  # stated in the header ("Arc: full")
    block: int | None = None  # number of the block in a file of concatenated layer blocks


def _numeric_line(line: str) -> bool:
    return numeric_line(line)


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
        while start > 0 and missing_row(lines[start - 1], lines[start]):
            start -= 1  # rows of missing values only at the top belong to the table
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
        best = sniff_separators(data_sample, delim, dec)
        if best is None:
            bad = data_sample[0]
            line_no = lines.index(bad) + 1 if bad in lines else header_lines + 1
            d = fmt.delimiter or sniff_delimiter(data_sample)
            hint = thousands_hint([c for ln in data_sample for c in fields(ln, d)], d)
            fix = (
                f"pass thousands='{hint}' if its numbers are grouped in thousands, else "
                if hint and fmt.thousands is None
                else "pass "
            )
            raise Refusal(
                f"'{path}' line {line_no}: cannot split {bad.strip()[:60]!r} into numbers with "
                "any delimiter (tab, ';', ',', whitespace) and decimal separator ('.', ','); "
                f"{fix}delimiter=... and decimal=..., or fix the line",
                ({"thousands": hint},) if hint and fmt.thousands is None else (),
            )
        d, c = best
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
            if _is_num(t, fmt.decimal or ".") and not np.isfinite(float(t.replace(",", "."))):
                raise BadInputError(
                    f"'{path}' line {ln_no}: {t!r} is beyond the range of numbers (not finite); "
                    "a corrupt value - fix or delete the line"
                )
            if not _is_num(t, fmt.decimal or "."):
                if t.lower() in ("nan", "-nan", "inf", "-inf", "+inf", "na", "n/a"):
                    raise BadInputError(
                        f"'{path}' line {ln_no}: {t!r} is not a measured value; remove the line "
                        "or re-export without missing points"
                    )
                hint = thousands_hint([t], fmt.delimiter) if fmt.thousands is None else None
                raise Refusal(
                    f"'{path}' line {ln_no}: {t!r} is not a number (expected decimal "
                    f"separator {fmt.decimal!r}, delimiter {_DELIMS.get(fmt.delimiter or ' ')}); "
                    + (
                        f"pass thousands='{hint}' if it is grouped in thousands, or "
                        if hint
                        else ""
                    )
                    + "fix the line or pass delimiter=/decimal=",
                    ({"thousands": hint},) if hint else (),
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
    text = _read_text(path, fmt.encoding, fmt.sheet)
    text, pre = normalise(text, str(path), fmt.thousands, fmt.delimiter)
    return _parse_text(path, text, fmt, pre)


def parse_blocks(path: str | Path, fmt: TextFormat = TextFormat()) -> list[ParsedFile]:
    """Like :func:`parse_file`, but a file of concatenated per-layer blocks (each with its own
    header lines) gives one :class:`ParsedFile` per block (line numbers are the file's)."""
    path = Path(path)
    text = _read_text(path, fmt.encoding, fmt.sheet)
    text, pre = normalise(text, str(path), fmt.thousands, fmt.delimiter)
    blocks = split_blocks(text) if fmt.header_lines is None else None
    if not blocks:
        return [_parse_text(path, text, fmt, pre)]
    out = []
    for k, (btext, numbers) in enumerate(blocks, start=1):
        pf = _parse_text(path, btext, fmt, {**pre, "block": f"block {k} of {len(blocks)}"})
        pf.line_numbers = np.asarray(numbers)[pf.line_numbers - 1]
        pf.block = k
        out.append(pf)
    return out


_BLANK_LINE = re.compile(r"\n[ \t\r\f\v]*\n")


def _has_blank_line(text: str, hl: int, tail: Sequence[str]) -> bool:
    """Whether the table (the lines after the ``hl`` header lines) holds a blank line; a regex
    over the text instead of a Python loop over its lines (a 13 x 18000 file: 0.1 s)."""
    pos = 0
    for _ in range(hl):
        pos = text.find("\n", pos) + 1
        if pos == 0:
            return any(not ln.strip() for ln in tail)  # not \n line ends: the plain way
    if "\r" in text[:4096].replace("\r\n", ""):
        return any(not ln.strip() for ln in tail)  # old Mac line ends
    return bool(_BLANK_LINE.search(text, max(pos - 1, 0))) or (bool(tail) and not tail[0].strip())


def _modal_width(lines: Sequence[str], body_idx: Sequence[int], delim: str) -> int:
    """The number of fields of most of the first 200 table lines (a first line whose last cell
    is missing, ``0.5<TAB>``, does not set the width)."""
    counts: dict[int, int] = {}
    for i in list(body_idx[:200]):
        toks = _split(lines[i], delim)
        if delim != " " and toks and toks[-1] == "":
            toks = toks[:-1]
        counts[len(toks)] = counts.get(len(toks), 0) + 1
    return max(counts.items(), key=lambda kv: (kv[1], kv[0]))[0]


#: Cells pandas reads as missing besides its defaults (every case of :data:`MISSING`).
_NA_CELLS = sorted({v for m in MISSING if m for v in (m, m.upper(), m.title())})
_PLACED = ("radius", "deviation", "value", "ignore")


def _short_rows(
    path: str, lines: Sequence[str], line_numbers: np.ndarray, data: np.ndarray, fmt, ncol: int
) -> None:
    """A row with a missing cell must still have every field (an empty cell between
    delimiters); fewer fields is a cut line, which pandas would pad with NaN: refused."""
    for r in np.flatnonzero(np.any(np.isnan(data), axis=1)):
        ln = lines[line_numbers[r] - 1]
        raw = ln.split() if fmt.delimiter == " " else ln.strip("\r\n ").split(fmt.delimiter)
        if len(raw) < ncol:
            more = " (the file looks truncated - re-export it)" if r == data.shape[0] - 1 else ""
            raise BadInputError(
                f"'{path}' line {line_numbers[r]}: expected {ncol} fields, found {len(raw)} in "
                f"{ln.strip()[:60]!r}{more}; a missing value is written as an empty field or a "
                "mark such as '---' or 'NaN' - fix or delete the line"
            )


def _missing(
    path: str, data: np.ndarray, cols: Sequence[str], line_numbers: np.ndarray, guessed: dict
) -> None:
    """Missing cells (:data:`MISSING`) of value columns are points without a value (NaN,
    counted in ``guessed["missing"]``); a missing angle, z or coordinate cannot be placed."""
    nan = np.isnan(data)
    if not nan.any():
        return
    for j, c in enumerate(cols):
        if c not in _PLACED and nan[:, j].any():
            r = int(np.flatnonzero(nan[:, j])[0])
            raise BadInputError(
                f"'{path}' line {line_numbers[r]}: the {c} (column {j + 1}) is missing; a point "
                "without its position cannot be placed - delete the line or re-export it"
            )
    count = int(nan[:, [j for j, c in enumerate(cols) if c in _PLACED[:3]]].sum())
    if count:
        guessed["missing"] = f"{count} missing value(s) (e.g. '---', 'NaN', empty) read as NaN"


def _parse_text(path: Path, text: str, fmt: TextFormat, pre: dict[str, str]) -> ParsedFile:
    fmt, guessed = sniff(text, fmt, path=str(path))
    guessed.update(pre)
    lines = text.splitlines()
    hl = fmt.header_lines or 0
    tail = lines[hl:]
    if _has_blank_line(text, hl, tail):
        body_idx = [i for i in range(hl, len(lines)) if lines[i].strip()]
    else:
        body_idx = range(hl, len(lines))
    line_numbers = np.asarray(body_idx, dtype=np.int64) + 1
    ncol = _modal_width(lines, body_idx, fmt.delimiter or " ")
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
            na_values=_NA_CELLS,
            usecols=range(ncol),
            skipinitialspace=True,
        )
        data = df.to_numpy(dtype=float)
    except (ValueError, pd.errors.ParserError):
        _bad_line(str(path), lines, line_numbers, fmt, ncol)
        raise  # pragma: no cover - _bad_line always raises
    if data.shape[0] != len(body_idx) or np.any(np.isinf(data)):
        bad = (
            np.flatnonzero(np.any(np.isinf(data), axis=1)) if data.shape[0] == len(body_idx) else []
        )
        if len(bad):
            _bad_line(str(path), lines, line_numbers[bad[0] :], fmt, ncol)
        _bad_line(str(path), lines, line_numbers, fmt, ncol)
    _short_rows(str(path), lines, line_numbers, data, fmt, ncol)
    # a short last line is read as NaN-padded by pandas; caught above. Extra fields:
    last = _split(lines[body_idx[-1]], fmt.delimiter or " ")
    if fmt.delimiter != " " and last and last[-1] == "":
        last = last[:-1]
    if len(last) != ncol:
        _bad_line(str(path), lines, line_numbers[-1:], fmt, ncol)
    if "header_lines" in guessed:
        _no_data_in_header(str(path), lines[:hl], fmt, ncol)
    _delimiter_in_numbers(str(path), lines, body_idx, hl, fmt, ncol)
    meta, names = _parse_header(lines[:hl], fmt.delimiter or " ", ncol)
    meta = drop_ignored(meta, fmt.ignore_header)
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
    _missing(str(path), data, cols, line_numbers, guessed)
    if "units" in fmt.ignore_header:
        name_units = {k: u for k, u in name_units.items() if cols[int(k)] not in _LENGTH_KINDS}
        guessed["ignored_header"] = "units (header and column names; ignore_header)"
    units = _file_units(str(path), lines[:hl], meta, cols, name_units, fmt.units, guessed)
    _check_last_line(str(path), text, lines, body_idx, fmt, guessed)
    angle_unit = _keyword(meta, _ANGLE_UNIT_KEYS)
    if angle_unit is not None:
        angle_unit = _ANGLE_UNIT_WORDS.get(angle_unit.lower().strip())
        if angle_unit is None:
            raise BadInputError(
                f"'{path}': header angle unit {_keyword(meta, _ANGLE_UNIT_KEYS)!r} is not known "
                "(deg, rad, index or grad)"
            )
    z_units = _keyword(meta, _Z_UNIT_KEYS)
    if z_units is not None:
        unit_factor(z_units, where=f"'{path}' header z unit")
        if fmt.z_units is not None and unit_factor(fmt.z_units) != unit_factor(z_units):
            raise BadInputError(
                f"'{path}': z_units={fmt.z_units!r} (--z-units) contradicts the header, which "
                f"says the z unit is {z_units!r}; drop the option or correct the header"
            )
    arc = _keyword(meta, _ARC_KEYS)
    if arc is not None:
        arc = arc.strip().lower()
        if arc not in ("full", "partial"):
            raise BadInputError(f"'{path}': header arc {arc!r} is not known (full or partial)")
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
        angle_unit=angle_unit,
        z_units=z_units or fmt.z_units,
        arc=arc,
    )


_ANGLE_UNIT_KEYS = re.compile(r"^(angle|theta)[ _]?units?$", re.I)
_Z_UNIT_KEYS = re.compile(r"^(z|height|level|axial)[ _]?units?$", re.I)
_ARC_KEYS = re.compile(r"^(arc|angular[ _]span|span)$", re.I)
_ANGLE_UNIT_WORDS = {
    "deg": "deg",
    "degree": "deg",
    "degrees": "deg",
    "°": "deg",
    "rad": "rad",
    "radian": "rad",
    "radians": "rad",
    "index": "index",
    "point": "index",
    "points": "index",
    "grad": "grad",
    "gon": "grad",
    "gradian": "grad",
    "gradians": "grad",
}


def _no_data_in_header(path: str, header: Sequence[str], fmt: TextFormat, ncol: int) -> None:
    """A data row with one bad field ('0.0<TAB>n.a.') just above the table would be taken for
    the line of column names and silently dropped: refuse it, naming the line."""
    idx = [i for i, ln in enumerate(header) if ln.strip()]
    if not idx:
        return
    i = idx[-1]
    toks = _split(header[i], fmt.delimiter or " ")
    if fmt.delimiter != " " and toks and toks[-1] == "":
        toks = toks[:-1]
    nums = [t for t in toks if _is_num(t, fmt.decimal or ".")]
    if len(toks) == ncol and nums and len(nums) < len(toks) and not re.search(r"[:=]", header[i]):
        bad = next(t for t in toks if not _is_num(t, fmt.decimal or "."))
        raise BadInputError(
            f"'{path}' line {i + 1}: {header[i].strip()[:60]!r} looks like a row of the table "
            f"with {bad!r} where a number belongs; fix or delete the line (or pass "
            "header_lines=... / --header-lines if it really is a header)"
        )


def _delimiter_in_numbers(path, lines, body_idx, hl: int, fmt, ncol: int) -> None:
    """``Angle,Radius`` over ``0.0,8,001.234``: the comma both separates the fields and groups
    the thousands, so a column of 3-digit groups after a column of 1-3 digit integers appears
    that the names do not have. Refused: no option can tell the two commas apart."""
    if fmt.delimiter != "," or ncol < 3:
        return
    names = [ln for ln in lines[:hl] if ln.strip()]
    if not names or len(_split(names[-1], ",")) >= ncol:
        return
    rows = [_split(lines[i], ",") for i in list(body_idx[:200])]
    groups = [
        j
        for j in range(1, ncol)
        if all(
            j < len(r)
            and re.fullmatch(r"\d{3}(?:\.\d+)?", r[j])
            and re.fullmatch(r"[-+]?\d{1,3}", r[j - 1])
            for r in rows
        )
    ]
    if groups:
        raise BadInputError(
            f"'{path}' line {body_idx[0] + 1}: {lines[body_idx[0]].strip()[:60]!r} has "
            f"{ncol} fields under {len(_split(names[-1], ','))} column names, and column "
            f"{groups[0] + 1} holds only 3-digit groups: the comma both separates the fields "
            "and groups thousands (8,001.234), which no option can tell apart - re-export "
            "without thousands separators, or with ';' or tab between the fields"
        )


def _keyword(meta: dict[str, str], pattern: re.Pattern) -> str | None:
    return next((v.strip() for k, v in meta.items() if pattern.match(k.strip())), None)


def _decimals(tok: str) -> int:
    mant = re.split(r"[eE]", tok)[0]
    for sep in ".,":
        if sep in mant:
            return len(mant.split(sep, 1)[1])
    return 0


def _check_last_line(
    path: str,
    text: str,
    lines: Sequence[str],
    body_idx: Sequence[int],
    fmt: TextFormat,
    guessed: dict[str, str],
) -> None:
    """A file cut mid-number ends without a newline: compare the last line's number format."""
    if text.endswith(("\n", "\r")) or len(body_idx) < 3:
        return
    ln = body_idx[-1]
    last = _split(lines[ln], fmt.delimiter or " ")
    prev = [_split(lines[i], fmt.delimiter or " ") for i in list(body_idx)[-51:-1]]
    checked = False
    for j, tok in enumerate(last):
        decs = {_decimals(p[j]) for p in prev if j < len(p)}
        if len(decs) == 1:
            checked = True
            (d,) = decs
            if _decimals(tok) != d:
                raise BadInputError(
                    f"'{path}' line {ln + 1}: the file ends without a newline and the last "
                    f"number {tok!r} has {_decimals(tok)} decimal(s) where every line before has "
                    f"{d}: the file looks cut off - re-export it, or delete the line"
                )
    guessed["last_line"] = (
        "the file does not end with a newline; the last line has the number format of the "
        "lines before (not cut)"
        if checked
        else "the file does not end with a newline and the number format varies, so a cut "
        "last line could not be ruled out"
    )
