"""Human-readable summary of a jointwear file (``jointwear info``)."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from jointwear import io
from jointwear.conventions import describe_status

if TYPE_CHECKING:
    import xarray as xr

__all__ = ["summarise", "describe_study"]


def _fmt_range(values: np.ndarray) -> str:
    if values.size == 0:
        return "empty"
    if values.dtype.kind in "fiu":
        return f"{np.nanmin(values):.6g} .. {np.nanmax(values):.6g}"
    shown = ", ".join(map(str, values[:4]))
    return shown + (", ..." if values.size > 4 else "")


def summarise(path: str | Path, *, validate: bool = True) -> str:
    """Return a text summary of the file at ``path`` (validated against the contract).

    Only the file's header is read (:func:`jointwear.io.load_header`, no xarray), except for a
    verification study, whose summary computes from its data.
    """
    ds = io.load_header(path, validate=validate)
    if ds.attrs.get("jointwear_file") == "verification_study":
        ds = io.load(path, validate=validate)
    lines = [f"file: {path}"]
    status = describe_status(ds)
    if status:
        lines.append(f"status: {status}")
    for key in ("title", "source", "Conventions"):
        if key in ds.attrs:
            lines.append(f"{key}: {ds.attrs[key]}")
    lines.append("dimensions: " + ", ".join(f"{k}={v}" for k, v in ds.sizes.items()))
    lines.append("coordinates:")
    for name, c in ds.coords.items():
        extra = ""
        if name == "theta":
            extra = f"  [zero {c.attrs.get('angle_zero')}, {c.attrs.get('angle_direction')}]"
        lines.append(
            f"  {name} ({c.attrs.get('units', '?')}): {_fmt_range(np.asarray(c.values))}{extra}"
        )
    lines.append("variables:")
    for name, v in ds.data_vars.items():
        dims = ", ".join(v.dims)
        lines.append(
            f"  {name}({dims}) [{v.attrs.get('units', '?')}]: {v.attrs.get('long_name', '')}"
        )
    if ds.attrs.get("jointwear_file") == "verification_study":
        lines.append(describe_study(ds))
    if ds.attrs.get("jointwear_file") == "posterior":  # jointwear sim calibrate
        lines.append("calibration (posterior/prior sd; 'NOT informed': the data do not fix it):")
        lines.extend("  " + t for t in str(ds.attrs.get("identifiability", "")).splitlines())
    if "history" in ds.attrs:
        lines.append("history:")
        lines.extend("  " + h for h in str(ds.attrs["history"]).splitlines())
    prov = io.parse_provenance(ds)
    if prov:
        lines.append("provenance:")
        sw = prov.get("software", {})
        lines.append("  software: " + ", ".join(f"{k} {v}" for k, v in sw.items()))
        if prov.get("command"):
            lines.append(f"  command: {prov['command']}")
        for rec in prov.get("inputs", []):
            lines.append(f"  input: {rec.get('path')} sha256={rec.get('sha256', '?')[:16]}")
        params = prov.get("parameters")
        if params:
            text = json.dumps(params, sort_keys=True)
            lines.append("  parameters: " + (text if len(text) < 400 else text[:400] + " ..."))
    return "\n".join(lines)


def describe_study(study: xr.Dataset) -> str:
    """Text summary of a verification study: one line per quantity with value ± u_num (k = 1),
    its parts and the branch taken, or why it is not assessed."""
    lines = [
        f"verification study: {study.attrs.get('cycles', float('nan')):g} cycles per run, "
        f"h = ΔN {', '.join(f'{v:g}' for v in np.asarray(study['h'].values))}, "
        f"{study.sizes.get('replicate', 0)} replicates per level, "
        f"{study.sizes.get('grid_replicate', 0)} runs on the grid refined "
        f"{study.attrs.get('grid_ratio', float('nan')):g}x; u_num is a standard uncertainty "
        "(k = 1)"
    ]
    for q in study["quantity"].values:
        row = study.sel(quantity=q)
        units = str(row["quantity_units"].values)
        if int(row["assessed"]) != 1:
            lines.append(f"  {q}: not assessed - {row['reason'].values}")
            continue
        v, u = float(row["value"]), float(row["u_num"])
        rel = f" ({100 * u / abs(v):.2g} %)" if v and math.isfinite(v) else ""
        lines.append(
            f"  {q} = {v:.5g} ± {u:.2g} {units}{rel} (stat {float(row['u_stat']):.2g}, "
            f"refinement {float(row['u_refinement']):.2g}, grid {float(row['u_grid']):.2g}; "
            f"{row['branch'].values})"
        )
    if "run_warnings_summary" in study.attrs:  # the runs' own warnings and what they mean
        lines.append(f"run warnings: {study.attrs['run_warnings_summary']}")
        lines.append(f"  for u_num: {study.attrs['run_warnings_verdict']}")
    return "\n".join(lines)
