"""Generic reader for roundness / cylindricity text exports (compatibility module).

The reader is split by concept: :mod:`~jointwear.metrology.readers.table` (text to a numeric
table), :mod:`~jointwear.metrology.readers.columns` (column meanings),
:mod:`~jointwear.metrology.readers.meaning` (angle unit, span and value kind),
:mod:`~jointwear.metrology.readers.layers` (table to traces) and
:mod:`~jointwear.metrology.readers.scan` (traces to a contract Dataset).
"""

from __future__ import annotations

from jointwear.metrology.readers.columns import COLUMN_KINDS
from jointwear.metrology.readers.scan import ScanReading, read_scan, read_text
from jointwear.metrology.readers.table import (
    UNITS,
    ParsedFile,
    TextFormat,
    parse_file,
    sniff,
    unit_factor,
)

__all__ = [
    "COLUMN_KINDS",
    "UNITS",
    "ScanReading",
    "TextFormat",
    "ParsedFile",
    "sniff",
    "parse_file",
    "read_text",
    "read_scan",
    "unit_factor",
]
