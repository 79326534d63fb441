"""Text as labs write it, made plain before sniffing: end-of-file marks, quoted CSV, thousands
separators, concatenated per-layer blocks; formats that are not supported are named.

* a trailing Ctrl-Z (DOS end-of-file mark, often after CRLF line ends) is dropped;
* JSON and angles in degrees-minutes-seconds are refused as unsupported formats (no delimiter
  advice can make them readable);
* quoted CSV (``"0.5","8.0012"``, also with a decimal comma inside the quotes) is unquoted
  with :mod:`csv` and re-joined with tabs;
* thousands separators (``8,001.234``, ``8.001,234``, ``8'001.234``) are removed when the file
  shows both separators in one number (unambiguous), or when ``thousands=`` is given;
* a file of several blocks, each a layer with its own header lines (``Layer 2``, ``Height:
  1 mm``, the column names again), is split into blocks (:func:`split_blocks`).
"""

from __future__ import annotations

import csv
import io
import re

from jointwear.metrology.readers.advice import Refusal

__all__ = ["normalise", "split_blocks"]

_DMS = re.compile(r"\d+\s*°\s*\d+\s*['′]|\d+d\s*\d+m\s*\d+(\.\d+)?s", re.I)


def normalise(text: str, path: str, thousands: str | None) -> tuple[str, dict[str, str]]:
    """(plain text, notes on what was changed) or a refusal for an unsupported format."""
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
    sep = thousands or _thousands(text)
    if sep is not None:
        dec = "," if sep == "." else "."
        pat = re.compile(
            rf"(?<![\d{re.escape(sep)}])(\d{{1,3}}(?:{re.escape(sep)}\d{{3}})+)(?=[{re.escape(dec)}\s;\t]|$)"
        )
        text = "\n".join(
            pat.sub(lambda m: m.group(1).replace(sep, ""), ln) if _is_data(ln) else ln
            for ln in text.splitlines()
        )
        notes["thousands"] = (
            f"thousands separator {sep!r} removed ({'given' if thousands else 'seen next to the decimal separator in one number'})"
        )
    return text, notes


def _is_data(line: str) -> bool:
    s = line.strip()
    return bool(s) and bool(re.match(r"^[-+]?\d", s)) and not re.search(r"[A-DF-Za-df-z]", s)


def _thousands(text: str) -> str | None:
    """A thousands separator shown unambiguously: a number holding both separators."""
    lines = [ln for ln in text[:65536].splitlines()[:400] if _is_data(ln)]
    for sep, dec in ((",", "."), (".", ","), ("'", "."), ("'", ",")):
        pat = re.compile(rf"\b\d{{1,3}}(?:{re.escape(sep)}\d{{3}})+{re.escape(dec)}\d+")
        if sum(bool(pat.search(ln)) for ln in lines) >= max(1, len(lines) // 10):
            return sep
    return None


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
    s = line.strip()
    return (
        bool(s)
        and bool(re.match(r"^[-+]?(?:\d|[.,]\d)", s))
        and not re.search(r"[A-DF-Za-df-z]", s)
    )


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
