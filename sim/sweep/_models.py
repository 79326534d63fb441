"""Analytic models for ``run = "function"`` sweeps: the sweep machinery, tested cheaply.

Each model takes its inputs by name and returns named scalar outputs. Their variance-based
sensitivity indices are known in closed form (:func:`analytic_sobol`), so a Sobol sweep through
the same spec parsing, sampling, executors, part files and SALib analysis as a simulator sweep
can be checked against the truth in seconds.

Every model also accepts these options (``[sweep.function_args]``), used by the tests:

``delay`` [s]
    Sleep this long per run (to kill a worker or the client mid-sweep).
``fail_above`` (mapping name -> threshold)
    Raise an error when an input exceeds its threshold (a failing run).
``log`` (path)
    Append ``<run index>`` to this file per evaluation (which runs were computed).
``noise`` (float)
    Add ``noise * N(0, 1)`` drawn from the run's own seed to every output (a stochastic model
    whose result must still be identical whatever the executor).
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from jointwear.errors import ParameterError, SimulationError

__all__ = ["FunctionModel", "MODELS", "get_model", "analytic_sobol"]


@dataclass(frozen=True)
class FunctionModel:
    """An analytic model: named inputs, named outputs with units, and its function."""

    name: str
    inputs: tuple[str, ...]
    outputs: dict[str, str]
    function: Callable[..., dict[str, float]]
    defaults: dict[str, float] = field(default_factory=dict)
    options: tuple[str, ...] = ()
    doc: str = ""


def _ishigami(x: Mapping[str, float], *, a: float = 7.0, b: float = 0.1) -> dict[str, float]:
    x1, x2, x3 = x["x1"], x["x2"], x["x3"]
    return {"y": math.sin(x1) + a * math.sin(x2) ** 2 + b * x3**4 * math.sin(x1)}


def _linear(
    x: Mapping[str, float], *, a: tuple[float, ...] = (1.0, 2.0, 3.0, 4.0)
) -> dict[str, float]:
    y = sum(float(c) * x[f"x{i + 1}"] for i, c in enumerate(a))
    return {"y": y, "y2": 2.0 * y}


MODELS: dict[str, FunctionModel] = {
    "ishigami": FunctionModel(
        "ishigami",
        ("x1", "x2", "x3"),
        {"y": "1"},
        _ishigami,
        options=("a", "b"),
        doc="sin x1 + a sin^2 x2 + b x3^4 sin x1 (inputs uniform on [-pi, pi])",
    ),
    "linear": FunctionModel(
        "linear",
        ("x1", "x2", "x3", "x4"),
        {"y": "1", "y2": "1"},
        _linear,
        defaults={"x1": 0.0, "x2": 0.0, "x3": 0.0, "x4": 0.0},
        options=("a",),
        doc="y = sum a_i x_i (inputs not swept are 0), y2 = 2 y",
    ),
}

_COMMON_OPTIONS = ("delay", "fail_above", "log", "noise")


def get_model(name: str) -> FunctionModel:
    """The analytic model ``name``; the error lists the known ones."""
    try:
        return MODELS[name]
    except KeyError:
        raise ParameterError(
            f"[sweep] function = {name!r} is not known; known: {', '.join(MODELS)}"
        ) from None


def check_function_args(model: FunctionModel, args: Mapping[str, Any]) -> None:
    """Refuse options the model does not take."""
    known = set(model.options) | set(_COMMON_OPTIONS)
    unknown = sorted(set(args) - known)
    if unknown:
        raise ParameterError(
            f"[sweep.function_args]: unknown option(s) {', '.join(unknown)} for function "
            f"{model.name!r}; known: {', '.join(sorted(known))}"
        )


def evaluate(
    model: FunctionModel,
    values: Mapping[str, float],
    args: Mapping[str, Any],
    *,
    seed: int,
    index: int,
) -> dict[str, float]:
    """Evaluate ``model`` at ``values`` with the options ``args`` (see the module docstring)."""
    args = dict(args)
    delay = float(args.pop("delay", 0.0))
    fail_above = args.pop("fail_above", {}) or {}
    log = args.pop("log", None)
    noise = float(args.pop("noise", 0.0))
    if log:
        # one short line per evaluation; O_APPEND keeps lines of concurrent workers whole
        fd = os.open(str(log), os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)
        try:
            os.write(fd, f"{index}\n".encode())
        finally:
            os.close(fd)
    if delay > 0:
        time.sleep(delay)
    for name, limit in fail_above.items():
        if values.get(name, -math.inf) > float(limit):
            raise SimulationError(f"{name} = {values[name]:g} exceeds fail_above = {limit:g}")
    x = {**model.defaults, **values}
    out = model.function(x, **args)
    if noise:
        rng = np.random.default_rng(seed)
        out = {k: v + noise * float(rng.standard_normal()) for k, v in out.items()}
    return out


def analytic_sobol(name: str, **options: Any) -> dict[str, dict[str, float]]:
    """Closed-form first-order (``S1``) and total (``ST``) Sobol indices of a model.

    Ishigami with inputs uniform on [-pi, pi] (Ishigami & Homma 1990; Sobol' & Levitan 1999):
    ``V1 = (1 + b pi^4 / 5)^2 / 2``, ``V2 = a^2 / 8``, ``V13 = b^2 pi^8 (1/18 - 1/50)``,
    ``V = V1 + V2 + V13``. Linear with independent inputs uniform on [0, 1]:
    ``S1_i = ST_i = a_i^2 / sum a_j^2``.

    Returns
    -------
    dict
        ``{"S1": {input: value}, "ST": {input: value}}``.
    """
    if name == "ishigami":
        a, b = float(options.get("a", 7.0)), float(options.get("b", 0.1))
        v1 = 0.5 * (1 + b * math.pi**4 / 5) ** 2
        v2 = a**2 / 8
        v13 = b**2 * math.pi**8 * (1 / 18 - 1 / 50)
        v = v1 + v2 + v13
        return {
            "S1": {"x1": v1 / v, "x2": v2 / v, "x3": 0.0},
            "ST": {"x1": (v1 + v13) / v, "x2": v2 / v, "x3": v13 / v},
        }
    if name == "linear":
        a = np.asarray(options.get("a", (1.0, 2.0, 3.0, 4.0)), dtype=float)
        s = a**2 / np.sum(a**2)
        d = {f"x{i + 1}": float(v) for i, v in enumerate(s)}
        return {"S1": d, "ST": dict(d)}
    raise ParameterError(f"no analytic Sobol indices for {name!r}")
