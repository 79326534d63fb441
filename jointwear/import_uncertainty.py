"""The uncertainty a user states for imported data (``jointwear import --u/--u-column``).

A CSV table from another tool carries numbers, not their uncertainty. V&V 20 needs it (u_D of a
measurement, u_num of a simulation): without it every V&V 20 criterion on the data is *not
assessed*. :class:`StatedUncertainty` is what the user says: one value for every point
(``"0.5 um"``) or a column of the table, its coverage factor ``k`` (1: a standard uncertainty,
2: an expanded one at about 95 %) and what it covers (probe noise, calibration, ...). It is
stored as the contract's ``<name>_u``: a standard uncertainty (``coverage_factor = 1``) in the
variable's units, with a ``comment`` saying what was stated and what it covers, so that a
combined budget counts nothing twice.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np
import xarray as xr

from jointwear.errors import ParameterError

__all__ = ["StatedUncertainty", "NO_UNCERTAINTY_NOTE", "attach_uncertainty", "parse_value"]

#: What ``jointwear import`` says when no uncertainty is stated (and how to state one).
NO_UNCERTAINTY_NOTE = (
    "no uncertainty stated for {what}: every V&V 20 criterion on these data will be NOT "
    "ASSESSED; state it with --u VALUE[unit] (one value for every point, e.g. --u {example}) or "
    "--u-column NAME (a column of the table), with --u-k (1: standard uncertainty, 2: expanded, "
    "about 95 %) and --u-covers (what it covers, e.g. 'probe noise and calibration')"
)

_VALUE = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*(.*?)\s*$")


@dataclass(frozen=True)
class StatedUncertainty:
    """An uncertainty stated at import.

    Parameters
    ----------
    value : str, optional
        One value for every point, with or without its unit (``"0.5 um"``, ``"2mm/s"``,
        ``"0.4"`` in the data's unit). Exactly one of ``value`` and ``columns``.
    columns : sequence of str, optional
        Column(s) of the table holding the uncertainty of each row, in the data's unit: one
        for all components, or one per component.
    k : float
        Coverage factor of the stated values [1]: 1 for a standard uncertainty, 2 for an
        expanded one (about 95 %); the stored ``_u`` is ``value / k``.
    covers : str
        What the uncertainty covers (noise, calibration, form of the reference, ...), kept in
        the ``comment`` so that a combined budget counts nothing twice.
    """

    value: str | None = None
    columns: tuple[str, ...] | None = None
    k: float | None = None
    covers: str | None = None

    def __post_init__(self) -> None:
        if self.columns is not None:
            object.__setattr__(self, "columns", tuple(self.columns))
        if (self.value is None) == (self.columns is None):
            raise ParameterError("--u / --u-column: give one of them, not both")
        missing = [
            f for f, v in (("--u-k", self.k), ("--u-covers", self.covers)) if v in (None, "")
        ]
        if missing:
            raise ParameterError(
                f"{' and '.join(missing)}: a stated uncertainty needs its coverage factor "
                "(--u-k 1 for a standard uncertainty, --u-k 2 for an expanded one at about "
                "95 %) and what it covers (--u-covers 'probe noise and calibration'); "
                "jointwear never guesses them"
            )
        if not (np.isfinite(self.k) and self.k > 0):
            raise ParameterError(f"--u-k {self.k!r}: expected a coverage factor > 0 (1 or 2)")

    def describe(self, unit: str) -> str:
        """The ``comment`` of the stored ``_u``."""
        given = (
            f"{self.value}" if self.value is not None else f"column(s) {', '.join(self.columns)}"
        )
        kind = "standard" if self.k == 1 else f"expanded with k = {self.k:g}, divided by {self.k:g}"
        return (
            f"stated by the user at import: {given} ({kind}; data in {unit}); covers: {self.covers}"
        )


def parse_value(text: str, default_unit: str, *, kind: str) -> float:
    """``"0.5 um"`` (or ``"0.5"`` in ``default_unit``) in SI units of ``kind``; refused
    naming ``--u`` when it is not a number >= 0 with a unit of the right kind."""
    from jointwear.external import to_si

    m = _VALUE.match(str(text))
    if not m:
        raise ParameterError(
            f"--u {text!r}: expected a number with an optional unit, e.g. 0.5um or 2 mm/s"
        )
    number, unit = float(m.group(1)), m.group(2) or default_unit
    if not (np.isfinite(number) and number >= 0):
        raise ParameterError(f"--u {text!r}: an uncertainty is a number >= 0")
    return float(to_si([number], unit, kind=kind, option="--u")[0])


def attach_uncertainty(
    ds: xr.Dataset,
    name: str,
    stated: StatedUncertainty,
    *,
    unit: str,
    kind: str,
    values: np.ndarray | None = None,
) -> xr.Dataset:
    """``ds`` with ``<name>_u`` from ``stated`` (a standard uncertainty in SI units).

    Parameters
    ----------
    ds : Dataset
        Holds ``name`` (its SI values).
    name : str
        The variable the uncertainty belongs to.
    stated : StatedUncertainty
    unit, kind : str
        The unit the data were given in (the default unit of ``--u``) and what they are
        (``"length"``, ``"velocity"``).
    values : ndarray, optional
        The stated column(s) in SI units, broadcastable to ``ds[name]`` (``stated.columns``).
    """
    var = ds[name]
    if stated.value is not None:
        u = np.full(var.shape, parse_value(stated.value, unit, kind=kind))
    else:
        u = np.broadcast_to(np.asarray(values, dtype=float), var.shape)
        bad = ~(np.isfinite(u) & (u >= 0))
        if bad.any():
            raise ParameterError(
                f"--u-column {', '.join(stated.columns)}: {int(bad.sum())} value(s) are not an "
                "uncertainty (a finite number >= 0); fix those rows"
            )
    ds = ds.copy()
    ds[f"{name}_u"] = (
        var.dims,
        u / float(stated.k),
        {
            "units": var.attrs.get("units", ""),
            "long_name": f"standard uncertainty of {var.attrs.get('long_name', name)}",
            "coverage_factor": 1.0,
            "comment": stated.describe(unit),
        },
    )
    ds[name].attrs["ancillary_variables"] = f"{name}_u"
    return ds
