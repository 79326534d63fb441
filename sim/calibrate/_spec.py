"""The calibration spec (TOML): the priors in the ``sim sweep`` grammar and a ``[calibrate]`` table.

::

    [calibrate]
    data = ["wear-2e5.nc"]        # measured wear maps (metrology wearmap) and reported-values
                                  # files (import reported: their quantities carry their cycles)
    cycles = 2e5                  # crank cycles of the data: one value, or one per file
    quantities = ["max_wear_depth", "worn_volume", "cylindricity"]   # the default; "wear_field":
                                  # the band's mean depth in field_bins_z x field_bins_theta bins
    samples = 24                  # training runs of the emulator (Latin hypercube over the prior)
    seed = 1
    u_num_rel = 0.03              # stated u_num / |S| (else: --verification STUDY.nc)

    [[calibrate.values]]          # stated values (reported data, or run = "function"):
    quantity = "max_wear_depth"   # quantity = value ± u at the [calibrate] cycles
    value = 12.1e-6
    u = 0.2e-6
    source = "Table 3 of the paper"

    [parameters."wear.kw"]        # the priors: docs/sweeps.md grammar (a distribution each)
    distribution = "uniform"
    bounds = [4.5e-16, 1.35e-15]

``run = "function"`` (with ``function`` and ``function_args``, as in a sweep spec) calibrates an
analytic model of :mod:`jointwear.sim.sweep._models` instead of the simulator (tests, and the
method on a problem with a closed-form posterior).
"""

from __future__ import annotations

import dataclasses
import json
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from jointwear.errors import ParameterError
from jointwear.params import check_known_keys
from jointwear.sim.calibrate._defaults import PREDICT_SAMPLES

__all__ = [
    "CalibrationSpec",
    "StatedValue",
    "read_calibration_spec",
    "MAP_QUANTITIES",
    "PREDICT_SAMPLES",
]


#: Quantities of a measured wear map, computed within its band (its z range).
MAP_QUANTITIES = ("max_wear_depth", "worn_volume", "cylindricity")
#: the whole-band wear field (a datum per bin; not a default: it adds field_bins_z x
#: field_bins_theta data, each emulated)
FIELD_QUANTITY = "wear_field"

_KEYS = {
    "data": "measured wear maps (metrology wearmap) and reported-values files (import reported, "
    "netCDF or its TOML), paths relative to the spec file",
    "values": "stated values: tables with quantity, value, u (standard uncertainty) and source",
    "cycles": "crank cycles of the data: one value, or one per data file",
    "quantities": "quantities of each map (default max_wear_depth, worn_volume, cylindricity; "
    "also wear_field, the mean depth in field_bins_z x field_bins_theta bins of the band)",
    "field_bins_z": "wear_field: bins of the band in z (default 4, as compare's criteria)",
    "field_bins_theta": "wear_field: bins of the band in theta (default 12, as compare's criteria)",
    "samples": "training runs of the emulator (default 10 per parameter, at least 12)",
    "seed": "seed of the design and of the sampler (default 0)",
    "u_num_rel": "stated numerical uncertainty as a fraction of the simulated value",
    "emulator_max_fraction": "largest emulator error (cross-validated) as a fraction of the "
    "data's u (default 0.5)",
    "walkers": "walkers of the ensemble sampler (default 32)",
    "max_steps": "most sampler steps per walker (default 20000)",
    "rhat_max": "largest split-R-hat across walkers accepted (default 1.01)",
    "ppc_level": "central probability of the posterior predictive interval the data must fall "
    "in (default 0.99)",
    "run": "wear (default) | function",
    "function": 'run = "function": name of the analytic model',
    "function_args": 'run = "function": options of the analytic model',
    "max_cycles_simulated": "wear: a training run simulating more crank cycles than this fails",
}


@dataclass(frozen=True)
class StatedValue:
    """A calibration datum stated in the spec: ``quantity = value ± u`` at ``cycles``.

    Attributes
    ----------
    quantity : str
        A map quantity (``max_wear_depth`` [m], ``worn_volume`` [m³], ``cylindricity`` [m]) or
        an output of the analytic function.
    value, u : float
        Value and its standard uncertainty (k = 1), SI.
    source : str
        Where the value comes from (provenance).
    z : tuple of float
        Layers [m] a map quantity was measured on (``z = [...]``): the quantity is computed on
        these layers of each simulated map, over the whole circle; empty: the simulation's own
        output over the whole bore.
    """

    quantity: str
    value: float
    u: float
    source: str = "stated in the calibration spec"
    z: tuple[float, ...] = ()


@dataclass(frozen=True)
class CalibrationSpec:
    """A parsed calibration spec (see the module docstring and docs/calibration.md)."""

    parameters: tuple[Any, ...]  # ParameterSpec, each with a distribution
    data: tuple[Path, ...] = ()
    values: tuple[StatedValue, ...] = ()
    cycles: tuple[float, ...] = (1.0,)
    quantities: tuple[str, ...] = MAP_QUANTITIES
    field_bins_z: int = 4
    field_bins_theta: int = 12
    samples: int = 12
    seed: int = 0
    u_num_rel: float | None = None
    emulator_max_fraction: float = 0.5
    walkers: int = 32
    max_steps: int = 20000
    rhat_max: float = 1.01
    ppc_level: float = 0.99
    run: str = "wear"
    function: str | None = None
    function_args: dict[str, Any] = field(default_factory=dict)
    max_cycles_simulated: float = 1000.0

    @property
    def names(self) -> list[str]:
        """Calibrated parameter names, in spec order."""
        return [p.name for p in self.parameters]

    def cycles_of(self, i: int) -> float:
        """Crank cycles of data file ``i`` (the stated values use the first)."""
        return self.cycles[i] if len(self.cycles) > 1 else self.cycles[0]

    def describe(self) -> dict[str, Any]:
        """JSON-ready record (provenance)."""
        d = {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}
        d["parameters"] = [p.describe() for p in self.parameters]
        d["values"] = [dataclasses.asdict(v) for v in self.values]
        d["data"] = [str(p) for p in self.data]
        return json.loads(json.dumps(d, default=list))


def _number(value: Any, where: str, *, positive: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ParameterError(f"{where}: expected a finite number, got {value!r}")
    if positive and not value > 0:
        raise ParameterError(f"{where}: must be > 0, got {value!r}")
    return float(value)


def _whole(value: Any, where: str, lo: int) -> int:
    v = _number(value, where)
    if not v.is_integer() or v < lo:
        raise ParameterError(f"{where}: expected a whole number >= {lo}, got {value!r}")
    return int(v)


def _stated(items: Any) -> tuple[StatedValue, ...]:
    if not isinstance(items, list):
        raise ParameterError("[calibrate] values: expected [[calibrate.values]] tables")
    out = []
    for i, t in enumerate(items):
        where = f"[[calibrate.values]] #{i + 1}"
        if not isinstance(t, Mapping):
            raise ParameterError(f"{where}: expected a table with quantity, value, u")
        bad = sorted(set(t) - {"quantity", "value", "u", "source", "z"})
        missing = sorted({"quantity", "value", "u"} - set(t))
        if bad or missing:
            raise ParameterError(
                f"{where}: "
                + (f"unknown key(s) {', '.join(bad)}; " if bad else "")
                + (f"missing {', '.join(missing)}; " if missing else "")
                + "a stated value has quantity, value, u (standard uncertainty), source and z"
            )
        z = t.get("z", [])
        if not isinstance(z, list) or (z and str(t["quantity"]) not in MAP_QUANTITIES):
            raise ParameterError(
                f"{where} z: expected a list of layer positions [m] of a map quantity "
                f"({', '.join(MAP_QUANTITIES)})"
            )
        out.append(
            StatedValue(
                str(t["quantity"]),
                _number(t["value"], f"{where} value"),
                _number(t["u"], f"{where} u", positive=True),
                str(t.get("source", "stated in the calibration spec")),
                tuple(_number(v, f"{where} z") for v in z),
            )
        )
    return tuple(out)


def _data_files(cal: Mapping[str, Any], folder: Path | None) -> tuple[Path, ...]:
    files = cal.get("data", [])
    if isinstance(files, str) or not isinstance(files, list):
        raise ParameterError(f"[calibrate] data: expected a list of file names, got {files!r}")
    paths = []
    for f in files:
        p = Path(str(f))
        if folder is not None and not p.is_absolute():
            p = folder / p
        if not p.is_file():
            raise ParameterError(f"[calibrate] data: no file {p}")
        paths.append(p)
    return tuple(paths)


def _cycles(cal: Mapping[str, Any], n_files: int, run: str) -> tuple[float, ...]:
    if "cycles" not in cal:
        if run == "function":
            return (1.0,)
        raise ParameterError(
            "[calibrate] cycles is required: the crank cycles at which the data were measured"
        )
    c = cal["cycles"]
    values = c if isinstance(c, list) else [c]
    out = tuple(_number(v, "[calibrate] cycles", positive=True) for v in values)
    if run == "wear" and any(not v.is_integer() for v in out):
        raise ParameterError(f"[calibrate] cycles = {c!r}: a wear run needs whole cycles")
    if len(out) > 1 and len(out) != n_files:
        raise ParameterError(
            f"[calibrate] cycles: {len(out)} values for {n_files} data file(s); give one value, "
            "or one per file"
        )
    return out


def _options(cal: Mapping[str, Any], n_par: int) -> dict[str, Any]:
    opts: dict[str, Any] = {
        "samples": _whole(cal.get("samples", max(12, 10 * n_par)), "[calibrate] samples", 4),
        "seed": _whole(cal.get("seed", 0), "[calibrate] seed", 0),
        "walkers": _whole(cal.get("walkers", 32), "[calibrate] walkers", 2 * n_par + 2),
        "max_steps": _whole(cal.get("max_steps", 20000), "[calibrate] max_steps", 200),
        "field_bins_z": _whole(cal.get("field_bins_z", 4), "[calibrate] field_bins_z", 1),
        "field_bins_theta": _whole(
            cal.get("field_bins_theta", 12), "[calibrate] field_bins_theta", 1
        ),
    }
    for key, default in (
        ("emulator_max_fraction", 0.5),
        ("rhat_max", 1.01),
        ("ppc_level", 0.99),
        ("max_cycles_simulated", 1000.0),
    ):
        opts[key] = _number(cal.get(key, default), f"[calibrate] {key}", positive=True)
    if not opts["rhat_max"] > 1.0:
        raise ParameterError("[calibrate] rhat_max must be > 1 (1.01 is the usual limit)")
    if not opts["ppc_level"] < 1.0:
        raise ParameterError("[calibrate] ppc_level must be in (0, 1), e.g. 0.99")
    if "u_num_rel" in cal:
        opts["u_num_rel"] = _number(cal["u_num_rel"], "[calibrate] u_num_rel", positive=True)
    return opts


def read_calibration_spec(spec: str | Path | Mapping[str, Any]) -> CalibrationSpec:
    """Parse a calibration spec from a TOML file or a mapping (paths relative to the file).

    Raises
    ------
    ParameterError
        The message names the table/key and what fixes it.
    """
    folder = None
    if not isinstance(spec, Mapping):
        from jointwear.params import read_toml

        folder = Path(spec).parent
        try:
            return _parse(read_toml(spec), folder)
        except ParameterError as exc:
            raise ParameterError(f"calibration spec '{spec}': {exc}") from None
    return _parse(spec, folder)


def _parse(data: Mapping[str, Any], folder: Path | None) -> CalibrationSpec:
    from jointwear.sim.sweep import parse_parameter

    unknown = sorted(set(data) - {"calibrate", "parameters"})
    if unknown:
        raise ParameterError(
            f"unknown table(s) {', '.join(unknown)}; a calibration spec has [calibrate] and "
            '[parameters."<name>"] tables (simulator parameters go in the --params file)'
        )
    cal = data.get("calibrate")
    if not isinstance(cal, Mapping):
        raise ParameterError("the spec has no [calibrate] table")
    check_known_keys("calibrate", cal, _KEYS)
    table = data.get("parameters")
    if not isinstance(table, Mapping) or not table:
        raise ParameterError(
            'the spec calibrates no parameter: add [parameters."<dotted name>"] tables with a '
            'prior, e.g. [parameters."wear.kw"] distribution = "uniform", bounds = [4.5e-16, '
            "1.35e-15]"
        )
    params = tuple(parse_parameter(str(k), v) for k, v in table.items())
    grid = [p.name for p in params if p.is_grid]
    if grid:
        raise ParameterError(
            f'[parameters."{grid[0]}"]: a calibrated parameter needs a prior (distribution = '
            "...), not grid values; set a fixed value in the --params file instead"
        )
    run = cal.get("run", "wear")
    if run not in ("wear", "function"):
        raise ParameterError(f'[calibrate] run = {run!r}: expected "wear" or "function"')
    files = _data_files(cal, folder)
    values = _stated(cal.get("values", []))
    if not files and not values:
        raise ParameterError(
            "[calibrate] has no data: give data = [measured wear maps] or [[calibrate.values]]"
        )
    if files and run != "wear":
        raise ParameterError('[calibrate] data (wear maps) need run = "wear"')
    quantities = cal.get("quantities", list(MAP_QUANTITIES))
    if isinstance(quantities, str) or not isinstance(quantities, list) or not quantities:
        raise ParameterError(f"[calibrate] quantities: expected a list, got {quantities!r}")
    for q in quantities:
        if q not in (*MAP_QUANTITIES, FIELD_QUANTITY):
            raise ParameterError(
                f"[calibrate] quantities: {q!r} is not a map quantity; known: "
                f"{', '.join((*MAP_QUANTITIES, FIELD_QUANTITY))}"
            )
    if run == "function" and "function" not in cal:
        raise ParameterError('[calibrate] run = "function" needs function = "<name>"')
    return CalibrationSpec(
        parameters=params,
        data=files,
        values=values,
        cycles=_cycles(cal, len(files), run),
        quantities=tuple(quantities),
        run=run,
        function=cal.get("function"),
        function_args=dict(cal.get("function_args", {}) or {}),
        **_options(cal, len(params)),
    )
