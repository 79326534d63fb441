"""Refusals that carry their own advice, in a form a program can apply.

A reader that refuses an ambiguous or contradictory file names the option(s) that settle it. A
:class:`Refusal` keeps those options as data (``suggestions``: alternative keyword sets of
:func:`~jointwear.metrology.readers.read_scan`) next to the message that names them, so that a
test can apply every suggestion to the same file and check that it reads the file right or
refuses again for a different reason (``tests/metrology/test_advice.py``). The message text is
made from the same data (:func:`advise`), so the two cannot drift apart; the command line
rewrites ``keyword=value`` into its ``--flag value`` (:func:`jointwear._cli.speak_flags`).
"""

from __future__ import annotations

from collections.abc import Mapping

from jointwear.errors import BadInputError
from jointwear.metrology.choices import PLAUSIBILITY

__all__ = ["Refusal", "advise", "plausibility", "PLAUSIBILITY"]


class Refusal(BadInputError):
    """A :class:`~jointwear.errors.BadInputError` with the options that settle it.

    Attributes
    ----------
    suggestions : tuple of dict
        Alternative option sets (keywords of ``read_scan``), each one a complete fix for one
        reading of the file; empty when nothing but a corrected file can help.
    """

    def __init__(self, message: str, suggestions: tuple[dict, ...] = ()):
        super().__init__(message)
        self.suggestions = tuple(dict(s) for s in suggestions)


def _spell(key: str, value: object) -> str:
    if isinstance(value, (tuple, list)):
        if key == "ignore_header":
            return " ".join(f"ignore_header={v}" for v in value)
        if key == "columns":  # one comma-joined word: the same in Python and on the command line
            return f"{key}='{','.join(str(v) for v in value)}'"
        return f"{key}=({','.join(str(v) for v in value)})"
    if isinstance(value, bool):
        return f"{key}={value}"
    if isinstance(value, str):
        return f"{key}={value}" if value.startswith("<") else f"{key}='{value}'"
    return f"{key}=<{'m' if key in _METRES else 'value'}>"


_METRES = ("layer_spacing", "max_deviation", "min_form")


def advise(options: list[tuple[Mapping, str]]) -> tuple[str, tuple[dict, ...]]:
    """Text naming each alternative fix, and the fixes as data.

    Parameters
    ----------
    options : list of (dict, str)
        Each alternative: the options to pass and when it is the right one.

    Returns
    -------
    (str, tuple of dict)
        "pass A (when ...), or B (when ...)" and the option sets.
    """
    parts = [
        " ".join(_spell(k, v) for k, v in opts.items()) + (f" ({why})" if why else "")
        for opts, why in options
    ]
    return "pass " + ", or ".join(parts), tuple(dict(o) for o, _ in options)


def plausibility(**overrides: float | None) -> dict[str, float]:
    """The plausibility limits with the given overrides (``None`` keeps the default)."""
    out = dict(PLAUSIBILITY)
    for k, v in overrides.items():
        if v is None:
            continue
        if k not in out:
            raise BadInputError(f"unknown plausibility limit {k!r}; known: {', '.join(out)}")
        if not float(v) > 0:
            raise BadInputError(f"plausibility limit {k}={v!r} must be > 0")
        out[k] = float(v)
    if out["radius_min"] >= out["radius_max"]:
        raise BadInputError(
            f"radius_range=({out['radius_min']:g}, {out['radius_max']:g}) m is empty; give "
            "(min, max) with min < max"
        )
    return out
