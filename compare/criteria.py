"""Validation criteria and the uncertainty fractions a user may state (editable from TOML)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from jointwear.errors import ParameterError
from jointwear.params import from_mapping, read_toml

__all__ = ["Criteria", "load_criteria"]

_STATED = ("wear_u_input_rel", "motion_u_input_rel", "wear_u_num_rel", "motion_u_num_rel")


@dataclass(frozen=True)
class Criteria:
    """Validation criteria and uncertainty statements (all editable from a TOML file).

    Parameters
    ----------
    k : float
        Coverage factor of the expanded validation uncertainty ``U_val = k u_val`` [1].
    wear_nrmse_max : float
        Largest acceptable normalised RMSE of the wear map [1].
    wear_r_min : float
        Smallest acceptable Pearson correlation between the simulated and measured wear maps
        [1]. Together with ``wear_nrmse_max`` it makes the shape criterion: a low NRMSE alone
        is also reached by a simulation that predicts almost no wear against a peaky
        measurement.
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
    """

    k: float = 2.0
    wear_nrmse_max: float = 0.25
    wear_r_min: float = 0.5
    max_angle_error_deg: float = 30.0
    max_z_error_m: float = 3.0e-3
    relative_error_max: float = 0.30
    motion_sg_c_max: float = 0.30
    max_volume_outside: float = 0.10
    strict_coverage: bool = False
    wear_u_input_rel: float | None = None
    motion_u_input_rel: float | None = None
    wear_u_num_rel: float | None = None
    motion_u_num_rel: float | None = None

    def __post_init__(self) -> None:
        for f in self.__dataclass_fields__:
            value = getattr(self, f)
            if value is None and f in _STATED:
                continue
            if f == "strict_coverage":
                if not isinstance(value, bool):
                    raise ParameterError(
                        f"criteria.strict_coverage must be true or false, got {value!r}"
                    )
                continue
            if not (isinstance(value, (int, float)) and np.isfinite(value) and value >= 0):
                raise ParameterError(f"criteria.{f} must be a finite number >= 0, got {value!r}")
        for f in _STATED:
            if getattr(self, f) == 0:
                raise ParameterError(
                    f"criteria.{f} = 0 states that the uncertainty is exactly zero, which no "
                    "simulation has; leave it out (not assessed) or state the real fraction"
                )
        if self.k == 0:
            raise ParameterError("criteria.k (coverage factor) must be > 0")
        if self.max_volume_outside >= 1:
            raise ParameterError(
                f"criteria.max_volume_outside is a fraction in [0, 1), got {self.max_volume_outside!r}"
            )


def load_criteria(path: str | Path | None) -> Criteria:
    """Criteria from a TOML file (keys of :class:`Criteria`, optionally in a ``[criteria]`` table)."""
    if path is None:
        return Criteria()
    data = read_toml(path)
    data = data.get("criteria", data)
    return from_mapping(Criteria, data, where="criteria")
