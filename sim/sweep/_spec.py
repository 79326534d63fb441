"""Sweep specs (TOML): what to run, which parameters vary, how they are sampled.

A spec has a ``[sweep]`` table and one ``[parameters."<dotted name>"]`` table per swept
parameter (docs/sweeps.md)::

    [sweep]
    run = "wear"            # wear | cycle | function
    cycles = 1.2e6
    method = "lhs"          # grid | lhs | sobol | morris
    samples = 32
    seed = 1
    outputs = ["max_wear_depth", "worn_volume"]

    [parameters."mechanism.joint_offset"]
    distribution = "uniform"
    bounds = [0.0, 0.01]

The design (the parameter values of every run) is drawn in the unit hypercube by SALib
(``latin``, ``sobol`` = Saltelli's scheme, ``morris``) and mapped through each parameter's
inverse cumulative distribution; a grid is the Cartesian product of the ``values`` lists. An
``lhs`` sweep may also have grid axes: every grid point then gets the same Latin hypercube.
"""

from __future__ import annotations

import dataclasses
import difflib
import hashlib
import itertools
import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from jointwear.errors import ParameterError
from jointwear.params import check_known_keys
from jointwear.sim.sweep._outputs import FIELDS, available_outputs
from jointwear.sim.sweep._params import ParameterSpec, parse_parameter

__all__ = ["SweepSpec", "Design", "read_spec", "make_design", "METHODS", "RUNS"]

METHODS = ("grid", "lhs", "sobol", "morris")
RUNS = ("wear", "cycle", "function")

_SWEEP_KEYS = {
    "run": "wear | cycle | function",
    "method": "grid | lhs | sobol | morris",
    "cycles": "wear: target cycles; cycle: recorded crank cycles",
    "samples": "base sample size (lhs: runs; sobol: N of Saltelli's N (D + 2); morris: trajectories)",
    "seed": "seed of the design (and of each run's own seed)",
    "outputs": "scalar outputs to keep",
    "keep": "fields to keep per run (wear_depth, contact_force)",
    "settle_cycles": "cycle: crank cycles simulated and discarded before recording (default 1)",
    "max_cycles_simulated": "wear: a run that simulates more crank cycles than this fails "
    "(default 1000; a full 1e6-cycle run simulates about 60-120)",
    "function": "run = function: name of the analytic model",
    "function_args": "run = function: options of the analytic model",
    "levels": "morris: number of grid levels (default 4)",
    "second_order": "sobol: also second-order indices (default false)",
    "confidence": "sobol/morris: confidence level of the intervals (default 0.95)",
    "resamples": "sobol/morris: bootstrap resamples of the intervals (default 100)",
}

_DEFAULT_OUTPUTS = {
    "wear": ("max_wear_depth", "worn_volume", "cylindricity", "max_wear_theta", "max_wear_z"),
    "cycle": ("mean_contact_force", "peak_contact_force", "follower_velocity_rms"),
}


@dataclass(frozen=True)
class SweepSpec:
    """A parsed sweep spec (see the module docstring and docs/sweeps.md)."""

    run: str
    method: str
    parameters: tuple[ParameterSpec, ...]
    cycles: float = 1.0
    samples: int | None = None
    seed: int = 0
    outputs: tuple[str, ...] = ()
    keep: tuple[str, ...] = ()
    settle_cycles: float = 1.0
    max_cycles_simulated: float = 1000.0
    function: str | None = None
    function_args: dict[str, Any] = field(default_factory=dict)
    levels: int = 4
    second_order: bool = False
    confidence: float = 0.95
    resamples: int = 100

    @property
    def names(self) -> list[str]:
        """Swept parameter names, in spec order."""
        return [p.name for p in self.parameters]

    @property
    def grid_parameters(self) -> list[ParameterSpec]:
        """The grid axes."""
        return [p for p in self.parameters if p.is_grid]

    @property
    def random_parameters(self) -> list[ParameterSpec]:
        """The parameters with a distribution."""
        return [p for p in self.parameters if not p.is_grid]

    @property
    def probabilistic_sample(self) -> bool:
        """True if the runs are a sample of the joint input distribution (lhs or sobol, no grid
        axes): their spread is then the propagated input uncertainty of every output."""
        return self.method in ("lhs", "sobol") and not self.grid_parameters

    def describe(self) -> dict[str, Any]:
        """JSON-ready record of the whole spec (provenance, digest)."""
        d = {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}
        d["parameters"] = [p.describe() for p in self.parameters]
        return json.loads(json.dumps(d, default=list))


@dataclass(frozen=True)
class Design:
    """The runs of a sweep.

    Attributes
    ----------
    values : ndarray (n_runs, n_parameters)
        Parameter values of every run (SI), columns in spec order.
    unit : ndarray (n_runs, n_random) or None
        The same runs in the unit hypercube (random parameters only; SALib's analysis input).
    seeds : ndarray (n_runs,)
        Each run's own seed (derived from the spec seed and the run index only).
    """

    values: np.ndarray
    unit: np.ndarray | None
    seeds: np.ndarray

    @property
    def n_runs(self) -> int:
        return int(self.values.shape[0])

    def run_values(self, names: list[str], index: int) -> dict[str, float]:
        """Parameter values of run ``index`` by name."""
        return {n: float(v) for n, v in zip(names, self.values[index], strict=True)}


def _int(value: Any, where: str, lo: int) -> int:
    if (
        isinstance(value, bool)
        or not isinstance(value, (int, float))
        or not float(value).is_integer()
    ):
        raise ParameterError(f"{where}: expected a whole number, got {value!r}")
    if value < lo:
        raise ParameterError(f"{where}: must be >= {lo}, got {value!r}")
    return int(value)


def _names(value: Any, where: str) -> tuple[str, ...]:
    if isinstance(value, str) or not isinstance(value, (list, tuple)):
        raise ParameterError(f"{where}: expected a list of names, got {value!r}")
    if not all(isinstance(v, str) for v in value):
        raise ParameterError(f"{where}: expected a list of names (strings), got {value!r}")
    if len(set(value)) != len(value):
        raise ParameterError(f"{where}: {list(value)} repeats a name")
    return tuple(value)


#: Parameters that change the bearing grid of the wear maps (their z or theta coordinates).
MAP_GRID_PARAMETERS = (
    "joint.n_layers",
    "joint.n_points",
    "joint.bearing_width",
    "joint.axial_grading",
)


def check_stackable_maps(keep: Sequence[str], names: Sequence[str]) -> None:
    """Refuse ``keep = ["wear_depth"]`` when a swept parameter changes the maps' grid."""
    clash = sorted(set(MAP_GRID_PARAMETERS) & set(names))
    if "wear_depth" in keep and clash:
        raise ParameterError(
            f'[sweep] keep = ["wear_depth"] with {", ".join(clash)} swept: the wear maps of '
            "the runs lie on different grids and cannot be stacked; drop wear_depth from keep"
        )


def _check_tables(spec: Mapping[str, Any]):
    """The [sweep] table, run kind, method and [parameters] table of a spec mapping."""
    data = dict(spec)
    unknown = sorted(set(data) - {"sweep", "parameters"})
    if unknown:
        raise ParameterError(
            f"unknown table(s) {', '.join(unknown)}; a sweep spec has [sweep] and "
            '[parameters."<name>"] tables (simulator parameters go in the --params file)'
        )
    if not isinstance(data.get("sweep"), Mapping):
        raise ParameterError("the spec has no [sweep] table")
    sw = dict(data["sweep"])
    check_known_keys("sweep", sw, _SWEEP_KEYS)
    run = sw.get("run", "wear")
    if run not in RUNS:
        raise ParameterError(f"[sweep] run = {run!r}: expected one of {', '.join(RUNS)}")
    method = sw.get("method")
    if method not in METHODS:
        raise ParameterError(
            f"[sweep] method = {method!r}: expected one of {', '.join(METHODS)}"
            + ("" if method is not None else " (method is required)")
        )
    params_tbl = data.get("parameters")
    if not isinstance(params_tbl, Mapping) or not params_tbl:
        raise ParameterError(
            'the spec sweeps no parameter: add [parameters."<dotted name>"] tables, e.g. '
            '[parameters."wear.kw"] with distribution = "lognormal", mean = 9e-16, std = 3e-16'
        )
    return sw, run, method, params_tbl


def _function_model(sw, run: str, parameters, params_tbl):
    """The model and its arguments of a ``run = "function"`` sweep (None, {} otherwise)."""
    model = None
    function_args: dict[str, Any] = {}
    if run == "function":
        from jointwear.sim.sweep._models import check_function_args, get_model

        if "function" not in sw:
            raise ParameterError('[sweep] run = "function" needs function = "<name>"')
        model = get_model(sw["function"])
        function_args = dict(sw.get("function_args", {}) or {})
        check_function_args(model, function_args)
        for p in parameters:
            if p.name not in model.inputs:
                close = difflib.get_close_matches(p.name, model.inputs, n=2)
                raise ParameterError(
                    f'[parameters."{p.name}"]: function {model.name!r} has no input {p.name!r}'
                    + (f" (did you mean {', '.join(close)}?)" if close else "")
                    + f"; its inputs: {', '.join(model.inputs)}"
                )
        missing = [n for n in model.inputs if n not in model.defaults and n not in params_tbl]
        if missing:
            raise ParameterError(
                f"function {model.name!r} needs input(s) {', '.join(missing)}: add "
                f'[parameters."{missing[0]}"]'
            )
    elif "function" in sw or "function_args" in sw:
        raise ParameterError(
            f'[sweep] function/function_args only apply to run = "function", not {run!r}'
        )
    return model, function_args


def _cycles(sw, run: str) -> tuple[Any, Any, Any]:
    """cycles, settle_cycles and max_cycles_simulated of [sweep], checked."""
    cycles = sw.get("cycles", 1.0 if run != "function" else 0.0)
    if run != "function":
        if (
            isinstance(cycles, bool)
            or not isinstance(cycles, (int, float))
            or not (math.isfinite(cycles) and cycles > 0)
        ):
            raise ParameterError(f"[sweep] cycles must be a positive number, got {cycles!r}")
        if run == "wear" and not float(cycles).is_integer():
            raise ParameterError(
                f"[sweep] cycles = {cycles!r}: a wear run needs a whole number of cycles"
            )
    settle = sw.get("settle_cycles", 1.0)
    if isinstance(settle, bool) or not isinstance(settle, (int, float)) or not settle >= 0:
        raise ParameterError(f"[sweep] settle_cycles must be >= 0, got {settle!r}")

    budget = sw.get("max_cycles_simulated", 1000.0)
    if isinstance(budget, bool) or not isinstance(budget, (int, float)) or not budget > 0:
        raise ParameterError(f"[sweep] max_cycles_simulated must be > 0, got {budget!r}")
    if "max_cycles_simulated" in sw and run != "wear":
        raise ParameterError('[sweep] max_cycles_simulated applies to run = "wear" only')
    return cycles, settle, budget


def _outputs_and_fields(sw, run: str, model, parameters):
    """The outputs and the kept fields of [sweep], checked against the run kind."""
    avail = available_outputs(run, model)
    outputs = (
        _names(sw["outputs"], "[sweep] outputs")
        if "outputs" in sw
        else (_DEFAULT_OUTPUTS.get(run) or tuple(avail))
    )
    for o in outputs:
        if o not in avail:
            close = difflib.get_close_matches(o, list(avail), n=2)
            raise ParameterError(
                f"[sweep] outputs: {o!r} is not an output of a {run!r} run"
                + (f" (did you mean {', '.join(close)}?)" if close else "")
                + f"; available: {', '.join(avail)}"
            )
    if not outputs:
        raise ParameterError("[sweep] outputs is empty: name at least one output")
    keep = _names(sw.get("keep", []), "[sweep] keep")
    for k in keep:
        ok = k in FIELDS and (run == "wear" or (run == "cycle" and k == "contact_force"))
        if not ok:
            allowed = (
                [] if run == "function" else (list(FIELDS) if run == "wear" else ["contact_force"])
            )
            raise ParameterError(
                f"[sweep] keep: {k!r} is not a field of a {run!r} run; available: "
                f"{', '.join(allowed) or 'none'}"
            )
    check_stackable_maps(keep, [p.name for p in parameters])
    return outputs, keep


def _sampling_options(sw):
    """seed, levels, resamples, confidence and second_order of [sweep], checked."""
    seed = _int(sw.get("seed", 0), "[sweep] seed", 0)
    levels = _int(sw.get("levels", 4), "[sweep] levels", 2)
    resamples = _int(sw.get("resamples", 100), "[sweep] resamples", 10)
    confidence = sw.get("confidence", 0.95)
    if isinstance(confidence, bool) or not isinstance(confidence, float) or not 0 < confidence < 1:
        raise ParameterError(f"[sweep] confidence must be in (0, 1), got {confidence!r}")
    second = sw.get("second_order", False)
    if not isinstance(second, bool):
        raise ParameterError(f"[sweep] second_order must be true or false, got {second!r}")
    return seed, levels, resamples, confidence, second


def _samples(sw, method: str, parameters) -> int | None:
    """The base sample size (None for a grid), checked against the method and parameters."""
    grid = [p for p in parameters if p.is_grid]
    rand = [p for p in parameters if not p.is_grid]
    samples = None
    if method == "grid":
        if rand:
            raise ParameterError(
                f'[parameters."{rand[0].name}"]: method = "grid" needs values = [...] for every '
                'parameter; it has a distribution (use method = "lhs", "sobol" or "morris", or '
                "give grid values)"
            )
        if "samples" in sw:
            raise ParameterError(
                '[sweep] samples does not apply to method = "grid" (the runs are the product '
                "of the values lists)"
            )
    else:
        if "samples" not in sw:
            raise ParameterError(f'[sweep] method = "{method}" needs samples = <base sample size>')
        samples = _int(sw["samples"], "[sweep] samples", 2)
        if not rand:
            raise ParameterError(
                f'method = "{method}" samples distributions, but every parameter is a grid axis '
                '(values = [...]); use method = "grid" or give a distribution'
            )
        if method in ("sobol", "morris") and grid:
            raise ParameterError(
                f'[parameters."{grid[0].name}"]: a grid axis (values = [...]) cannot be part of a '
                f"{method} design (its estimator needs every parameter sampled its way); give it "
                "a distribution, or set it in the --params file and run one sweep per value"
            )
        if method == "sobol" and samples & (samples - 1):
            raise ParameterError(
                f"[sweep] samples = {samples}: Saltelli's scheme on a Sobol' sequence needs a "
                f"power of 2 (e.g. {1 << samples.bit_length()} or {1 << (samples.bit_length() - 1)})"
            )
        if method == "morris":
            unbounded = [p for p in rand if not p.bounded]
            if unbounded:
                raise ParameterError(
                    f'[parameters."{unbounded[0].name}"]: Morris screening steps across a bounded '
                    f"range; a {unbounded[0].distribution} distribution has none (use uniform or "
                    "truncnormal with bounds)"
                )
    return samples


def read_spec(spec: str | Path | Mapping[str, Any]) -> SweepSpec:
    """Parse a sweep spec from a TOML file or an already-read mapping.

    Checks everything that does not need the simulator's parameters: keys, run kind, method,
    sample sizes, outputs, fields, and that grid axes and distributions fit the method.
    :func:`jointwear.sim.sweep.run_sweep` then checks the parameter names against the simulator.

    Raises
    ------
    ParameterError
        The message names the table/key and says what fixes it.
    """
    if not isinstance(spec, Mapping):
        from jointwear.params import read_toml

        where_file = f"sweep spec '{spec}': "
        data = read_toml(spec)
        try:
            return read_spec(data)
        except ParameterError as exc:
            raise ParameterError(where_file + str(exc)) from None
    sw, run, method, params_tbl = _check_tables(spec)
    parameters = tuple(parse_parameter(str(k), v) for k, v in params_tbl.items())
    model, function_args = _function_model(sw, run, parameters, params_tbl)
    cycles, settle, budget = _cycles(sw, run)
    outputs, keep = _outputs_and_fields(sw, run, model, parameters)
    seed, levels, resamples, confidence, second = _sampling_options(sw)
    samples = _samples(sw, method, parameters)
    return SweepSpec(
        run=run,
        method=method,
        parameters=parameters,
        cycles=float(cycles),
        samples=samples,
        seed=seed,
        outputs=tuple(outputs),
        keep=tuple(keep),
        settle_cycles=float(settle),
        max_cycles_simulated=float(budget),
        function=model.name if model else None,
        function_args=function_args,
        levels=levels,
        second_order=second,
        confidence=float(confidence),
        resamples=resamples,
    )


def _problem(n: int) -> dict[str, Any]:
    return {"num_vars": n, "names": [f"u{i}" for i in range(n)], "bounds": [[0.0, 1.0]] * n}


def make_design(spec: SweepSpec) -> Design:
    """The parameter values of every run (deterministic in the spec)."""
    rand = spec.random_parameters
    grid = spec.grid_parameters
    unit = None
    if rand:
        problem = _problem(len(rand))
        if spec.method == "lhs":
            from SALib.sample import latin

            unit = latin.sample(problem, spec.samples, seed=spec.seed)
        elif spec.method == "sobol":
            from SALib.sample import sobol

            unit = sobol.sample(
                problem, spec.samples, calc_second_order=spec.second_order, seed=spec.seed
            )
        elif spec.method == "morris":
            from SALib.sample import morris

            unit = morris.sample(problem, spec.samples, num_levels=spec.levels, seed=spec.seed)
        unit = np.asarray(unit, dtype=float)
        # a point exactly on 0 or 1 maps to an infinite value for unbounded distributions
        tiny = np.finfo(float).eps
        rvals = np.column_stack(
            [
                p.ppf(np.clip(unit[:, j], tiny, 1 - tiny) if not p.bounded else unit[:, j])
                for j, p in enumerate(rand)
            ]
        )
    grid_points = list(itertools.product(*(p.values for p in grid))) if grid else [()]
    rows = []
    units = []
    for g in grid_points:
        gvals = dict(zip([p.name for p in grid], g, strict=True))
        n = rvals.shape[0] if rand else 1
        for i in range(n):
            rv = dict(zip([p.name for p in rand], rvals[i], strict=True)) if rand else {}
            rows.append([gvals[p.name] if p.is_grid else rv[p.name] for p in spec.parameters])
            if rand:
                units.append(unit[i])
    values = np.asarray(rows, dtype=float).reshape(len(rows), len(spec.parameters))
    seeds = np.array(
        [np.random.SeedSequence([spec.seed, i]).generate_state(1)[0] for i in range(len(rows))],
        dtype=np.int64,
    )
    return Design(values=values, unit=np.asarray(units) if rand else None, seeds=seeds)


def spec_digest(spec: SweepSpec, base: Mapping[str, Any]) -> str:
    """sha256 of everything that determines the runs' results: the spec and the base parameters."""
    text = json.dumps({"spec": spec.describe(), "base": base}, sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()
