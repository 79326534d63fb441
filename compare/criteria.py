"""Validation criteria and the uncertainty fractions a user may state (editable from TOML)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from jointwear.errors import ParameterError
from jointwear.params import check_fields, checked, from_mapping, read_toml

__all__ = ["Criteria", "load_criteria"]


def _limit(where: str, name: str, value: Any) -> Any:
    if not (isinstance(value, (int, float)) and np.isfinite(value) and value >= 0):
        raise ParameterError(f"{where}.{name} must be a finite number >= 0, got {value!r}")
    return value


def _coverage_factor(where: str, name: str, value: Any) -> Any:
    if _limit(where, name, value) == 0:
        raise ParameterError(f"{where}.{name} (coverage factor) must be > 0")
    return value


def _fraction(where: str, name: str, value: Any) -> Any:
    if _limit(where, name, value) >= 1:
        raise ParameterError(f"{where}.{name} is a fraction in [0, 1), got {value!r}")
    return value


def _stated(where: str, name: str, value: Any) -> Any:
    """A user-stated relative uncertainty: None (not stated) or a fraction > 0."""
    if value is not None and _limit(where, name, value) == 0:
        raise ParameterError(
            f"{where}.{name} = 0 states that the uncertainty is exactly zero, which no "
            "simulation has; leave it out (not assessed) or state the real fraction"
        )
    return value


def _rate(where: str, name: str, value: Any) -> Any:
    if _fraction(where, name, value) == 0:
        raise ParameterError(f"{where}.{name} = 0 would never fail a model; state a rate in (0, 1)")
    return value


def _count(where: str, name: str, value: Any) -> Any:
    if not (isinstance(value, int) and not isinstance(value, bool) and value >= 1):
        raise ParameterError(f"{where}.{name} must be an integer >= 1, got {value!r}")
    return value


def _true_or_false(where: str, name: str, value: Any) -> Any:
    if not isinstance(value, bool):
        raise ParameterError(f"{where}.{name} must be true or false, got {value!r}")
    return value


@dataclass(frozen=True)
class Criteria:
    """Validation criteria and uncertainty statements (all editable from a TOML file).

    Parameters
    ----------
    k : float
        Coverage factor of the expanded validation uncertainty ``U_val = k u_val`` [1].
    wear_nrmse_max : float
        Reference value shown beside the NRMSE of the wear map; not decided [1]: NRMSE (RMSE
        over the range of D) cannot fail a scaled map (a map whose rms is 0.09 of its range
        gives NRMSE < 0.25 for a zero prediction), so the shape is decided on r alone.
    wear_r_min : float
        Smallest acceptable Pearson correlation between the simulated and measured wear maps:
        the shape criterion [1]. Scale-invariant: it judges the pattern, not its size; its
        resolution, the turn of the simulated pattern that brings r below it, is stated.
    max_angle_error_deg : float
        Largest acceptable error of the angle of maximum wear [degree].
    max_z_error_m : float
        Largest acceptable error of the axial position of maximum wear [m].
    relative_error_max : float
        Screening threshold of ``|S - D| / |D|`` of a scalar quantity, shown (labelled
        *screening only*) when V&V 20 cannot be assessed; never decided as a pass or a fail
        [1].
    motion_sg_c_max : float
        Largest acceptable Sprague-Geers comprehensive error of a motion component [1].
    max_volume_outside : float
        With ``strict_coverage``: largest fraction of the simulated worn volume that may lie
        outside the axial range the measurement covers for the whole-map criteria (shape, worn
        volume, cylindricity) to be judged; above it they are *not comparable* [1].
    strict_coverage : bool
        False (default): every wear criterion is decided on the band the measurement covers
        and named so; what lies outside is stated as extrapolation. True: the old strict rule,
        a simulated maximum outside the band (or more than ``max_volume_outside`` of the
        volume) makes the criteria *not comparable*.
    wear_u_input_rel, motion_u_input_rel : float or None
        User-stated relative standard uncertainty of the simulated quantities from their inputs
        (e.g. the wear coefficient), ``u_input = rel * |S|`` [1]. None (default) = not stated:
        without an ensemble (``--ensemble``) the V&V 20 criteria are then *not assessed*.
        A stated value is labelled "user-stated" in the report.
    wear_u_num_rel, motion_u_num_rel : float or None
        User-stated relative numerical standard uncertainty, used where neither the simulation
        (``<name>_u``) nor a verification study (``--verification``) gives one [1].
        None (default) = not stated.
    gain_u_rel : float or None
        User-stated relative standard uncertainty of the measuring instrument's gain
        (magnification calibration) [1]; a ``[measurement]`` table may state it. A gain error
        scales the whole measured map, so it adds ``gain_u_rel·|D|`` to u_D of every wear
        quantity, in quadrature with the map's own u. None (default) = not stated.
    field_false_fail_rate : float
        The rate at which a right model fails a field criterion (wear field, axial
        distribution): the Mahalanobis distance is decided against chi² at ``1 -`` it [1].
    field_bins_z, field_bins_theta : int
        Bins of the band in z and theta whose mean depths are the wear field's features (at
        most the grid's layers and angles) [1].
    probe_u_m : float or None
        User-stated standard uncertainty of a radial offset common to the whole measured wear
        map (stylus/probe radius calibration, an offset between the before- and after-wear
        scans) [m]; a ``[measurement]`` table may state it. It adds to u_D of the maximum depth
        as itself and of the worn volume as itself times the band's area; the cylindricity
        removes a uniform offset (no term). None (default) = not stated.
    """

    k: float = checked(2.0, _coverage_factor)
    wear_nrmse_max: float = checked(0.25, _limit)
    wear_r_min: float = checked(0.5, _limit)
    max_angle_error_deg: float = checked(30.0, _limit)
    max_z_error_m: float = checked(3.0e-3, _limit)
    relative_error_max: float = checked(0.30, _limit)
    motion_sg_c_max: float = checked(0.30, _limit)
    max_volume_outside: float = checked(0.10, _fraction)
    strict_coverage: bool = checked(False, _true_or_false)
    wear_u_input_rel: float | None = checked(None, _stated)
    motion_u_input_rel: float | None = checked(None, _stated)
    wear_u_num_rel: float | None = checked(None, _stated)
    motion_u_num_rel: float | None = checked(None, _stated)
    gain_u_rel: float | None = checked(None, _stated)
    probe_u_m: float | None = checked(None, _stated)
    field_false_fail_rate: float = checked(0.05, _rate)
    field_bins_z: int = checked(4, _count)
    field_bins_theta: int = checked(12, _count)

    def __post_init__(self) -> None:
        check_fields(self, "criteria")


#: the keys a ``[measurement]`` table may state (the instrument's calibration terms of u_D)
MEASUREMENT_KEYS = ("gain_u_rel", "probe_u_m")


def load_criteria(path: str | Path | None) -> Criteria:
    """Criteria from a TOML file (keys of :class:`Criteria`, optionally in a ``[criteria]``
    table; the instrument's calibration terms, ``gain_u_rel`` and ``probe_u_m``, also in a
    ``[measurement]`` table)."""
    if path is None:
        return Criteria()
    data = read_toml(path)
    measurement = dict(data.get("measurement", {}) or {})
    data = dict(data.get("criteria", {k: v for k, v in data.items() if k != "measurement"}))
    other = sorted(set(measurement) - set(MEASUREMENT_KEYS))
    if other:
        raise ParameterError(
            f"measurement.{other[0]}: unknown key; the [measurement] table states "
            f"{' and '.join(MEASUREMENT_KEYS)}"
        )
    twice = sorted(set(measurement) & set(data))
    if twice:
        raise ParameterError(
            f"{twice[0]} is stated both in [criteria] and in [measurement]: state it once"
        )
    return from_mapping(Criteria, {**data, **measurement}, where="criteria")
