"""The four states of a validation criterion and how they are counted, stored and summarised.

A criterion is

``pass``
    the data cover what it judges, every uncertainty it needs is known, and it is met;
``fail``
    the same, but it is not met;
``not_assessed``
    an uncertainty it needs is unknown (never treated as zero): e.g. V&V 20 without the input
    uncertainty of the simulation;
``not_comparable``
    the data do not cover what it judges: e.g. the simulated maximum wear lies outside the
    axial range the measurement covers, or too much of the simulated worn volume does.

In netCDF a decision is an ``int8`` with CF ``flag_values = [0, 1, 2, 3]`` and
``flag_meanings = "fail pass not_assessed not_comparable"`` (the data contract).
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np
import pandas as pd

__all__ = [
    "PASS",
    "FAIL",
    "NOT_ASSESSED",
    "NOT_COMPARABLE",
    "STATES",
    "FLAG_VALUES",
    "FLAG_MEANINGS",
    "LABELS",
    "state_code",
    "state_of_code",
    "counts",
    "summary_line",
]

PASS = "pass"
FAIL = "fail"
NOT_ASSESSED = "not_assessed"
NOT_COMPARABLE = "not_comparable"

#: the states in the order of their flag values
STATES: tuple[str, ...] = (FAIL, PASS, NOT_ASSESSED, NOT_COMPARABLE)
FLAG_VALUES = np.array([0, 1, 2, 3], dtype=np.int8)
FLAG_MEANINGS = " ".join(STATES)

#: how a state is shown to a person (decision card, console)
LABELS: dict[str, str] = {
    PASS: "PASS",
    FAIL: "FAIL",
    NOT_ASSESSED: "NOT ASSESSED",
    NOT_COMPARABLE: "NOT COMPARABLE",
}


def state_code(state: str) -> np.int8:
    """The flag value of a state (``fail`` 0, ``pass`` 1, ``not_assessed`` 2, ``not_comparable`` 3)."""
    try:
        return np.int8(STATES.index(state))
    except ValueError:
        raise ValueError(f"unknown verdict state {state!r}; one of {', '.join(STATES)}") from None


def state_of_code(code: int) -> str:
    """Inverse of :func:`state_code`."""
    code = int(code)
    if not 0 <= code < len(STATES):
        raise ValueError(f"verdict flag {code} is not one of {list(FLAG_VALUES)}")
    return STATES[code]


def counts(states: Iterable[str] | pd.Series) -> dict[str, int]:
    """Number of decisions in each state (every state present, possibly 0)."""
    out = dict.fromkeys(STATES, 0)
    for s in states:
        out[str(s)] += 1
    return out


def summary_line(states: Iterable[str] | pd.Series) -> str:
    """``"12 criteria: 3 pass, 1 fail, 5 not assessed, 3 not comparable"`` (zero counts omitted)."""
    c = counts(states)
    n = sum(c.values())
    parts = [f"{c[s]} {s.replace('_', ' ')}" for s in (PASS, FAIL, NOT_ASSESSED, NOT_COMPARABLE)]
    shown = [
        p for p, s in zip(parts, (PASS, FAIL, NOT_ASSESSED, NOT_COMPARABLE), strict=True) if c[s]
    ]
    return f"{n} criteria: " + (", ".join(shown) if shown else "none")
