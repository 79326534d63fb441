"""Excel workbooks (``.xlsx``) as tables: a Talyrond-style sheet of angle and value columns.

A workbook is turned into the same tab-separated text a text export would be (cells above the
table become header lines, numbers keep every digit), so that it goes through the same sniffing
and the same refusals as any text export. "Line" in messages is the worksheet row.
"""

from __future__ import annotations

import datetime as _dt
import re
import zipfile
from pathlib import Path

import numpy as np

from jointwear.errors import BadInputError
from jointwear.metrology.readers.pretext import numeric_line

_NUM = r"[-+]?(?:\d+(?:[.,]\d*)?|[.,]\d+)"

__all__ = ["workbook_text"]


def _cell(v: object) -> str:
    if v is None:
        return ""
    if isinstance(v, bool):
        return str(v)
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        return repr(v)
    if isinstance(v, (_dt.datetime, _dt.date, _dt.time)):
        return v.isoformat()
    return " ".join(str(v).split())  # tabs and line breaks inside a cell become spaces


def _has_numbers(ws) -> bool:
    for row in ws.iter_rows(values_only=True):
        if any(isinstance(v, (int, float)) and not isinstance(v, bool) for v in row):
            return True
    return False


_LAYER_HEAD = re.compile(
    rf"^(?:(?:layer|plane|trace|level|section)\s*(?:no\.?|#)?\s*(\d+))?[\s,;:-]*"
    rf"(?:(?:z|height|h)\s*[=:]?\s*({_NUM})\s*(mm|um|µm|μm|m|in|inch)?)?\s*$",
    re.I,
)


def _merged_layer_heads(rows: list[list[str]]) -> list[list[str]] | None:
    """A sheet whose layers stand side by side under merged header cells (``Layer 2  z = 1.0
    mm`` over an angle and a value column each) as one long table: a z column (or a layer
    number column when the cells give no z), then each group's columns, layer after layer.
    None when the sheet has no such header row."""
    for h, row in enumerate(rows[:40]):
        cells = [(j, c) for j, c in enumerate(row) if c]
        if len(cells) < 2:
            continue
        found = [(j, _LAYER_HEAD.match(c)) for j, c in cells]
        if not all(m and (m.group(1) or m.group(2)) for _, m in found):
            continue
        pos = [j for j, _ in found]
        steps = set(np.diff(pos).tolist())
        if len(steps) != 1 or min(steps) < 2:
            continue
        width = steps.pop()
        p0 = pos[0]
        body = rows[h + 1 :]
        names = body[0] if body and not numeric_line("\t".join(body[0])) else None
        data = body[1:] if names is not None else body
        zs = [m.group(2) for _, m in found]
        units = {m.group(3) for _, m in found if m.group(3)}
        if all(zs):
            head = [f"z [{units.pop()}]" if len(units) == 1 else "z"]
            keys = [z.replace(",", ".") for z in zs]
        else:
            head, keys = ["Layer"], [m.group(1) or str(k + 1) for k, (_, m) in enumerate(found)]
        group = (names or [])[p0 : p0 + width]
        out = rows[:h] + ([head + group] if names is not None else [])
        for g, key in enumerate(keys):
            lo = p0 + g * width
            for r in data:
                part = (r[lo : lo + width] + [""] * width)[:width]
                if any(part):
                    out.append([key, *part])
        return out
    return None


def _blank_cells_missing(rows: list[list[str]]) -> list[list[str]]:
    """Rows of numbers padded to the table's width: a blank cell at the end of a row of the
    table is a missing value (a worksheet has no cut lines), not a shorter row."""
    from collections import Counter

    numeric = [bool(r) and numeric_line("\t".join(r)) for r in rows]
    widths = Counter(len(r) for r, n in zip(rows, numeric, strict=True) if n)
    if not widths:
        return rows
    width = widths.most_common(1)[0][0]
    return [
        r + [""] * (width - len(r)) if n and len(r) < width else r
        for r, n in zip(rows, numeric, strict=True)
    ]


def workbook_text(path: Path, sheet: str | None = None) -> str:
    """Tab-separated text of one worksheet of ``path``.

    Parameters
    ----------
    path : Path
        An ``.xlsx`` / ``.xlsm`` workbook.
    sheet : str, optional
        Worksheet name; required when several sheets hold numbers.

    Raises
    ------
    BadInputError
        Not a readable workbook, no sheet with numbers, an unknown sheet, or several sheets with
        numbers and no ``sheet``.
    """
    try:
        with zipfile.ZipFile(path) as zf:
            names = set(zf.namelist())
    except (zipfile.BadZipFile, OSError) as exc:
        raise BadInputError(f"'{path}': damaged zip container ({exc}); re-export it") from None
    if "main.xml" in names:
        from jointwear.metrology.readers.x3p import x3p_text

        return x3p_text(path)
    if "xl/workbook.xml" not in names:
        raise BadInputError(
            f"'{path}' is a zip archive but neither an Excel workbook (.xlsx) nor an X3P file; "
            "unpack it and import the text export inside"
        )
    import openpyxl

    try:
        wb = openpyxl.load_workbook(path, read_only=True, data_only=True)
    except Exception as exc:  # openpyxl raises many kinds on damaged files
        raise BadInputError(
            f"'{path}': cannot read the workbook ({type(exc).__name__}: {exc}); re-save it in "
            "Excel as .xlsx or export the trace as text"
        ) from None
    try:
        if sheet is not None:
            if sheet not in wb.sheetnames:
                raise BadInputError(
                    f"'{path}': no sheet {sheet!r}; the sheets are "
                    + ", ".join(repr(s) for s in wb.sheetnames)
                )
            ws = wb[sheet]
        else:
            data = [s for s in wb.sheetnames if _has_numbers(wb[s])]
            if not data:
                raise BadInputError(f"'{path}': no sheet holds numbers; is this a measurement?")
            if len(data) > 1:
                raise BadInputError(
                    f"'{path}': several sheets hold numbers ("
                    + ", ".join(repr(s) for s in data)
                    + "); say which is the trace with sheet=... (--sheet NAME)"
                )
            ws = wb[data[0]]
        rows = []
        for row in ws.iter_rows(values_only=True):
            cells = [_cell(v) for v in row]
            while cells and cells[-1] == "":
                cells.pop()
            rows.append(cells)
    finally:
        wb.close()
    rows = _merged_layer_heads(rows) or _blank_cells_missing(rows)
    text = "\n".join("\t".join(r) for r in rows).rstrip("\n") + "\n"
    if not text.strip():
        raise BadInputError(f"'{path}': the sheet is empty")
    return text
