"""Parameter sweeps, ensembles and sensitivity analysis of the simulator, executed on dask.

:func:`run_sweep` reads a sweep spec (:mod:`jointwear.sim.sweep._spec`, docs/sweeps.md), draws
the design, runs every member as one dask task (in-process, on a local cluster of worker
processes, or on an existing cluster by address), writes each finished run at once to
``<out>.parts/`` (so an interrupted sweep resumes with only the missing runs), and returns one
Dataset along ``run`` with the parameter values as coordinates, the outputs as variables and,
for ``method = "sobol"``/``"morris"``, the sensitivity indices computed by SALib.
"""

from __future__ import annotations

import json
import logging
import time
import warnings
from collections.abc import Callable
from concurrent.futures import Executor
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from jointwear.errors import BadInputError, ParameterError
from jointwear.sim.sweep._outputs import (
    ANGLE_UNITS,
    FIELDS,
    available_outputs,
    phase_grid,
    uncertainty_note,
)
from jointwear.sim.sweep._report import circular_summary, sample_size_check
from jointwear.sim.sweep._run import RunResult, RunTask
from jointwear.sim.sweep._spec import (
    Design,
    SweepSpec,
    check_stackable_maps,
    make_design,
    read_spec,
    spec_digest,
)

__all__ = ["run_sweep", "read_spec", "SweepSpec", "make_design", "to_grid", "STATUS"]

#: Run status flags (``status`` variable).
STATUS = {"ok": 0, "failed": 1, "not_run": 2}


def _base(
    spec: SweepSpec, params: Any, wear: Any, base: str | None = None
) -> tuple[Any, Any, dict[str, Any], list]:
    """(SimParameters, WearSettings, JSON record, input files) of the base of every run."""
    from jointwear.params import from_mapping, read_toml, to_jsonable
    from jointwear.sim.wear import WearSettings

    if spec.run == "function":
        if params is not None:
            raise BadInputError('--params does not apply to run = "function" sweeps')
        return None, None, {}, []
    from jointwear.sim.parameters import (
        DEFAULT_PARAMETER_SET,
        PARAMETER_SETS,
        SimParameters,
        load_parameters,
    )

    inputs = []
    table: dict[str, Any] = {}
    if params is None:
        try:
            sim = PARAMETER_SETS[base or DEFAULT_PARAMETER_SET]
        except KeyError as exc:
            raise ParameterError(f"base: {exc.args[0]}") from None
    elif isinstance(params, SimParameters):
        sim = params
    else:
        path = Path(params)
        table = read_toml(path)
        sim = load_parameters(path, base=base or DEFAULT_PARAMETER_SET)
        inputs.append(path)
    if wear is None:
        wear = from_mapping(WearSettings, dict(table.get("wear", {}) or {}), where="wear")
    if spec.run != "wear" and table.get("wear"):
        raise BadInputError(f"--params '{params}': a [wear] table applies to run = \"wear\" only")
    record = {"parameters": to_jsonable(sim)}
    if spec.run == "wear":
        record["wear"] = to_jsonable(wear)
    return sim, wear, record, inputs


def _check_feasible(spec: SweepSpec, sim: Any, wear: Any) -> None:
    """Each swept value at its extremes must be a valid parameter (impossible bounds -> error)."""
    from jointwear.sim.sweep._params import apply_values, check_simulator_names

    check_simulator_names(spec.parameters, sim, wear, run=spec.run)
    for p in spec.parameters:
        if p.is_grid:
            probes = [(v, f"value {v:g}") for v in p.values]
        elif p.bounded:
            probes = [(v, f"bound {v:g}") for v in p.bounds]
        else:
            lo, hi = p.ppf(np.array([1e-3, 1 - 1e-3]))
            probes = [(lo, f"0.1 % quantile {lo:g}"), (hi, f"99.9 % quantile {hi:g}")]
        for value, what in probes:
            try:
                apply_values(sim, wear, {p.name: value})
            except ParameterError as exc:
                hint = "" if p.is_grid or p.bounded else " (use truncnormal with bounds)"
                raise ParameterError(
                    f'[parameters."{p.name}"]: its {what} is not a valid value{hint}: {exc}'
                ) from None
    check_stackable_maps(spec.keep, spec.names)  # also for a SweepSpec built directly


def _param_coord(spec: SweepSpec, p: Any, values: np.ndarray) -> xr.Variable:
    from jointwear.sim.sweep._params import DERIVED, parameter_units

    units = "1" if spec.run == "function" else parameter_units(p.name)
    attrs = {"units": units, "long_name": f"swept parameter {p.name}"}
    if p.name in DERIVED:
        attrs["comment"] = DERIVED[p.name][1]
    d = p.describe()
    d.pop("name")
    attrs["sweep_definition"] = json.dumps(d)
    return xr.Variable("run", values, attrs)


def _field_coords(spec: SweepSpec, sim: Any) -> dict[str, xr.DataArray]:
    coords: dict[str, Any] = {}
    if "wear_depth" in spec.keep:
        from jointwear.sim.wearmap import BearingGrid, wear_map_dataset

        grid = BearingGrid.from_params(sim)
        empty = wear_map_dataset(np.zeros((1, *grid.shape)), np.ones(1), grid, cylindricity=False)
        coords["z"], coords["theta"] = empty["z"], empty["theta"]
    if "contact_force" in spec.keep:
        cyc = 1.0 if spec.run == "wear" else spec.cycles
        coords["cycle_phase"] = xr.DataArray(
            phase_grid(cyc),
            dims="cycle_phase",
            attrs={"units": "1", "long_name": "crank cycles since the start of the record"},
        )
    return coords


def assemble(
    spec: SweepSpec,
    design: Design,
    results: dict[int, RunResult],
    lost: dict[int, str],
    *,
    sim: Any = None,
) -> xr.Dataset:
    """The sweep's Dataset along ``run`` from the runs' results (missing runs: ``not_run``)."""
    from jointwear.sim.sweep._models import get_model

    n = design.n_runs
    model = get_model(spec.function) if spec.run == "function" else None
    avail = available_outputs(spec.run, model)
    coords: dict[str, Any] = {
        "run": xr.Variable("run", np.arange(n), {"long_name": "sweep member", "units": "1"}),
        "run_seed": xr.Variable(
            "run",
            design.seeds,
            {"long_name": "the run's own seed (spec seed, run index)", "units": "1"},
        ),
    }
    for j, p in enumerate(spec.parameters):
        coords[p.name] = _param_coord(spec, p, design.values[:, j])
    coords.update(_field_coords(spec, sim))
    ds = xr.Dataset(coords=coords)
    status = np.full(n, STATUS["not_run"], dtype=np.int8)
    error = np.full(n, "", dtype=object)
    elapsed = np.full(n, np.nan)
    host = np.full(n, "", dtype=object)
    for i, msg in lost.items():
        error[i] = f"not run: {msg}"
    for i, r in results.items():
        status[i] = STATUS[r.status]
        error[i] = r.error
        elapsed[i] = r.elapsed
        host[i] = r.host
    for name in spec.outputs:
        units, long_name = avail[name]
        value, u = (np.full(n, np.nan) for _ in range(2))
        for i, r in results.items():
            if r.status == "ok":
                value[i] = r.outputs.get(name, np.nan)
                u[i] = r.outputs.get(f"{name}_u", np.nan)
        attrs = {"units": units, "long_name": long_name, "ancillary_variables": f"{name}_u"}
        if units == ANGLE_UNITS:
            attrs.update(circular_summary(value))
        ds[name] = xr.Variable("run", value, attrs)
        ds[f"{name}_u"] = xr.Variable(
            "run",
            u,
            {
                "units": units,
                "long_name": f"standard uncertainty of {name}",
                "coverage_factor": 1,
                "comment": uncertainty_note(name),
            },
        )
    accuracy = np.full(n, "", dtype=object)
    warned = np.full(n, "", dtype=object)
    for i, r in results.items():
        accuracy[i] = r.accuracy_status if r.status == "ok" else ""
        warned[i] = json.dumps(list(r.warnings)) if r.warnings else ""
    ds["accuracy_status"] = xr.Variable(
        "run",
        accuracy.astype(str),
        {
            "units": "1",
            "long_name": "accuracy_status of the run (reached, not reached, not assessed; "
            "empty if it did not finish)",
        },
    )
    ds["run_warnings"] = xr.Variable(
        "run",
        warned.astype(str),
        {
            "units": "1",
            "long_name": "the run's warnings as a JSON list of 'kind: message' (empty: none)",
        },
    )
    for name in spec.keep:
        dims, units, long_name = FIELDS[name]
        shape = tuple(ds.sizes[d] for d in dims)
        arr = np.full((n, *shape), np.nan)
        for i, r in results.items():
            if r.status == "ok" and name in r.fields:
                arr[i] = r.fields[name]
        ds[name] = xr.Variable(("run", *dims), arr, {"units": units, "long_name": long_name})
    ds["status"] = xr.Variable(
        "run",
        status,
        {
            "units": "1",
            "long_name": "outcome of the run",
            "flag_values": np.array(list(STATUS.values()), dtype=np.int8),
            "flag_meanings": " ".join(STATUS),
        },
    )
    ds["error"] = xr.Variable(
        "run", error.astype(str), {"units": "1", "long_name": "error of a failed run (empty if ok)"}
    )
    ds["run_time"] = xr.Variable(
        "run", elapsed, {"units": "s", "long_name": "wall time of the run on its worker"}
    )
    ds["worker"] = xr.Variable(
        "run", host.astype(str), {"units": "1", "long_name": "host:pid that computed the run"}
    )
    n_failed = int(np.sum(status == STATUS["failed"]))
    n_missing = int(np.sum(status == STATUS["not_run"]))
    ds.attrs.update(
        {
            "title": f"jointwear sweep: {spec.method} design of {spec.run} runs",
            "data_origin": "synthetic" if spec.run == "function" else "simulated",
            "sweep_run": spec.run,
            "sweep_method": spec.method,
            "sweep_parameters": list(spec.names),
            "sweep_grid_parameters": [p.name for p in spec.grid_parameters],
            "sweep_outputs": list(spec.outputs),
            "sweep_spec": json.dumps(spec.describe(), sort_keys=True),
            "probabilistic_sample": spec.probabilistic_sample,
            "probabilistic_sample_note": (
                "the runs are a sample of the joint input distribution: the spread of an output "
                "over run is its propagated input uncertainty"
                if spec.probabilistic_sample
                else "the runs are not a sample of an input distribution (grid axes or a Morris "
                "design): their spread is NOT an input uncertainty"
            ),
            "n_runs": n,
            "ensemble_complete": bool(np.all(status == STATUS["ok"])),
            "n_ok": int(np.sum(status == STATUS["ok"])),
            "n_failed": n_failed,
            "n_not_run": n_missing,
        }
    )
    if spec.run != "function":
        ds.attrs["cycles"] = spec.cycles
    return ds


_log = logging.getLogger("jointwear.sim.sweep")

#: Why Sobol/Morris indices of an angle output are refused.
_ANGLE_REFUSED = (
    "an angle (circular: a variance-based index depends on where the cut at 0/360 lies); "
    "request its cosine and sine (max_wear_theta_cos, max_wear_theta_sin), the documented "
    "transform"
)


def _salib_problem(spec: SweepSpec) -> dict[str, Any]:
    names = [p.name for p in spec.random_parameters]
    return {"num_vars": len(names), "names": names, "bounds": [[0.0, 1.0]] * len(names)}


def _quietly(fn: Callable[[], Any]) -> tuple[Any, list[str]]:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        out = fn()
    return out, sorted({str(w.message).strip() for w in caught})


def _sobol_indices(ds, spec: SweepSpec, problem, not_assessed: dict, notes: list) -> None:
    """Add the Sobol indices of every output to ``ds`` (NaN, and named in ``not_assessed``,
    for an output with failed runs or in degrees)."""
    names = problem["names"]
    from SALib.analyze import sobol

    keys = ("S1", "S1_conf", "ST", "ST_conf")
    table = {k: np.full((len(spec.outputs), len(names)), np.nan) for k in keys}
    keys2 = ("S2", "S2_conf") if spec.second_order else ()
    table.update({k: np.full((len(spec.outputs), len(names), len(names)), np.nan) for k in keys2})
    for i, out in enumerate(spec.outputs):
        y = np.asarray(ds[out].values, dtype=float)
        if ds[out].attrs.get("units") == ANGLE_UNITS:
            not_assessed[out] = _ANGLE_REFUSED
            continue
        if not np.all(np.isfinite(y)):
            not_assessed[out] = f"{int(np.sum(~np.isfinite(y)))} run(s) failed or not run"
            continue
        res, caught = _quietly(
            lambda y=y: sobol.analyze(
                problem,
                y,
                calc_second_order=spec.second_order,
                num_resamples=spec.resamples,
                conf_level=spec.confidence,
                seed=spec.seed,
            )
        )
        notes += [f"{out}: {c}" for c in caught]
        for k in keys + keys2:
            table[k][i] = np.asarray(res[k], dtype=float)
    long = {
        "S1": "first-order Sobol index",
        "ST": "total-effect Sobol index",
        "S2": "second-order Sobol index of the pair (parameter, parameter_2)",
    }
    for k in keys2:
        attrs = {"units": "1", "long_name": long["S2"]}
        if k.endswith("_conf"):
            attrs["long_name"] = (
                f"half-width of the {100 * spec.confidence:g} % bootstrap confidence interval "
                "of the second-order Sobol index"
            )
        ds[f"sobol_{k}"] = xr.Variable(("output", "parameter", "parameter_2"), table[k], attrs)
    for k in keys:
        base = k.split("_")[0]
        attrs = {"units": "1", "long_name": long[base]}
        if k.endswith("_conf"):
            attrs["long_name"] = (
                f"half-width of the {100 * spec.confidence:g} % bootstrap confidence interval "
                f"of the {long[base]}"
            )
        else:
            attrs["ancillary_variables"] = f"sobol_{k}_conf"
        ds[f"sobol_{k}"] = xr.Variable(("output", "parameter"), table[k], attrs)
    ds.attrs["sensitivity_method"] = (
        f"SALib sobol.analyze (Saltelli 2002 / Jansen estimators), N = {spec.samples}, "
        f"{spec.resamples} bootstrap resamples"
    )


def _morris_measures(
    ds, spec: SweepSpec, design: Design, problem, not_assessed: dict, notes: list
) -> None:
    """Add the Morris measures of every output to ``ds`` (as :func:`_sobol_indices`)."""
    names = problem["names"]
    from SALib.analyze import morris

    for out in spec.outputs:
        y = np.asarray(ds[out].values, dtype=float)
        units = ds[out].attrs["units"]
        angle = units == ANGLE_UNITS
        if angle or not np.all(np.isfinite(y)):
            not_assessed[out] = (
                _ANGLE_REFUSED
                if angle
                else f"{int(np.sum(~np.isfinite(y)))} run(s) failed or not run"
            )
            res = {
                k: np.full(len(names), np.nan) for k in ("mu", "mu_star", "sigma", "mu_star_conf")
            }
        else:
            res, caught = _quietly(
                lambda y=y: morris.analyze(
                    problem,
                    design.unit,
                    y,
                    num_resamples=spec.resamples,
                    conf_level=spec.confidence,
                    num_levels=spec.levels,
                    seed=spec.seed,
                )
            )
            notes += [f"{out}: {c}" for c in caught]
        for k, long in (
            ("mu_star", "Morris mu*: mean absolute elementary effect"),
            (
                "mu_star_conf",
                f"half-width of the {100 * spec.confidence:g} % bootstrap "
                "confidence interval of Morris mu*",
            ),
            ("sigma", "Morris sigma: standard deviation of the elementary effects"),
            ("mu", "Morris mu: mean elementary effect"),
        ):
            ds[f"{out}_morris_{k}"] = xr.Variable(
                "parameter",
                np.asarray(res[k], dtype=float),
                {
                    "units": units,
                    "long_name": f"{long} of {out}",
                    "comment": "elementary effects per unit of the parameter's range "
                    "(unit hypercube)",
                },
            )
    ds.attrs["sensitivity_method"] = (
        f"SALib morris.analyze, {spec.samples} trajectories, {spec.levels} levels"
    )


def sensitivity(ds: xr.Dataset, spec: SweepSpec, design: Design) -> xr.Dataset:
    """Add SALib's Sobol indices (``method = "sobol"``) or Morris measures (``"morris"``).

    Sobol: ``sobol_S1``, ``sobol_ST`` (and ``*_conf``, the half-width of the bootstrap
    confidence interval at ``spec.confidence``) with dims (``output``, ``parameter``). Morris:
    ``morris_mu_star``, ``morris_mu_star_conf``, ``morris_sigma``, ``morris_mu`` per output
    (``<output>_`` prefix, output units: the elementary effects are per unit of the parameter's
    range on the unit hypercube). An output with failed or missing runs has NaN indices and is
    named in the attribute ``sensitivity_not_assessed`` (never a silently biased estimate).
    """
    if spec.method not in ("sobol", "morris"):
        return ds
    problem = _salib_problem(spec)
    names = problem["names"]
    not_assessed: dict[str, str] = {}
    notes: list[str] = []
    if spec.method == "sobol":
        _sobol_indices(ds, spec, problem, not_assessed, notes)
    else:
        _morris_measures(ds, spec, design, problem, not_assessed, notes)
    ds = ds.assign_coords(
        parameter=xr.Variable("parameter", np.array(names), {"long_name": "swept parameter"})
    )
    if spec.method == "sobol":
        ds = ds.assign_coords(
            output=xr.Variable("output", np.array(spec.outputs), {"long_name": "sweep output"})
        )
        if spec.second_order:
            ds = ds.assign_coords(
                parameter_2=xr.Variable(
                    "parameter_2", np.array(names), {"long_name": "swept parameter (second)"}
                )
            )
    if not_assessed:
        ds.attrs["sensitivity_not_assessed"] = json.dumps(not_assessed, sort_keys=True)
    check = sample_size_check(ds, spec.method, spec.samples)
    ds.attrs["sensitivity_recommended_samples"] = check["recommended_samples"]
    if not check["ok"]:
        msg = (
            f"{spec.method} with samples = {spec.samples} is too small for the indices asked: "
            + "; ".join(check["problems"])
            + f"; use samples = {check['recommended_samples']} (the indices in this file are "
            "not reliable)"
        )
        ds.attrs["sensitivity_sample_warning"] = msg
        _log.warning("%s", msg)
    if notes:
        ds.attrs["sensitivity_warnings"] = json.dumps(sorted(set(notes)))
    return ds


def to_grid(ds: xr.Dataset) -> xr.Dataset:
    """A pure grid sweep reshaped to one dimension per parameter (instead of ``run``).

    Raises
    ------
    BadInputError
        The sweep is not a pure grid (``method != "grid"``).
    """
    if ds.attrs.get("sweep_method") != "grid":
        raise BadInputError(
            f'to_grid: only a method = "grid" sweep can be reshaped to parameter axes, this one '
            f"is {ds.attrs.get('sweep_method')!r}"
        )
    names = list(ds.attrs["sweep_parameters"])
    out = ds.drop_vars(["run_seed"]).set_index(run=names).unstack("run")
    for n in names:
        out[n].attrs.update(ds[n].attrs)
    return out


def run_sweep(
    spec: str | Path | SweepSpec | dict,
    *,
    out: str | Path | None = None,
    params: Any = None,
    wear: Any = None,
    workers: int | None = None,
    scheduler: str | Executor | None = None,
    resume: bool = False,
    on_progress: Callable[[dict[str, Any]], None] | None = None,
    base: str | None = None,
) -> xr.Dataset:
    """Run a parameter sweep / ensemble and return it as one Dataset along ``run``.

    Parameters
    ----------
    spec : path, mapping or SweepSpec
        The sweep spec (TOML file; docs/sweeps.md).
    out : path, optional
        Result file (netCDF). Each finished run is first written to ``<out>.parts/`` (removed
        once ``out`` is written); without ``out`` nothing is written and nothing can resume.
    params : path or SimParameters, optional
        Base parameters of every run (a ``--params`` TOML, possibly with a ``[wear]`` table,
        over the named set ``base``); default the named set ``base``.
    wear : WearSettings, optional
        Base wear settings (default: the ``[wear]`` table of ``params``, else the defaults).
    workers : int, optional
        0: run in this process (no dask); N: a local dask cluster of N single-threaded worker
        processes (default: one per core).
    scheduler : str or Executor, optional
        Address of a running dask scheduler, or a :class:`concurrent.futures.Executor` of the
        caller's (each run one task); ``workers`` is then ignored.
    resume : bool
        Continue an interrupted sweep writing ``out``: only runs without a part file are
        computed (the spec and base parameters must be the same).
    on_progress : callable, optional
        Called after each run with ``{"done", "failed", "total", "computed", "executor"}``.
    base : str, optional
        Named parameter set (``PARAMETER_SETS``) of the base, e.g. ``"slider_crank"``; default
        :data:`~jointwear.sim.DEFAULT_PARAMETER_SET`.

    Returns
    -------
    Dataset
        Along ``run``: parameter values (coordinates), outputs, ``status`` (ok/failed/not_run),
        ``error``; Sobol/Morris indices for those methods.

    Raises
    ------
    ParameterError
        A bad spec (named entry), impossible bounds, unknown parameter names.
    BadInputError
        Unreachable scheduler, resume of another sweep, unwritable ``out``.

    Examples
    --------
    >>> from jointwear.sim import run_sweep  # below: y = x1 + 2 x2 on a grid, in-process
    >>> sweep = {"run": "function", "function": "linear", "method": "grid"}
    >>> grid = {"x1": {"values": [0.0, 1.0]}, "x2": {"values": [0.0, 0.5]}}
    >>> run_sweep({"sweep": sweep, "parameters": grid}, workers=0)["y"].values.tolist()
    [0.0, 1.0, 1.0, 2.0]
    """

    if resume and out is None:
        raise BadInputError("resume needs the sweep's result file (out=/--out)")
    spec_file = [Path(spec)] if isinstance(spec, (str, Path)) else []
    spec = spec if isinstance(spec, SweepSpec) else read_spec(spec)
    sim, wear, base_record, inputs = _base(spec, params, wear, base)
    if spec.run != "function":
        _check_feasible(spec, sim, wear)
    if workers is not None and workers < 0:
        raise BadInputError(f"workers must be >= 0, got {workers}")
    design = make_design(spec)
    digest = spec_digest(spec, base_record)
    record = {"spec": spec.describe(), "base": base_record}
    names = spec.names
    tasks = [
        RunTask(i, design.run_values(names, i), int(design.seeds[i]), spec, sim, wear)
        for i in range(design.n_runs)
    ]

    def build(results: dict[int, RunResult], lost: dict[int, str]) -> xr.Dataset:
        return sensitivity(assemble(spec, design, results, lost, sim=sim), spec, design)

    how = Execution(out, resume, workers, scheduler, on_progress)
    inputs = [*spec_file, *inputs]
    return run_and_save(tasks, design.values, build, how, digest, record, inputs, "sim.sweep")


@dataclass(frozen=True)
class Execution:
    """Where the runs of a sweep or study go (see :func:`run_sweep`): the result file, resume,
    executor (``workers``, ``scheduler``: an address or a caller's executor) and progress."""

    out: str | Path | None
    resume: bool
    workers: int | None
    scheduler: Any
    on_progress: Callable[[dict[str, Any]], None] | None


def run_and_save(
    tasks: list[RunTask],
    values: np.ndarray,
    build: Callable[[dict[int, RunResult], dict[int, str]], xr.Dataset],
    how: Execution,
    digest: str,
    record: dict[str, Any],
    inputs: list[Path],
    source: str,
) -> xr.Dataset:
    """Run ``tasks`` through the part store and an executor, build the result and write it.

    A finished result of the same ``digest`` in ``how.out`` is returned as it is on resume.

    Each finished run goes at once to ``<out>.parts/`` (checked against ``digest`` and its row
    of ``values`` on resume), the runs are executed in the order given, ``build(results, lost)``
    makes the Dataset, which gets ``sweep_digest``, ``runs_computed_now``, ``runs_resumed`` and
    ``executor`` and is written atomically to ``out``; the part files are removed once it is
    written and no run was lost. Shared by :func:`run_sweep` and
    :func:`jointwear.sim.verify_wear`; ``source`` names the producer (``"sim.sweep"``).
    """
    from jointwear import io
    from jointwear._version import source_attribute

    out, resume, on_progress = how.out, how.resume, how.on_progress
    if resume and _already_complete(out, digest):
        ds = io.load(out)
        ds.attrs.update(runs_computed_now=0, runs_resumed=len(tasks))
        ds.attrs["executor"] = "none (all runs resumed)"
        return ds

    store = None
    results: dict[int, RunResult] = {}
    if out is not None:
        from jointwear.sim.sweep._store import PartStore

        io.check_writable(out, what="--out")
        store = PartStore(out, digest, record, resume=resume)
    lost: dict[int, str] = {}
    finished = False
    try:
        if store is not None:
            results = store.load(values)
        todo = [t for t in tasks if t.index not in results]
        state = {
            "done": len(results),
            "failed": sum(r.status == "failed" for r in results.values()),
            "total": len(tasks),
            "computed": 0,
            "resumed": len(results),
            "executor": "",
            "started": time.monotonic(),
        }

        def started(what: str) -> None:
            state["executor"] = what
            if on_progress:
                on_progress(dict(state))

        def got(res: RunResult) -> None:
            if store is not None:
                store.write(res, values[res.index])
            results[res.index] = res
            state["done"] += 1
            state["computed"] += 1
            state["failed"] += res.status == "failed"
            if on_progress:
                on_progress(dict(state))

        def gone(index: int, reason: str) -> None:
            lost[index] = reason

        execute_runs(
            todo,
            workers=how.workers,
            scheduler=how.scheduler,
            on_result=got,
            on_lost=gone,
            on_start=started,
        )
        ds = build(results, lost)
        ds.attrs["sweep_digest"] = digest
        ds.attrs["runs_computed_now"] = state["computed"]
        ds.attrs["runs_resumed"] = state["resumed"]
        ds.attrs["executor"] = state["executor"] or "none (all runs resumed)"
        if out is not None:
            io.save(ds, out, inputs=inputs, parameters=record, source=source_attribute(source))
            finished = not lost
    finally:
        if store is not None:
            store.close(remove=finished)
    return ds


def _already_complete(out: str | Path | None, digest: str) -> bool:
    """True if ``out`` is the finished result of this very sweep (nothing left to resume)."""
    from jointwear import io
    from jointwear.sim.sweep._store import parts_dir

    if out is None or not Path(out).exists() or parts_dir(out).exists():
        return False
    try:
        attrs = io.load(out, validate=False).attrs
    except BadInputError:
        return False
    return attrs.get("sweep_digest") == digest and attrs.get("n_not_run") == 0


def execute_runs(tasks: list[RunTask], **kwargs: Any) -> None:
    """Indirection so that tests can count what an executor is given."""
    from jointwear.sim.sweep._exec import execute

    execute(tasks, **kwargs)
