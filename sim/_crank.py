"""What the parameters of every crank-driven mechanism share (four-bar, slider-crank).

The crank's speed and period from ``crank_speed_rpm``, and the field of a body's three
principal moments of inertia with its check.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from typing import Any

from jointwear.errors import ParameterError
from jointwear.params import check_positive, checked

__all__ = ["CrankDriven", "principal_inertias", "inertias"]


class CrankDriven:
    """Mixin of a mechanism's parameters whose crank turns at ``crank_speed_rpm``."""

    crank_speed_rpm: float

    @property
    def crank_speed(self) -> float:
        """Crank angular speed [rad/s] (counter-clockwise positive)."""
        return self.crank_speed_rpm * 2.0 * math.pi / 60.0

    @property
    def period(self) -> float:
        """Duration of one crank revolution at the nominal speed [s] (inf when it stands)."""
        return 2.0 * math.pi / abs(self.crank_speed) if self.crank_speed else math.inf


def principal_inertias(
    where: str, name: str, values: Sequence[float], axes: str
) -> tuple[float, ...]:
    """Three positive moments of inertia [kg m2] as floats, or a ParameterError naming
    ``where.name`` and the ``axes`` they are about."""
    if len(values) != 3:
        raise ParameterError(
            f"{where}.{name} must hold 3 values ({axes}) [kg m2], got {len(values)}"
        )
    out = tuple(float(v) for v in values)
    for i, v in enumerate(out):
        check_positive(where, **{f"{name}[{i}]": v})
    return out


def inertias(default: tuple[float, ...], axes: str) -> Any:
    """A dataclass field of three principal moments of inertia [kg m2] about ``axes``
    (checked by :func:`principal_inertias` and kept as floats; see
    :func:`jointwear.params.check_fields`)."""
    return checked(default, functools.partial(principal_inertias, axes=axes))
