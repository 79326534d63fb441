"""The criteria table: every decided wear criterion, by name, in the order of the decision card.

A row names the criterion, the function that decides it (``"module:function"``, imported when
the table is read, so that a new criterion is one module and one row here), what decides it
(``threshold``, ``V&V 20`` or ``field``) and how its resolution is stated. The function takes
the :class:`jointwear.compare._wear.WearCase` of the comparison and appends its metric rows and
its decision (four states, :mod:`jointwear.compare.verdicts`).

Adding a criterion: write ``decide(case)`` in a module of its own (reading ``case.s``,
``case.d``, ``case.al``, ``case.src`` for the budget), append one :class:`Criterion` to
:data:`CRITERIA`; the card, ``metrics.nc``, the report and the summary take it from there.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from dataclasses import dataclass
from functools import cache
from typing import Any

__all__ = ["Criterion", "CRITERIA", "criteria_of"]


@dataclass(frozen=True)
class Criterion:
    """One row of the criteria table.

    Attributes
    ----------
    name : str
        Identifier of the criterion.
    family : str
        What it compares: ``"wear"`` (the aligned wear maps).
    decider : str
        ``"module:function"`` deciding it; a function name ending in ``()`` is a factory called
        with ``argument``.
    basis : str
        What decides it: ``"threshold"``, ``"V&V 20"`` or ``"field"`` (a Mahalanobis distance,
        :mod:`jointwear.compare._field`).
    resolution : str
        How its resolution (the smallest error it detects) is stated.
    argument : str
        Argument of a factory ``decider``.
    """

    name: str
    family: str
    decider: str
    basis: str
    resolution: str
    argument: str = ""

    @property
    def decide(self) -> Callable[[Any], None]:
        """The deciding function."""
        return _resolve(self.decider, self.argument)


@cache
def _resolve(decider: str, argument: str) -> Callable[[Any], None]:
    module, _, name = decider.partition(":")
    fn = getattr(importlib.import_module(module), name.removesuffix("()"))
    return fn(argument) if name.endswith("()") else fn


_WEAR = "jointwear.compare._wear"
_FIELD = "jointwear.compare._field"
_VV20 = "detectable relative errors, both ways (detectable_error_low/high)"

#: the criteria table, in the order of the decision card
CRITERIA: tuple[Criterion, ...] = (
    Criterion("wear_shape", "wear", "jointwear.compare._shape:shape_criterion", "threshold",
              "the turn of the pattern that brings r below min(wear_r_min, r_alpha)"),
    Criterion("max_wear_angle", "wear", f"{_WEAR}:angle_criterion", "threshold",
              "the threshold itself (max_angle_error_deg)"),
    Criterion("max_wear_z", "wear", f"{_WEAR}:axial_criterion", "threshold",
              "the threshold itself (max_z_error_m)"),
    Criterion("max_wear_depth", "wear", f"{_WEAR}:vv20_band_criterion()", "V&V 20", _VV20,
              "max_wear_depth"),
    Criterion("worn_volume", "wear", f"{_WEAR}:vv20_band_criterion()", "V&V 20", _VV20,
              "worn_volume"),
    Criterion("cylindricity", "wear", f"{_WEAR}:vv20_band_criterion()", "V&V 20", _VV20,
              "cylindricity"),
    Criterion("wear_field", "wear", f"{_FIELD}:field_criterion", "field",
              "D² threshold and the smallest common scale error (detectable_scale_error)"),
    Criterion("axial_distribution", "wear", f"{_FIELD}:axial_criterion_field", "field",
              "D² threshold (scale-free: shares per layer)"),
)  # fmt: skip


def criteria_of(family: str) -> tuple[Criterion, ...]:
    """The rows of :data:`CRITERIA` of one family, in order."""
    return tuple(c for c in CRITERIA if c.family == family)
