"""Excel workbooks (``.xlsx``) as tables: a Talyrond-style sheet of angle and value columns.

A workbook is turned into the same tab-separated text a text export would be (cells above the
table become header lines, numbers keep every digit), so that it goes through the same sniffing
and the same refusals as any text export. "Line" in messages is the worksheet row.
"""

from __future__ import annotations

import datetime as _dt
import zipfile
from pathlib import Path

from jointwear.errors import BadInputError

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


def _blank_cells_missing(rows: list[list[str]]) -> list[list[str]]:
    """Rows of numbers padded to the table's width: a blank cell at the end of a row of the
    table is a missing value (a worksheet has no cut lines), not a shorter row."""
    from collections import Counter

    from jointwear.metrology.readers.pretext import numeric_line

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
    text = "\n".join("\t".join(r) for r in _blank_cells_missing(rows)).rstrip("\n") + "\n"
    if not text.strip():
        raise BadInputError(f"'{path}': the sheet is empty")
    return text
