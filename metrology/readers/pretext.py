"""Text as labs write it, made plain before sniffing: end-of-file marks, quoted CSV, thousands
marks, concatenated per-layer blocks; formats that are not supported are named.

* a trailing Ctrl-Z (DOS end-of-file mark, often after CRLF line ends) is dropped;
* JSON and angles in degrees-minutes-seconds are refused as unsupported formats (no delimiter
  advice can make them readable);
* quoted CSV (``"0.5","8.0012"``, also with a decimal comma inside the quotes) is unquoted
  with :mod:`csv` and re-joined with tabs;
* the field delimiter is decided first, from the data lines (:func:`sniff_delimiter`); a
  thousands mark (``8,001.234``, ``8.001,234``, ``8'001.234``, ``8 001,234``) is then looked
  for *within* the fields (:func:`sniff_thousands`): accepted only when it is not the delimiter,
  one number shows it next to the decimal mark, and every value of each column holding it is
  grouped by it; or given (``thousands=``, :func:`thousands_mark` reads its names);
* a file of several blocks, each a layer with its own header lines (``Layer 2``, ``Height:
  1 mm``, the column names again), is split into blocks (:func:`split_blocks`).

:func:`sniff_delimiter`, :func:`sniff_thousands`, :func:`fields` and :data:`MISSING` are the
sniffer's parts that other importers reuse (lines in, decisions out; nothing read from disk);
the last three, with the delimiter/decimal sniffer, live in :mod:`jointwear.dialect`, which the
root library may use, and are re-exported here.
"""

from __future__ import annotations

import csv
import io
import re
from collections.abc import Sequence

from jointwear.dialect import (
    DELIMITERS,
    MISSING,
    fields,
    is_missing,
    sniff_thousands,
)
from jointwear.dialect import grouped_number as _grouped
from jointwear.metrology.readers.advice import Refusal

__all__ = [
    "DELIMITERS",
    "MISSING",
    "THOUSANDS_NAMES",
    "fields",
    "is_missing",
    "missing_row",
    "normalise",
    "numeric_line",
    "sniff_delimiter",
    "sniff_thousands",
    "split_blocks",
    "thousands_hint",
    "thousands_mark",
]

_DMS = re.compile(r"\d+\s*°\s*\d+\s*['′]|\d+d\s*\d+m\s*\d+(\.\d+)?s", re.I)

#: Spellings of a thousands mark (``thousands=`` / ``--thousands``) -> the character.
THOUSANDS_NAMES: dict[str, str] = {
    ",": ",",
    "comma": ",",
    ".": ".",
    "point": ".",
    "dot": ".",
    "period": ".",
    "'": "'",
    "apostrophe": "'",
    "quote": "'",
    " ": " ",
    "space": " ",
}
#: The name a suggestion uses for each mark (one the shell passes as it is).
THOUSANDS_WORD = {",": "comma", ".": "point", "'": "apostrophe", " ": "space"}
_LOOSE = re.compile(
    r"^[-+]?(?:\d{1,3}(?:[,.'\u00a0\u202f ]\d{3})+|\d+)?(?:[.,]\d*)?(?:[eE][-+]?\d+)?$"
)


def thousands_mark(name: str | None) -> str | None:
    """The character of a thousands mark given by name (``comma``, ``point``, ``apostrophe``,
    ``space``) or as itself; None stays None; anything else is refused."""
    if name is None:
        return None
    key = name if name == " " else str(name).strip().lower()
    if key not in THOUSANDS_NAMES:
        raise Refusal(
            f"thousands={name!r} (--thousands) is not a thousands mark; use comma, point, "
            "apostrophe or space"
        )
    return THOUSANDS_NAMES[key]


def _numberish(tok: str) -> bool:
    """A number under some decimal/thousands reading, or a missing-value mark."""
    return is_missing(tok) or (any(c.isdigit() for c in tok) and bool(_LOOSE.match(tok)))


def sniff_delimiter(lines: Sequence[str]) -> str | None:
    """The field delimiter of lines of numbers, decided before any decimal or thousands mark.

    Parameters
    ----------
    lines : sequence of str
        Data lines (a table's rows; header lines left out).

    Returns
    -------
    str or None
        The first of tab, ``;``, ``,``, ``" "`` (whitespace) that splits at least 90 % of the
        lines into the same number (>= 2) of fields that are each a number under some reading
        (decimal point or comma, grouped thousands) or a missing-value mark, with at least one
        number per line; None when none does (one column, or not a table).
    """
    rows = [ln for ln in lines if ln.strip()]
    if not rows:
        return None
    for d in DELIMITERS:
        counts: dict[int, int] = {}
        for ln in rows:
            toks = fields(ln, d)
            if len(toks) >= 2 and all(map(_numberish, toks)) and not all(map(is_missing, toks)):
                counts[len(toks)] = counts.get(len(toks), 0) + 1
        if counts and max(counts.values()) >= 0.9 * len(rows):
            return d
    return None


def thousands_hint(cells: Sequence[str], delimiter: str | None) -> str | None:
    """The word (``comma``, ``point``, ``apostrophe``, ``space``) of a thousands mark that some
    cell is grouped by (``8,001``, ``8 001,5``) and that is not the delimiter, else None: the
    ``thousands=`` a refusal of those cells can offer."""
    for sep in (" ", "'", ",", "."):
        if sep == delimiter or (sep == " " and delimiter in (None, " ")):
            continue
        pat = re.compile(rf"^[-+]?\d{{1,3}}(?:{re.escape(sep)}\d{{3}})+(?:[.,]\d+)?$")
        if any(pat.match(c.strip()) for c in cells):
            return THOUSANDS_WORD[sep]
    return None


def _remove_thousands(
    text: str, path: str, given: str | None, delimiter: str | None
) -> tuple[str, str | None]:
    """``text`` with the thousands mark removed inside the fields of its data lines, and a note
    (None when there is none). A given mark that is the delimiter is refused."""
    sep = thousands_mark(given)
    sample = []
    for ln in text[:65536].splitlines()[:-1]:  # the first 400 data lines (whole ones) decide
        if _is_data(ln):
            sample.append(ln)
            if len(sample) == 400:
                break
    delim = delimiter or sniff_delimiter(sample)
    if sep is None:
        sep = sniff_thousands(sample, delim)
        if sep is None:
            return text, None
        how = "one number shows it next to the decimal mark, every value of its column grouped"
    else:
        how = "given"
        if sep == delim:
            raise Refusal(
                f"'{path}': thousands={THOUSANDS_WORD[sep]!r} (--thousands) is the field "
                "delimiter of the table; a thousands mark cannot also separate the fields - drop "
                "the option, or pass delimiter=... if the fields are separated otherwise"
            )
    pat = _grouped(sep, None)
    lines = text.splitlines()
    for i in [i for i, ln in enumerate(lines) if _is_data(ln)]:
        toks = [
            t.replace(sep, "") if sep in t and pat.match(t) else t for t in fields(lines[i], delim)
        ]
        lines[i] = (delim or " ").join(toks)
    end = "\n" if text.endswith(("\n", "\r")) else ""
    note = f"thousands mark {THOUSANDS_WORD[sep]!r} removed within the fields ({how})"
    return "\n".join(lines) + end, note


def normalise(
    text: str, path: str, thousands: str | None, delimiter: str | None = None
) -> tuple[str, dict[str, str]]:
    """(plain text, notes on what was changed) or a refusal for an unsupported format.

    ``thousands`` is the thousands mark given (None: sniffed, :func:`sniff_thousands`),
    ``delimiter`` the field delimiter given (None: sniffed, :func:`sniff_delimiter`).
    """
    notes: dict[str, str] = {}
    stripped = text.rstrip("\r\n\t ")
    if stripped.endswith("\x1a"):
        text = stripped.rstrip("\x1a").rstrip() + "\n"
        notes["eof_mark"] = "trailing Ctrl-Z (DOS end-of-file mark) removed"
    head = text.lstrip()[:1]
    if head in ("{", "["):
        raise Refusal(
            f"'{path}' is JSON, which the readers do not support (no reader option makes it "
            "readable); export the trace as text/CSV (one angle and one value per "
            "line) or convert it to CSV first"
        )
    body = [ln for ln in text[:65536].splitlines()[:400] if ln.strip()]
    if sum(bool(_DMS.search(ln)) for ln in body) > max(3, len(body) // 4):
        raise Refusal(
            f"'{path}': the angles are written in degrees-minutes-seconds (e.g. 12°30'15\"), "
            "which the readers do not support; export decimal degrees, radians or the point "
            "index"
        )
    if sum(ln.count('"') >= 2 for ln in body) > len(body) // 2:
        text = _unquote(text)
        notes["quoted"] = "quoted CSV fields unquoted (csv module) and re-joined with tabs"
        delimiter = "\t"
    text, note = _remove_thousands(text, path, thousands, delimiter)
    if note:
        notes["thousands"] = note
    return text, notes


_TOKENS = re.compile(r"[\t;,]|\s+")
_NUMBER_START = re.compile(r"^[-+]?(?:\d|[.,]\d)[^A-DF-Za-df-z]*$")


def numeric_line(line: str) -> bool:
    """A line of the table: every field (split at tab, ``;``, ``,`` or whitespace) a number
    (starting with a digit; no letter but an exponent's ``e``) or a missing-value mark
    (:data:`MISSING`), at least one of them a number."""
    toks = [t for t in _TOKENS.split(line.strip()) if t]
    numbers = [bool(_NUMBER_START.match(t)) for t in toks]
    return any(numbers) and all(n or is_missing(t) for n, t in zip(numbers, toks, strict=True))


def missing_row(line: str, like: str) -> bool:
    """``line`` is a row of missing values only (``NaN``, ``---``) with as many fields as the
    table row ``like``: a table row, not a header line (a first point missing)."""
    toks = [t for t in _TOKENS.split(line.strip()) if t]
    width = len([t for t in _TOKENS.split(like.strip()) if t])
    return bool(toks) and len(toks) == width and all(map(is_missing, toks))


def _is_data(line: str) -> bool:
    return numeric_line(line)


def _unquote(text: str) -> str:
    lines = text.splitlines()
    sample = "\n".join(ln for ln in lines[:200] if ln.strip())
    delim = ","
    for d in ("\t", ";", ","):
        if f'"{d}"' in sample or f'"{d} "' in sample:
            delim = d
            break
    out = []
    for row in csv.reader(io.StringIO("\n".join(lines)), delimiter=delim, skipinitialspace=True):
        out.append("\t".join(c.strip() for c in row))
    return "\n".join(out) + "\n"


_MARK = re.compile(
    r"^\W*(layer|plane|trace|block|section|profile)\s*(?:no\.?|#|:|=)?\s*(\d+)\b", re.I
)
_BLOCK_KEY = re.compile(r"^\W*(layer|plane|trace|block|section|z|height|level|position)\b", re.I)


def _numeric(line: str) -> bool:
    return numeric_line(line)


_FIRST_NUMBER = re.compile(r"^[ \t]*[-+]?(?:\d|[.,]\d)", re.M)
_WORDY = re.compile(r"[A-DF-Za-df-z]")


def split_blocks(text: str) -> list[tuple[str, list[int]]] | None:
    """Concatenated per-layer blocks: [(block text, file line number of each block line)], or
    None when the file is one table.

    A block starts at header lines naming a layer (``Layer 2``, ``Plane: 3``, ``Height: 1 mm``)
    or repeating the first block's column names, and holds at least 4 rows of numbers. The
    file's own header (before the first block) is repeated in every block; a block's own lines
    override it. A line like ``Layer 2`` becomes ``Layer number: 2``.
    """
    first = _FIRST_NUMBER.search(text)
    if first is None or not _WORDY.search(text, first.start()):
        return None  # no line with words after the table starts: one table (fast path)
    lines = text.splitlines()
    runs: list[tuple[int, int]] = []  # [start, end) of numeric runs (blank lines inside allowed)
    i = 0
    while i < len(lines):
        if _numeric(lines[i]):
            j = i
            last = i
            while j < len(lines) and (_numeric(lines[j]) or not lines[j].strip()):
                if lines[j].strip():
                    last = j
                j += 1
            runs.append((i, last + 1))
            i = j
        else:
            i += 1
    runs = [r for r in runs if r[1] - r[0] >= 4]
    if len(runs) < 2:
        return None
    first_head = [k for k in range(runs[0][0]) if lines[k].strip()]
    names = lines[first_head[-1]].strip() if first_head else None
    if names is not None and (":" in names or "=" in names or _MARK.match(names)):
        names = None
    groups = []
    for (_, e0), (s1, _) in zip(runs[:-1], runs[1:], strict=True):
        g = [k for k in range(e0, s1) if lines[k].strip()]
        ok = bool(g) and any(
            _BLOCK_KEY.match(lines[k]) or (names and lines[k].strip() == names) for k in g
        )
        if not ok:
            return None  # text inside the table that is no block header: refused later
        groups.append(g)
    own = [k for k in first_head if lines[k].strip() != names]
    first_marks = [k for k in own if _BLOCK_KEY.match(lines[k])]
    common = [k for k in own if k not in first_marks]
    blocks = []
    heads = [first_marks] + groups
    for (s, e), g in zip(runs, heads, strict=True):
        idx = common + [k for k in g if lines[k].strip() != names]
        body = []
        for k in idx:
            m = _MARK.match(lines[k])
            body.append(f"Layer number: {m.group(2)}" if m and ":" not in lines[k] else lines[k])
        nums = idx[:]
        if names is not None:
            body.append(names)
            nums.append(first_head[-1])
        rows = [k for k in range(s, e) if lines[k].strip()]
        body += [lines[k] for k in rows]
        nums += rows
        blocks.append(("\n".join(body) + "\n", [k + 1 for k in nums]))
    return blocks
