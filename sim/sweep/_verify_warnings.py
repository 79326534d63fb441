"""The warnings of a verification study's runs and what they mean for its u_num.

Every wear run of a study (:mod:`jointwear.sim.sweep._verify`) may carry the wear module's
warnings (:data:`~jointwear.sim.sweep._run.WARNING_ATTRS`: an update not converged in ΔN, an
accuracy not reached, the contact model outside its validity range). The study file keeps each
run's warnings, counts them per ΔN level and on the grid runs, shows each kind's text once and
says what it means for the study's u_num (:func:`warnings_summary`), so that a study whose
runs warn says so in its output, its file and ``jointwear info``.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

__all__ = ["KINDS", "run_warnings", "warning_counts", "warnings_summary"]

#: The kinds of warnings a run may carry (attribute names of a wear map).
KINDS = ("convergence_warning", "accuracy_warning", "contact_validity_warning")


def run_warnings(where: Sequence[tuple], results: Mapping[int, Any]) -> list[list[str]]:
    """Each run's warnings as ``"kind: message"`` strings (empty for a run without, or not run)."""
    out: list[list[str]] = []
    for i in range(len(where)):
        res = results.get(i)
        ok = res is not None and res.status == "ok"
        out.append([str(w) for w in getattr(res, "warnings", ())] if ok else [])
    return out


def _kind(text: str) -> str:
    return text.split(":", 1)[0].strip()


def warning_counts(
    where: Sequence[tuple], warned: Sequence[Sequence[str]], n_levels: int
) -> tuple[np.ndarray, np.ndarray]:
    """Runs carrying each kind of warning: per ΔN level (kind, level) and on the grid (kind)."""
    level = np.zeros((len(KINDS), n_levels), dtype=np.int32)
    grid = np.zeros(len(KINDS), dtype=np.int32)
    for (kind, lev, _), texts in zip(where, warned, strict=True):
        for k, name in enumerate(KINDS):
            if any(_kind(t) == name for t in texts):
                if kind == "level":
                    level[k, lev] += 1
                else:
                    grid[k] += 1
    return level, grid


def _meaning(name: str, level: np.ndarray, grid: int, levels: Sequence[int]) -> str:
    """What ``name`` warnings at these levels mean for u_num."""
    if name == "convergence_warning":
        if level[0] or grid:
            return (
                f"the finest level (ΔN = {levels[0]}) is itself not converged in ΔN (the explicit "
                "update overshoots), so the value and u_num rest on an unconverged solution and "
                "u_num may understate the error: repeat the study with smaller ΔN levels"
            )
        coarse = ", ".join(str(levels[i]) for i in np.flatnonzero(level))
        return (
            f"the coarser levels (ΔN = {coarse}) lie outside the range where the update is "
            "stable; the least-squares fit includes them, so their departure enters "
            "u_refinement (conservative); the finest level is converged"
        )
    if name == "contact_validity_warning":
        return (
            "the contact model left its validity range in these runs: u_num is the numerical "
            "uncertainty of a model used outside its range, the model-form error is not in it"
        )
    if name == "accuracy_warning":
        return (
            "these runs could not hold their accuracy tolerance; their scatter is in the "
            "replicates (u_stat, sd_run), so u_num covers it"
        )
    return "not interpreted for u_num"


def warnings_summary(
    where: Sequence[tuple],
    warned: Sequence[Sequence[str]],
    levels: Sequence[int],
    replicates: int,
    grid_replicates: int,
) -> tuple[str, str]:
    """(summary, verdict): per kind the count per level and on the grid with its text once,
    and what the warnings mean for u_num ("none: ..." when no run warned)."""
    level, grid = warning_counts(where, warned, len(levels))
    n_runs = len(where)
    lines, verdicts = [], []
    for k, name in enumerate(KINDS):
        total = int(level[k].sum() + grid[k])
        if not total:
            continue
        per = ", ".join(
            f"ΔN {lv}: {int(c)} of {replicates}" for lv, c in zip(levels, level[k], strict=True)
        )
        first = next(t for texts in warned for t in texts if _kind(t) == name)
        lines.append(
            f"{name} in {total} of {n_runs} runs ({per}; grid: {int(grid[k])} of "
            f"{grid_replicates}); e.g. {first.split(':', 1)[1].strip()}"
        )
        verdicts.append(f"{name}: {_meaning(name, level[k], int(grid[k]), levels)}")
    if not lines:
        return "none", "none: no run warned"
    return "; ".join(lines), " ".join(verdicts)


def warning_variables(
    where: Sequence[tuple], results: Mapping[int, Any], spec: Any
) -> tuple[dict[str, tuple], dict[str, str]]:
    """The study file's warning variables (name -> (dims, values, attrs)) and attributes."""
    warned = run_warnings(where, results)
    level, grid = warning_counts(where, warned, len(spec.levels))
    summary, verdict = warnings_summary(
        where, warned, spec.levels, spec.replicates, spec.grid_replicates
    )
    texts = np.array([json.dumps(w) if w else "" for w in warned], dtype=object).astype(str)
    variables = {
        "run_warnings": (
            ("run",),
            texts,
            {"units": "1", "long_name": "the run's warnings as a JSON list of 'kind: message'"},
        ),
        "level_warning_count": (
            ("warning_kind", "level"),
            level,
            {"units": "1", "long_name": "runs of each ΔN level carrying the warning"},
        ),
        "grid_warning_count": (
            ("warning_kind",),
            grid,
            {"units": "1", "long_name": "runs on the next grid carrying the warning"},
        ),
    }
    attrs = {"run_warnings_summary": summary, "run_warnings_verdict": verdict}
    return variables, attrs
