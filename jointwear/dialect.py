"""The dialect of a delimited text table, sniffed from its data lines: field delimiter, decimal
mark, thousands mark (light: ``re`` only, no numpy).

Lines in, decisions out; nothing is read from disk. The metrology readers
(:mod:`jointwear.metrology.readers.table`, :mod:`~jointwear.metrology.readers.pretext`) and the
own-data importers (:mod:`jointwear.external`) share this one sniffer.
"""

from __future__ import annotations

import re
from collections.abc import Sequence

from jointwear.errors import BadInputError

__all__ = [
    "DELIMITERS",
    "DELIMITER_NAMES",
    "MISSING",
    "NUMBER",
    "delimiter_char",
    "fields",
    "grouped_number",
    "is_missing",
    "is_number",
    "sniff_separators",
    "sniff_thousands",
    "split_fields",
]

#: Field delimiters in the order they are tried (``" "``: any run of whitespace).
DELIMITERS = ("\t", ";", ",", " ")
#: Field delimiter -> its name in notes and messages.
DELIMITER_NAMES = {"\t": "tab", ";": "semicolon", ",": "comma", " ": "whitespace"}
#: A number with either decimal mark (no thousands mark), as a regular expression.
NUMBER = r"[-+]?(?:\d+(?:[.,]\d*)?|[.,]\d+)(?:[eE][-+]?\d+)?"
_NUMBER_RE = re.compile(rf"^\s*{NUMBER}\s*$")
#: Cells that mean "no value here" (a missing point), compared lower-cased.
MISSING = frozenset(
    (
        "",
        "-",
        "--",
        "---",
        "----",
        "*",
        "**",
        "***",
        "nan",
        "-nan",
        "+nan",
        "na",
        "n/a",
        "#n/a",
        "null",
        "none",
        "?",
        "invalid",
        "void",
        "missing",
        "#value!",
    )
)


def is_missing(cell: str) -> bool:
    """True for a cell that marks a missing point (:data:`MISSING`: ``---``, ``NaN``, empty…)."""
    return cell.strip().lower() in MISSING


def delimiter_char(name: str | None) -> str | None:
    """The delimiter character of ``name`` (the character itself, or ``tab``, ``semicolon``,
    ``comma``, ``whitespace``/``space``); None stays None; anything else is refused."""
    if name is None or name in DELIMITER_NAMES:
        return name
    names = {"tab": "\t", "semicolon": ";", "comma": ",", "whitespace": " ", "space": " "}
    if name in names:
        return names[name]
    raise BadInputError(
        f"delimiter {name!r} is not supported; use tab, ';', ',' or ' ' (whitespace)"
    )


def fields(line: str, delimiter: str | None) -> list[str]:
    """The stripped fields of ``line`` split at ``delimiter`` (``" "``: any whitespace run;
    None: the whole line is one field); a trailing delimiter adds no field."""
    if delimiter is None:
        return [line.strip()]
    if delimiter == " ":
        return line.split()
    toks = [t.strip() for t in line.strip().split(delimiter)]
    return toks[:-1] if len(toks) > 1 and toks[-1] == "" else toks


def split_fields(line: str, delim: str) -> list[str]:
    """The stripped fields of ``line`` split at ``delim``, a trailing empty field kept."""
    if delim == " ":
        return line.split()
    return [t.strip() for t in line.strip().split(delim)]


def is_number(tok: str, dec: str) -> bool:
    """Whether ``tok`` is a number with the decimal mark ``dec`` (and not the other one)."""
    if not tok:
        return False
    if dec == ".":
        if "," in tok:
            return False
    elif "." in tok:
        return False
    return bool(_NUMBER_RE.match(tok))


def _score(lines: Sequence[str], delim: str, dec: str) -> tuple[int, float] | None:
    """(modal number of columns, fraction of sample lines that are that many numbers)."""
    if delim == dec:
        return None
    counts: dict[int, int] = {}
    for ln in lines:
        toks = split_fields(ln, delim)
        if delim != " " and toks and toks[-1] == "":
            toks = toks[:-1]  # trailing delimiter
        nums = [is_number(t, dec) for t in toks]
        if any(nums) and all(n or is_missing(t) for n, t in zip(nums, toks, strict=True)):
            counts[len(toks)] = counts.get(len(toks), 0) + 1
    if not counts:
        return None
    n, c = max(counts.items(), key=lambda kv: (kv[1], kv[0]))
    frac = c / len(lines)
    return (n, frac) if frac >= 0.75 else None


def sniff_separators(
    sample: Sequence[str], delimiter: str | None = None, decimal: str | None = None
) -> tuple[str, str] | None:
    """The (delimiter, decimal mark) under which the data lines ``sample`` read as numbers.

    Parameters
    ----------
    sample : sequence of str
        Non-blank data lines (no header).
    delimiter, decimal : str, optional
        Given ones are kept; the others are tried (:data:`DELIMITERS`; ``"."``, ``","``).

    Returns
    -------
    tuple of str or None
        The reading under which at least 95 % of the lines (else 75 %) are the same number of
        numbers, preferring more columns, then an explicit delimiter; None when no reading does.
        A comma that only ever separates integers with leading zeros, or two integer fields of
        which the second always has the same width, is a decimal comma, not a delimiter.
    """
    best = None
    for d in [delimiter] if delimiter else list(DELIMITERS):
        for c in [decimal] if decimal else [".", ","]:
            sc = _score(sample, d, c)
            if sc is None:
                continue
            # lines that all parse first, then more columns, then an explicit delimiter
            key = (sc[1] >= 0.95, sc[0], sc[1], d != " ")
            # a comma that only ever separates integers with leading zeros is a decimal comma
            if d == "," and c == ".":
                toks = [split_fields(ln, ",") for ln in sample]
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
    return None if best is None else (best[1], best[2])


def grouped_number(sep: str, dec: str | None) -> re.Pattern:
    """A number whose integer part is grouped by ``sep`` (or has at most 3 digits)."""
    d = "[.,]" if dec is None else re.escape(dec)
    s = re.escape(sep)
    return re.compile(rf"^[-+]?\d{{1,3}}(?:{s}\d{{3}})*(?:{d}\d*)?(?:[eE][-+]?\d+)?$")


def _plain(dec: str) -> re.Pattern:
    d = re.escape(dec)
    return re.compile(rf"^[-+]?(?:\d+(?:{d}\d*)?|{d}\d+)(?:[eE][-+]?\d+)?$")


def sniff_thousands(lines: Sequence[str], delimiter: str | None) -> str | None:
    """A thousands mark that the table shows unambiguously, else None.

    Parameters
    ----------
    lines : sequence of str
        Data lines.
    delimiter : str or None
        Their field delimiter; None for one column.

    Returns
    -------
    str or None
        ``sep`` when, within the fields, (1) neither ``sep`` nor the decimal mark is the
        delimiter, (2) at least one number holds ``sep`` and the decimal mark
        (``8,001.234``), and (3) every value of every column holding ``sep`` is grouped by it
        (``999.5`` yes; ``1234.5`` or ``0.458`` with ``sep='.'`` no) and every other column
        reads with the decimal mark alone.
    """
    table = [fields(ln, delimiter) for ln in lines if ln.strip()]
    if not table:
        return None
    width = max(map(len, table))
    cols = [[r[j] for r in table if j < len(r) and not is_missing(r[j])] for j in range(width)]
    for sep, dec in ((",", "."), (".", ","), ("'", "."), ("'", ","), (" ", ","), (" ", ".")):
        if delimiter in (sep, dec) or (delimiter is None and sep == " "):
            continue
        both = re.compile(rf"^[-+]?\d{{1,3}}(?:{re.escape(sep)}\d{{3}})+{re.escape(dec)}\d+")
        if not any(both.match(v) for col in cols for v in col):
            continue
        grouped, plain = grouped_number(sep, dec), _plain(dec)
        if all(
            all(map((grouped if any(sep in v for v in col) else plain).match, col)) for col in cols
        ):
            return sep
    return None
