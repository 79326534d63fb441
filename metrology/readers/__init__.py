"""Instrument file readers (one module per instrument family)."""
