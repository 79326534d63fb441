"""Instrument file readers (one module per instrument family)."""

from jointwear.metrology.readers.talyrond import TALYROND_DEFAULTS, read_talyrond
from jointwear.metrology.readers.text import (  # the split modules, re-exported
    COLUMN_KINDS,
    ScanReading,
    TextFormat,
    parse_file,
    read_scan,
    read_text,
    sniff,
)

__all__ = [
    "COLUMN_KINDS",
    "ScanReading",
    "TALYROND_DEFAULTS",
    "TextFormat",
    "parse_file",
    "read_scan",
    "read_talyrond",
    "read_text",
    "sniff",
]
