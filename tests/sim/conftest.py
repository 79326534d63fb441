"""Fixtures shared by the simulator's tests."""

from __future__ import annotations

import pytest


@pytest.fixture
def interrupt_after():
    """``interrupt_after(n)``: an ``on_update`` callback that stops a wear run at its n-th update
    (KeyboardInterrupt, as Ctrl-C would), to test checkpoints and resume."""

    def make(n: int):
        seen = []

        def on_update(info):
            seen.append(info)
            if len(seen) == n:
                raise KeyboardInterrupt

        return on_update

    return make
