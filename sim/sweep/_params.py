"""Swept parameters of a sweep spec: names, units, distributions, and applying values to a run.

A swept parameter is named by its dotted name in the ``--params`` TOML (``"joint.bearing_radius"``,
``"friction.dynamic_coefficient"``) or in its ``[wear]`` table (``"wear.kw"``), plus the derived
``"joint.radial_clearance"`` (sets ``joint.bearing_radius = joint.journal_radius + value``).
Values are SI, as in the parameter files. Overrides are applied by rebuilding the frozen
parameter dataclasses (:func:`jointwear.params.replace_nested`), so every value goes through the
same checks as a parameter file.
"""

from __future__ import annotations

import dataclasses
import difflib
import math
import typing
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from jointwear.errors import ParameterError

__all__ = [
    "DISTRIBUTIONS",
    "ParameterSpec",
    "parse_parameter",
    "numeric_fields",
    "parameter_units",
    "check_simulator_names",
    "apply_values",
]

#: Distributions a swept parameter may follow, and the keys each one needs.
DISTRIBUTIONS: dict[str, tuple[str, ...]] = {
    "uniform": ("bounds",),
    "normal": ("mean", "std"),
    "lognormal": ("mean", "std"),
    "truncnormal": ("mean", "std", "bounds"),
}

#: Derived parameters (not fields of the dataclasses): name -> (target field, doc).
DERIVED = {
    "joint.radial_clearance": (
        "joint.bearing_radius",
        "radial clearance [m]; sets joint.bearing_radius = joint.journal_radius + value",
    ),
}

# Units of the numeric simulator fields, by field name (SI, as in the parameter files).
_UNITS_BY_NAME = {
    "crank_speed_rpm": "min-1",
    "initial_crank_angle_deg": "degree",
    "gravity": "m s-2",
    "kw": "m2 N-1",
    "journal_modulus": "Pa",
    "bearing_modulus": "Pa",
    "axial_stiffness": "N m-1.5",
    "foundation_thickness": "m",
    "stick_velocity": "m s-1",
    "slide_velocity": "m s-1",
    "impact_velocity_floor": "m s-1",
    "max_step": "s",
    "min_step": "s",
    "output_interval": "s",
    "baumgarte": "s-1",
    "atol": "rad",
    "max_increment": "m",
    "onset_penetration": "m",
    "joint_offset": "m",
    "axial_clearance": "m",
    "radial_clearance": "m",
    "tilt_stiffness": "N m rad-1",
    "tilt_damping": "N m s rad-1",
}
_UNITS_BY_SUFFIX = (
    ("_length", "m"),
    ("_radius", "m"),
    ("_width", "m"),
    ("_mass", "kg"),
    ("_inertia", "kg m2"),
    ("_coefficient", "1"),
    ("_poisson", "1"),
    ("_cycles", "1"),
    ("_fraction", "1"),
)
_DIMENSIONLESS = {
    "exponent",
    "restitution",
    "rtol",
    "tol",
    "dn",
    "dn_min",
    "dn_max",
    "n_layers",
    "n_points",
    "axial_grading",
    "reject_factor",
    "noise_floor",
}


def parameter_units(name: str) -> str:
    """Units of a swept simulator parameter (by its dotted name).

    Raises
    ------
    ParameterError
        A field whose units are not known (add it to the table above).
    """
    field = name.rpartition(".")[2]
    if field in _UNITS_BY_NAME:
        return _UNITS_BY_NAME[field]
    if field in _DIMENSIONLESS:
        return "1"
    for suffix, units in _UNITS_BY_SUFFIX:
        if field.endswith(suffix):
            return units
    raise ParameterError(f"units of parameter '{name}' are not known to the sweep module")


@dataclass(frozen=True)
class ParameterSpec:
    """One swept parameter: a grid axis (``values``) or a distribution.

    Attributes
    ----------
    name : str
        Dotted name (``"mechanism.joint_offset"``), or a function argument for ``run = "function"``.
    values : tuple of float or None
        Grid values (a grid axis); None for a distributed parameter.
    distribution : str or None
        ``"uniform"`` (``bounds``), ``"normal"`` (``mean``, ``std``), ``"lognormal"`` (``mean``
        and ``std`` of the quantity itself, not of its logarithm) or ``"truncnormal"`` (``mean``,
        ``std`` of the parent normal, cut to ``bounds``).
    bounds : tuple of float or None
    mean, std : float or None
    """

    name: str
    values: tuple[float, ...] | None = None
    distribution: str | None = None
    bounds: tuple[float, float] | None = None
    mean: float | None = None
    std: float | None = None

    @property
    def is_grid(self) -> bool:
        """True for a grid axis (``values``)."""
        return self.values is not None

    @property
    def bounded(self) -> bool:
        """True if the distribution has finite support (uniform, truncnormal)."""
        return self.distribution in ("uniform", "truncnormal")

    def _scipy(self) -> Any:
        from scipy import stats

        d = self.distribution
        if d == "uniform":
            lo, hi = self.bounds
            return stats.uniform(loc=lo, scale=hi - lo)
        if d == "normal":
            return stats.norm(loc=self.mean, scale=self.std)
        if d == "lognormal":
            s2 = math.log1p((self.std / self.mean) ** 2)
            return stats.lognorm(s=math.sqrt(s2), scale=self.mean * math.exp(-s2 / 2))
        if d == "truncnormal":
            lo, hi = self.bounds
            a, b = (lo - self.mean) / self.std, (hi - self.mean) / self.std
            return stats.truncnorm(a, b, loc=self.mean, scale=self.std)
        raise ParameterError(f"parameter '{self.name}' has no distribution")

    def ppf(self, u: np.ndarray) -> np.ndarray:
        """Values at the probabilities ``u`` in [0, 1] (the inverse cumulative distribution)."""
        return np.asarray(self._scipy().ppf(np.asarray(u, dtype=float)), dtype=float)

    def describe(self) -> dict[str, Any]:
        """JSON-ready record (for provenance and the spec digest)."""
        return {k: v for k, v in dataclasses.asdict(self).items() if v is not None}


def _number(value: Any, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ParameterError(f"{where}: expected a number, got {value!r}")
    value = float(value)
    if not math.isfinite(value):
        raise ParameterError(f"{where}: expected a finite number, got {value!r}")
    return value


def parse_parameter(name: str, table: Any) -> ParameterSpec:
    """Parse one ``[parameters."<name>"]`` table of a sweep spec.

    Raises
    ------
    ParameterError
        Unknown keys, a table with both ``values`` and ``distribution``, missing or extra
        distribution keys, impossible bounds (``lo >= hi``), ``std <= 0``, a lognormal with
        ``mean <= 0``, or a truncnormal whose mean lies outside its bounds.
    """
    where = f'[parameters."{name}"]'
    if not isinstance(table, Mapping):
        raise ParameterError(
            f"{where}: expected a table (values = [...] or distribution = ...), got {table!r}"
        )
    known = {"values", "distribution", "bounds", "mean", "std"}
    unknown = sorted(set(table) - known)
    if unknown:
        raise ParameterError(
            f"{where}: unknown key(s) {', '.join(unknown)}; known: {', '.join(sorted(known))}"
        )
    if "values" in table:
        extra = sorted(set(table) - {"values"})
        if extra:
            raise ParameterError(
                f"{where}: a grid axis (values = [...]) takes no {', '.join(extra)}; give either "
                "values or a distribution"
            )
        vals = table["values"]
        if isinstance(vals, (str, bytes)) or not isinstance(vals, Sequence) or not vals:
            raise ParameterError(f"{where}: values must be a non-empty list of numbers")
        values = tuple(_number(v, f"{where} values[{i}]") for i, v in enumerate(vals))
        if len(set(values)) != len(values):
            raise ParameterError(f"{where}: values {list(values)} repeat a value")
        return ParameterSpec(name, values=values)
    dist = table.get("distribution")
    if dist is None:
        raise ParameterError(
            f"{where}: give values = [...] (a grid axis) or distribution = "
            f"{' | '.join(DISTRIBUTIONS)}"
        )
    if dist not in DISTRIBUTIONS:
        close = difflib.get_close_matches(str(dist), list(DISTRIBUTIONS), n=1)
        hint = f" (did you mean {close[0]!r}?)" if close else ""
        raise ParameterError(
            f"{where}: unknown distribution {dist!r}{hint}; known: {', '.join(DISTRIBUTIONS)}"
        )
    needed = set(DISTRIBUTIONS[dist])
    given = set(table) - {"distribution"}
    if needed - given:
        raise ParameterError(
            f"{where}: distribution {dist!r} needs {', '.join(sorted(needed - given))}"
        )
    if given - needed:
        raise ParameterError(
            f"{where}: distribution {dist!r} takes {', '.join(sorted(needed))}, not "
            f"{', '.join(sorted(given - needed))}"
        )
    kw: dict[str, Any] = {}
    if "bounds" in needed:
        b = table["bounds"]
        if isinstance(b, (str, bytes)) or not isinstance(b, Sequence) or len(b) != 2:
            raise ParameterError(f"{where}: bounds must be [low, high], got {b!r}")
        lo, hi = (_number(v, f"{where} bounds") for v in b)
        if not lo < hi:
            raise ParameterError(f"{where}: bounds [{lo:g}, {hi:g}] are impossible (low >= high)")
        kw["bounds"] = (lo, hi)
    if "mean" in needed:
        kw["mean"] = _number(table["mean"], f"{where} mean")
        kw["std"] = _number(table["std"], f"{where} std")
        if not kw["std"] > 0:
            raise ParameterError(f"{where}: std must be > 0, got {kw['std']:g}")
    if dist == "lognormal" and not kw["mean"] > 0:
        raise ParameterError(f"{where}: a lognormal quantity needs mean > 0, got {kw['mean']:g}")
    if dist == "truncnormal" and not kw["bounds"][0] <= kw["mean"] <= kw["bounds"][1]:
        raise ParameterError(
            f"{where}: mean {kw['mean']:g} lies outside the bounds {list(kw['bounds'])}"
        )
    return ParameterSpec(name, distribution=dist, **kw)


def numeric_fields(sim_params: Any, wear_settings: Any) -> dict[str, type]:
    """Dotted names of the numeric simulator and wear fields that a sweep may vary -> type."""
    out: dict[str, type] = {}
    for section in dataclasses.fields(sim_params):
        obj = getattr(sim_params, section.name)
        if not dataclasses.is_dataclass(obj):
            continue
        hints = typing.get_type_hints(type(obj))
        for f in dataclasses.fields(obj):
            if hints[f.name] in (float, int):
                out[f"{section.name}.{f.name}"] = hints[f.name]
    hints = typing.get_type_hints(type(wear_settings))
    for f in dataclasses.fields(wear_settings):
        tp = hints[f.name]
        if tp in (float, int) or tp == (float | None):
            out[f"wear.{f.name}"] = int if tp is int else float
    for name in DERIVED:
        out[name] = float
    return out


def _all_names(sim_params: Any, wear_settings: Any) -> list[str]:
    names = []
    for section in dataclasses.fields(sim_params):
        obj = getattr(sim_params, section.name)
        if dataclasses.is_dataclass(obj):
            names += [f"{section.name}.{f.name}" for f in dataclasses.fields(obj)]
    names += [f"wear.{f.name}" for f in dataclasses.fields(wear_settings)]
    return names + list(DERIVED)


def check_simulator_names(
    specs: Sequence[ParameterSpec], sim_params: Any, wear_settings: Any, *, run: str
) -> None:
    """Refuse unknown, non-numeric, conflicting or (for integers) non-integral swept parameters.

    Raises
    ------
    ParameterError
        Naming the entry and listing close matches of an unknown name.
    """
    numeric = numeric_fields(sim_params, wear_settings)
    every = _all_names(sim_params, wear_settings)
    for p in specs:
        where = f'[parameters."{p.name}"]'
        if p.name not in every:
            close = difflib.get_close_matches(p.name, every, n=4, cutoff=0.6)
            field = p.name.rpartition(".")[2]
            close += [n for n in every if n.endswith("." + field) and n not in close]
            hint = f"; did you mean {', '.join(close)}?" if close else ""
            raise ParameterError(
                f"{where}: unknown parameter '{p.name}'{hint} Swept names are the dotted names "
                "of the --params TOML (mechanism.*, joint.*, contact.*, friction.*, solver.*) "
                "and wear.*"
            )
        if p.name not in numeric:
            raise ParameterError(
                f"{where}: '{p.name}' is not a number; a sweep varies numeric parameters only "
                "(set it in the --params file instead)"
            )
        if p.name.startswith("wear.") and run != "wear":
            raise ParameterError(f'{where}: wear parameters only apply to run = "wear"')
        if numeric[p.name] is int:
            if not p.is_grid or any(not float(v).is_integer() for v in p.values):
                raise ParameterError(
                    f"{where}: '{p.name}' is an integer; give it as a grid of whole numbers "
                    "(values = [...]), not a distribution"
                )
    names = {p.name for p in specs}
    for derived, (target, _) in DERIVED.items():
        if derived in names and target in names:
            raise ParameterError(
                f"[parameters]: '{derived}' and '{target}' both set {target}; sweep only one"
            )


def apply_values(sim_params: Any, wear_settings: Any, values: Mapping[str, float]) -> tuple:
    """The simulator parameters and wear settings of one run: base with ``values`` applied.

    Parameters
    ----------
    sim_params : SimParameters
        Base parameters.
    wear_settings : WearSettings
        Base wear settings.
    values : mapping of str to float
        Dotted name -> value (SI).

    Returns
    -------
    tuple
        ``(SimParameters, WearSettings)``.

    Raises
    ------
    ParameterError
        A value the parameter dataclasses refuse (their message names the field).
    """
    from jointwear.sim.mechanisms import replace_checked

    numeric = numeric_fields(sim_params, wear_settings)
    sim_changes: dict[str, Any] = {}
    wear_changes: dict[str, Any] = {}
    clearance = None
    for name, value in values.items():
        value = float(value)
        if numeric.get(name) is int:
            value = int(value)
        if name == "joint.radial_clearance":
            clearance = value
        elif name.startswith("wear."):
            wear_changes[name[5:]] = value
        else:
            sim_changes[name] = value
    if clearance is not None:
        journal = sim_changes.get("joint.journal_radius", sim_params.joint.journal_radius)
        sim_changes["joint.bearing_radius"] = float(journal) + clearance
    try:
        p = replace_checked(sim_params, sim_changes) if sim_changes else sim_params
        w = dataclasses.replace(wear_settings, **wear_changes) if wear_changes else wear_settings
    except (TypeError, ValueError) as exc:
        if isinstance(exc, ParameterError):
            raise
        raise ParameterError(str(exc)) from None
    return p, w
