"""Bytes to text: encodings (UTF-8, UTF-8-BOM, UTF-16, Latin-1), workbooks and X3P files."""

from __future__ import annotations

from pathlib import Path

from jointwear.errors import BadInputError

__all__ = []


def _utf16(raw: bytes) -> str | None:
    """The UTF-16 codec of ``raw`` (BOM, or ASCII text with every other byte zero), else None."""
    if raw[:2] in (b"\xff\xfe", b"\xfe\xff"):
        return "utf-16"
    head = raw[:4096]
    if len(head) >= 4:
        even, odd = head[0::2], head[1::2]
        if odd.count(0) > 0.9 * len(odd) and even.count(0) < 0.1 * len(even):
            return "utf-16-le"
        if even.count(0) > 0.9 * len(even) and odd.count(0) < 0.1 * len(odd):
            return "utf-16-be"
    return None


def _read_text(path: Path, encoding: str | None, sheet: str | None = None) -> str:
    try:
        raw = path.read_bytes()
    except FileNotFoundError:
        raise BadInputError(f"'{path}' does not exist") from None
    except IsADirectoryError:
        raise BadInputError(
            f"'{path}' is a folder; use layout='folder' to read per-layer files"
        ) from None
    except OSError as exc:
        raise BadInputError(f"'{path}': cannot read ({exc.strerror or exc})") from None
    if raw[:4] == b"PK\x03\x04":
        from jointwear.metrology.readers.workbook import workbook_text

        return workbook_text(path, sheet)
    if raw[:8] == b"\xd0\xcf\x11\xe0\xa1\xb1\x1a\xe1":
        raise BadInputError(
            f"'{path}' is an old binary Excel (.xls) or other OLE file; save it as .xlsx or "
            "export the trace as text (CSV)"
        )
    if sheet is not None:
        raise BadInputError(f"sheet={sheet!r} (--sheet) was given but '{path}' is not a workbook")
    codec = encoding or _utf16(raw)
    if codec is None and raw[:3] == b"\xef\xbb\xbf":
        codec = "utf-8-sig"
    text = None
    if codec:
        try:
            text = raw.decode(codec)
        except (UnicodeDecodeError, LookupError) as exc:
            raise BadInputError(
                f"'{path}': cannot decode as {codec!r} ({exc}); pass encoding=..."
            ) from None
        text = text.lstrip("\ufeff")
    if not (text if text is not None else raw).strip():
        raise BadInputError(
            f"'{path}' is empty (line 1): expected a text export of a roundness trace; "
            "re-export the measurement"
        )
    if text is None:
        head = raw[:8192]
        ctrl = sum(1 for b in head if b < 32 and b not in (9, 10, 13, 12, 26))
        if b"\x00" in head or ctrl > 0.01 * len(head):
            raise BadInputError(
                f"'{path}' looks like a binary file (line 1 holds control bytes), not a text "
                "export; export the trace as text (ASCII/CSV, UTF-8 or UTF-16) from the "
                "instrument software"
            )
        try:
            text = raw.decode("utf-8")
        except UnicodeDecodeError:
            text = raw.decode("latin-1")
    else:
        ctrl = sum(1 for c in text[:8192] if ord(c) < 32 and c not in "\t\n\r\f\x1a")
        if ctrl > 0.01 * min(len(text), 8192):
            raise BadInputError(
                f"'{path}' decoded as {codec} holds control characters; not a text export"
            )
    return text
