"""Shared pytest configuration."""

from __future__ import annotations

import os

os.environ.setdefault("MPLBACKEND", "Agg")
# the CLI's compile-once warm-up (jointwear._compile) is off in tests: a test compiles the
# kernels it calls, as before; tests/root/test_compile.py turns it on where it tests it
os.environ.setdefault("JOINTWEAR_WARM_UP", "0")
