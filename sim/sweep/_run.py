"""One run of a sweep: build its inputs, simulate, reduce to outputs; never raises.

:func:`evaluate_run` is the task every executor runs (in-process, on a local cluster or on a
remote dask worker). It depends only on its :class:`RunTask` (spec, base parameters, run values
and the run's own seed), so a run gives the same numbers wherever it runs.
"""

from __future__ import annotations

import logging
import os
import socket
import time
import traceback
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["RunTask", "RunResult", "evaluate_run"]


@dataclass(frozen=True)
class RunTask:
    """Everything one run needs (picklable, sent to a worker)."""

    index: int
    values: dict[str, float]
    seed: int
    spec: Any  # SweepSpec
    sim_params: Any = None  # SimParameters (run = wear | cycle)
    wear_settings: Any = None  # WearSettings (run = wear)


@dataclass
class RunResult:
    """What one run returns: status, outputs, kept fields, error text, timing."""

    index: int
    status: str  # "ok" | "failed"
    outputs: dict[str, float]
    fields: dict[str, np.ndarray]
    error: str = ""
    elapsed: float = 0.0
    host: str = ""
    accuracy_status: str = "not assessed"
    warnings: tuple[str, ...] = ()  # "kind: message", kind an attribute name of the run's file


def _record_cycles(params: Any, h: np.ndarray | None, settle: float, cycles: float) -> Any:
    from jointwear.sim.dynamics import run_cycles

    state = None
    if settle > 0:
        state = run_cycles(params, cycles=settle, wear_depth=h, record=False).state
    return run_cycles(params, cycles=cycles, wear_depth=h, state=state, record=True).dataset


#: Attributes of a wear map that hold a warning (their names are the kinds of warnings).
WARNING_ATTRS = ("accuracy_warning", "convergence_warning", "contact_validity_warning")


class _Quiet(logging.Handler):
    """Keeps the wear module's log records from the console: the run's record holds them."""

    def emit(self, record: logging.LogRecord) -> None:  # pragma: no cover - nothing to do
        pass


def _run_quietly(run: Any) -> Any:
    log = logging.getLogger("jointwear.sim.wear")
    handler, propagate = _Quiet(), log.propagate
    log.addHandler(handler)
    log.propagate = False
    try:
        return run.run()
    finally:
        log.removeHandler(handler)
        log.propagate = propagate


def _wear(
    task: RunTask, on_dataset: Callable[[Any], None] | None = None
) -> tuple[dict[str, float], dict[str, np.ndarray]]:
    from jointwear.errors import SimulationError
    from jointwear.sim.sweep._outputs import (
        MOTION_OUTPUTS,
        force_history,
        motion_outputs,
        wear_outputs,
    )
    from jointwear.sim.sweep._params import apply_values
    from jointwear.sim.wear import DynamicContact, WearRun

    spec = task.spec
    params, settings = apply_values(task.sim_params, task.wear_settings, task.values)
    budget = spec.max_cycles_simulated

    def within_budget(info: dict[str, Any]) -> None:
        # a deterministic cap (cycles, not seconds): the same runs stop on any executor
        if info["cycles_simulated"] > budget:
            raise SimulationError(
                f"wear run stopped after simulating {info['cycles_simulated']:g} crank cycles "
                f"([sweep] max_cycles_simulated = {budget:g}) with only {info['cycles_done']} "
                f"of {info['target']} cycles done: the update interval has shrunk to "
                f"dN = {info['dn']} (the wear-rate field changes by {info['rate_change']:.2f} "
                "per update); raise max_cycles_simulated, or set wear.dn_min (or the wear "
                "scheme's other settings) in the [wear] table of --params"
            )

    run = WearRun(
        DynamicContact(params),
        settings,
        cycles=spec.cycles,
        snapshots=[spec.cycles],
        on_update=within_budget,
    )
    ds = _run_quietly(run)
    if on_dataset is not None:
        on_dataset(ds)
    out = wear_outputs(ds)
    out["__accuracy_status"] = ds.attrs.get("accuracy_status", "not assessed")
    out["__warnings"] = tuple(f"{k}: {ds.attrs[k]}" for k in WARNING_ATTRS if k in ds.attrs)
    fields: dict[str, np.ndarray] = {}
    if "wear_depth" in spec.keep:
        fields["wear_depth"] = np.asarray(ds["wear_depth"].isel(cycles=-1).values)
    if any(o in MOTION_OUTPUTS for o in spec.outputs) or "contact_force" in spec.keep:
        rec = _record_cycles(params, run.wear_depth, 1.0, 1.0)
        out.update(motion_outputs(rec))
        if "contact_force" in spec.keep:
            fields["contact_force"] = force_history(rec, params.mechanism.period, 1.0)
    return out, fields


def _cycle(task: RunTask) -> tuple[dict[str, float], dict[str, np.ndarray]]:
    from jointwear.sim.sweep._outputs import force_history, motion_outputs
    from jointwear.sim.sweep._params import apply_values

    spec = task.spec
    params, _ = apply_values(task.sim_params, task.wear_settings, task.values)
    rec = _record_cycles(params, None, spec.settle_cycles, spec.cycles)
    fields = {}
    if "contact_force" in spec.keep:
        fields["contact_force"] = force_history(rec, params.mechanism.period, spec.cycles)
    return motion_outputs(rec), fields


def _function(task: RunTask) -> tuple[dict[str, float], dict[str, np.ndarray]]:
    from jointwear.sim.sweep._models import evaluate, get_model

    spec = task.spec
    out = evaluate(
        get_model(spec.function), task.values, spec.function_args, seed=task.seed, index=task.index
    )
    return out, {}


_RUNNERS = {"wear": _wear, "cycle": _cycle, "function": _function}


def _error_text(exc: BaseException) -> str:
    """The error and where it was raised (last frame), on one or two lines."""
    tb = traceback.extract_tb(exc.__traceback__)
    where = f" [at {os.path.basename(tb[-1].filename)}:{tb[-1].lineno}]" if tb else ""
    return f"{type(exc).__name__}: {exc}{where}"


def evaluate_run(task: RunTask, on_dataset: Callable[[Any], None] | None = None) -> RunResult:
    """Run one member of a sweep; a failure is returned as ``status = "failed"`` with its error.

    Only the requested outputs are returned (missing ones as NaN). ``on_dataset`` (wear runs):
    called with the run's whole wear map Dataset before it is reduced (``jointwear demo`` keeps
    the study run that is also its compared run).
    """
    t0 = time.perf_counter()
    host = f"{socket.gethostname()}:{os.getpid()}"
    try:
        if on_dataset is not None and task.spec.run == "wear":
            out, fields = _wear(task, on_dataset)
        else:
            out, fields = _RUNNERS[task.spec.run](task)
    except Exception as exc:  # a failing run is recorded, not raised: the sweep goes on
        return RunResult(
            task.index, "failed", {}, {}, _error_text(exc), time.perf_counter() - t0, host
        )
    status = str(out.pop("__accuracy_status", "not assessed"))
    warned = tuple(out.pop("__warnings", ()))
    names = [*task.spec.outputs, *(f"{n}_u" for n in task.spec.outputs)]
    outputs = {name: float(out.get(name, np.nan)) for name in names}
    return RunResult(
        task.index, "ok", outputs, fields, "", time.perf_counter() - t0, host, status, warned
    )
