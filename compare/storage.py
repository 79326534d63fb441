"""A comparison in netCDF: aligned fields, metrics as scalar variables, decisions as CF flags."""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import xarray as xr

import jointwear.compare.metrics as mt
import jointwear.compare.verdicts as vd
from jointwear import io
from jointwear.compare._choices import ALIGN_METHOD
from jointwear.compare._decide import DECISION_COLUMNS, METRIC_COLUMNS
from jointwear.compare.comparison import DEFAULT_AXES, Comparison
from jointwear.compare.criteria import Criteria
from jointwear.compare.sensitivity import SENSITIVITY_COLUMNS
from jointwear.errors import ParameterError
from jointwear.params import from_mapping, to_jsonable

__all__ = ["to_dataset", "load_comparison", "save_comparison", "metrics_table", "compare_files"]


def metrics_table(comparison: Comparison | xr.Dataset) -> pd.DataFrame:
    """The tidy metrics table (quantity, metric, value, units, long_name, definition, basis)."""
    if isinstance(comparison, Comparison):
        return comparison.metrics.copy()
    return load_comparison(comparison).metrics


def json_dumps(criteria: Criteria) -> str:
    """Criteria as JSON text (sorted keys)."""
    return json.dumps(to_jsonable(criteria), sort_keys=True)


def to_dataset(c: Comparison) -> xr.Dataset:
    """Aligned fields, differences, metrics (scalar variables) and decisions in one Dataset."""
    parts = []
    attrs: dict[str, Any] = {}
    for prefix, part in (("wear", c.wear), ("motion", c.motion)):
        if part is None:
            continue
        parts.append(part)
        attrs.update({f"{prefix}_{k}": v for k, v in part.attrs.items() if k != "title"})
    ds = xr.merge(parts, combine_attrs="override", join="outer") if parts else xr.Dataset()
    for row in c.metrics.itertuples():
        name = f"{row.quantity}__{row.metric}"
        extra = {"basis": row.basis} if row.basis else {}
        ds[name] = xr.DataArray(
            float(row.value),
            attrs={
                "units": row.units,
                "long_name": f"{row.long_name} of {row.quantity}",
                "definition": row.definition,
                "quantity": row.quantity,
                "metric": row.metric,
                **extra,
            },
        )
    for i, row in enumerate(c.decisions.itertuples()):
        ds[f"decision_{i:02d}"] = xr.DataArray(
            vd.state_code(row.state),
            attrs={
                "units": "1",
                "long_name": f"validation decision: {row.quantity}",
                "quantity": row.quantity,
                "criterion": row.criterion,
                "value": row.value,
                "basis": row.basis,
                "reason": row.reason,
                "key": row.key,
                "resolution": row.resolution,
                "flag_values": vd.FLAG_VALUES,
                "flag_meanings": vd.FLAG_MEANINGS,
            },
        )
    for i, row in enumerate(c.sensitivity.itertuples()):
        attrs[f"sensitivity_{i:02d}"] = json.dumps(
            {
                "quantity": row.quantity,
                "parameter": row.parameter,
                "S1": row.S1,
                "ST": row.ST,
                "method": row.method,
                "estimator": row.estimator,
            }
        )
    n = vd.counts(c.states)
    attrs.update(
        {
            "title": "jointwear comparison of simulation and measurement",
            "validation_passed": int(c.passed),
            "n_criteria": len(c.decisions),
            "n_pass": n[vd.PASS],
            "n_failed": n[vd.FAIL],
            "n_not_assessed": n[vd.NOT_ASSESSED],
            "n_not_comparable": n[vd.NOT_COMPARABLE],
            "verdict_summary": c.summary(),
            "resolution_summary": c.resolution(),
            "notes": "\n".join(c.notes),
            "partial": "\n".join(c.partial),
            "criteria": json_dumps(c.criteria),
            "data_origin_simulation": c.data_origin.get("simulation", "not stated"),
            "data_origin_measurement": c.data_origin.get("measurement", "not stated"),
        }
    )
    if "synthetic" in c.data_origin.values():
        attrs["data_origin"] = "synthetic"
    ds.attrs = attrs
    return ds


def _state(var: xr.DataArray) -> str:
    meanings = str(var.attrs.get("flag_meanings", vd.FLAG_MEANINGS)).split()
    values = [int(v) for v in np.ravel(var.attrs.get("flag_values", vd.FLAG_VALUES))]
    code = int(var.values)
    if meanings == ["fail", "pass"]:  # files written before the four states
        return vd.PASS if code else vd.FAIL
    return meanings[values.index(code)]


def load_comparison(source: str | Path | xr.Dataset) -> Comparison:
    """Rebuild a :class:`Comparison` from the netCDF written by :func:`save_comparison`."""
    ds = io.load(source) if not isinstance(source, xr.Dataset) else source
    metric_rows = []
    decision_rows = []
    for name, var in ds.data_vars.items():
        if "__" in str(name) and "metric" in var.attrs:
            metric_rows.append(
                {
                    "quantity": var.attrs["quantity"],
                    "metric": var.attrs["metric"],
                    "value": float(var.values),
                    "units": var.attrs.get("units", ""),
                    "long_name": mt.DEFINITIONS.get(var.attrs["metric"], ("",))[0],
                    "definition": var.attrs.get("definition", ""),
                    "basis": var.attrs.get("basis", ""),
                }
            )
        elif str(name).startswith("decision_"):
            state = _state(var)
            decision_rows.append(
                {
                    "quantity": var.attrs.get("quantity", str(name)),
                    "criterion": var.attrs.get("criterion", ""),
                    "value": var.attrs.get("value", ""),
                    "state": state,
                    "basis": var.attrs.get("basis", ""),
                    "reason": var.attrs.get("reason", ""),
                    "passed": state == vd.PASS,
                    "key": var.attrs.get("key", var.attrs.get("quantity", str(name))),
                    "resolution": var.attrs.get("resolution", ""),
                }
            )
    wear_dims = ({"z", "theta"}, {"z_sim", "theta_sim"}, {"run", "z", "theta"})
    wear_vars = [v for v in ds.data_vars if set(ds[v].dims) in wear_dims]
    motion_vars = [v for v in ds.data_vars if "time" in ds[v].dims]
    wear = ds[wear_vars] if wear_vars else None
    motion = ds[motion_vars] if motion_vars else None
    for prefix, part in (("wear_", wear), ("motion_", motion)):
        if part is not None:
            part.attrs = {k[len(prefix) :]: v for k, v in ds.attrs.items() if k.startswith(prefix)}
    try:
        crit = from_mapping(Criteria, json.loads(ds.attrs.get("criteria", "{}")), where="criteria")
    except (ValueError, ParameterError):
        crit = Criteria()
    notes = tuple(n for n in str(ds.attrs.get("notes", "")).splitlines() if n)
    partial = tuple(n for n in str(ds.attrs.get("partial", "")).splitlines() if n)
    sens = [json.loads(v) for k, v in sorted(ds.attrs.items()) if k.startswith("sensitivity_")]
    return Comparison(
        wear=wear,
        motion=motion,
        metrics=pd.DataFrame(metric_rows, columns=METRIC_COLUMNS),
        decisions=pd.DataFrame(decision_rows, columns=DECISION_COLUMNS).astype({"passed": bool}),
        notes=notes,
        criteria=crit,
        data_origin={
            "simulation": str(ds.attrs.get("data_origin_simulation", "not stated")),
            "measurement": str(ds.attrs.get("data_origin_measurement", "not stated")),
        },
        partial=partial,
        sensitivity=pd.DataFrame(
            [{"estimator": "SRC²" if "SRC" in s.get("method", "") else "S1", **s} for s in sens],
            columns=SENSITIVITY_COLUMNS,
        ),
    )


def save_comparison(
    comparison: Comparison,
    path: str | Path,
    *,
    inputs: Sequence[str | Path] = (),
    parents: Sequence[xr.Dataset] = (),
    command: str | None = None,
) -> Path:
    """Write the aligned fields, differences, metrics and decisions to netCDF (atomic, provenance)."""
    ds = comparison.to_dataset()
    return io.save(
        ds,
        path,
        inputs=inputs,
        parameters=comparison.criteria,
        parents=parents,
        command=command,
        source="jointwear compare",
    )


def compare_files(
    sim: Sequence[str | Path],
    meas: Sequence[str | Path],
    out: str | Path,
    *,
    table: str | Path | None = None,
    criteria: Criteria | str | Path | None = None,
    cycles: float | None = None,
    period_s: float | None = None,
    motion_method: str = ALIGN_METHOD,
    variables: Sequence[str] | None = None,
    axes: Sequence[str] | None = DEFAULT_AXES,
    ensemble: Sequence[str | Path] = (),
    verification: Sequence[str | Path] = (),
    allow_other_rig: bool = False,
    warn: Callable[[str], None] | None = None,
    calibration_check: bool = False,
) -> Comparison:
    """Compare files: load simulation and measurement, :func:`compare` them, save the result.

    Parameters
    ----------
    sim, meas : sequence of path
        Simulated and measured netCDF files (wear maps and/or motion records); a foreign CF
        file is read by :func:`jointwear.external.load_for_comparison`.
    out : path
        netCDF to write: aligned fields, differences, metrics and decisions.
    table : path, optional
        Also write the metrics table as CSV.
    criteria : Criteria or path, optional
        Validation criteria, or a TOML file of them (:func:`load_criteria`).
    cycles, period_s, motion_method, variables, axes
        Passed to :func:`jointwear.compare.compare`.
    ensemble : sequence of path
        Ensembles of simulations (``run`` dimension): their spread is the input uncertainty.
    verification : sequence of path
        Verification studies or refinement data (numerical uncertainty).
    allow_other_rig : bool
        Use a study or an ensemble of another rig, labelled (default: refused, exit 3).
    warn : callable, optional
        Receives the warning text for a file from another tool (the CLI prints it on stderr).
    calibration_check : bool
        Compare with data a posterior prediction was calibrated on, labelled as a calibration
        check and never counted as validation (else such data are refused:
        :mod:`jointwear.compare.calibration_use`).

    Returns
    -------
    Comparison
    """
    from jointwear.compare import calibration_use
    from jointwear.compare.comparison import compare
    from jointwear.compare.criteria import load_criteria
    from jointwear.compare.ensemble import as_ensemble
    from jointwear.external import load_for_comparison

    io.check_writable(out)
    if not isinstance(criteria, Criteria):
        criteria = load_criteria(criteria)
    sims = [load_for_comparison(p, role="simulated", warn=warn) for p in sim]
    meass = [load_for_comparison(p, role="measured", warn=warn) for p in meas]
    ens = [io.load(p) for p in ensemble]
    posterior = [
        Path(p).name for p, ds in zip(sim, sims, strict=True) if calibration_use.is_prediction(ds)
    ]
    sims, ens, ens_names, used = calibration_use.prepare(
        sims, sim, meas, ens, [Path(p).name for p in ensemble], calibration_check
    )
    vers = [io.load(p, validate=False) for p in verification]
    result = compare(
        sims,
        meass,
        criteria=criteria,
        cycles=cycles,
        period_s=period_s,
        motion_method=motion_method,
        variables=variables or None,
        axes=axes,
        ensemble=as_ensemble(ens, ens_names) if ens else None,
        verification=vers or None,
        allow_other_rig=allow_other_rig,
    )
    if posterior:
        note = calibration_use.posterior_note(posterior)
        result = dataclasses.replace(result, notes=(*result.notes, note))
    if used:
        result = calibration_use.as_calibration_check(result, used)
    save_comparison(
        result,
        out,
        inputs=[*sim, *meas, *ensemble, *verification],
        parents=[*sims, *meass],
    )
    if table is not None:
        with io.atomic_path(table) as tmp:
            result.metrics.to_csv(tmp, index=False, float_format="%.6g")
    return result
