"""Verification study of a wear run (``jointwear sim verify``): u_num from replicates, ΔN and grid.

The wear-cycle dynamics are chaotic: single runs differ by their start, so a refinement study on
single runs has a random sign of convergence. The study therefore runs, as one sweep of dask
tasks (the machinery of :func:`jointwear.sim.run_sweep`: part files, resume, local or remote
cluster):

* at each of ``>= 4`` wear-update intervals ΔN (the refinement parameter ``h``; the fixed update
  scheme, so that ΔN is the only thing that changes), ``replicates`` runs whose measurement
  starts at different phases of the motion (``wear.initial_settle_cycles`` = base, base + 1, ...);
* at the finest ΔN, ``replicates`` runs on the next bearing grid (``joint.n_layers`` and
  ``joint.n_points`` times ``grid``) for the grid term.

Each run keeps its final wear map and its scalar outputs (:data:`QUANTITIES`); the study file
(:func:`study_dataset`) holds them all with, per quantity, the Eça-Hoekstra fit on the replicate
means and u_num = sqrt(u_stat^2 + u_refinement^2 + u_grid^2) (:mod:`jointwear.refinement`).
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
from collections.abc import Callable, Mapping, Sequence
from concurrent.futures import Executor
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from jointwear.errors import BadInputError, ParameterError
from jointwear.sim.sweep._verify_spec import VerifySpec
from jointwear.sim.sweep._verify_warnings import KINDS, warning_variables

__all__ = [
    "VerifySpec",
    "read_verify_spec",
    "verify_wear",
    "study_dataset",
    "band_quantities",
    "QUANTITIES",
]

#: Quantities of the study: sweep output name -> circular period (None: linear quantity).
QUANTITIES: dict[str, float | None] = {
    "max_wear_depth": None,
    "worn_volume": None,
    "cylindricity": None,
    "max_wear_theta": 360.0,
    "max_wear_z": None,
    "follower_velocity_rms": None,
    "rms_contact_force": None,
    "peak_contact_force": None,
    "max_penetration": None,
}

_KEYS = {
    "cycles": "wear cycles of every run (the --cycles option overrides it)",
    "levels": "wear-update intervals ΔN [cycles], >= 4 distinct whole numbers",
    "replicates": "runs per level, starting at different phases of the motion (>= 2)",
    "grid": "refinement factor of the next grid (n_layers and n_points times it), >= 2",
    "grid_replicates": "runs at the next grid (default: replicates)",
    "formal_order": "formal order of the ΔN update (1: explicit Euler)",
    "phases": "start phase of each replicate [cycles] (default 0, 1, 2, ...)",
    "seed": "draw the replicates' start phases from this seed instead",
}


def read_verify_spec(spec: str | Path | Mapping[str, Any], *, cycles: float | None) -> VerifySpec:
    """A study spec from a TOML file (``[verify]`` table) or mapping; ``cycles`` overrides.

    Raises
    ------
    ParameterError
        Unknown keys (with the known ones), bad values; the message names the key.
    """
    where = ""
    if not isinstance(spec, Mapping):
        from jointwear.params import read_toml

        where = f"study spec '{spec}': "
        spec = read_toml(spec)
    data = dict(spec)
    if set(data) != {"verify"}:
        raise ParameterError(
            f"{where}expected one [verify] table, got {', '.join(map(str, data)) or 'nothing'}"
        )
    table = dict(data["verify"] or {})
    bad = sorted(set(table) - set(_KEYS))
    if bad:
        raise ParameterError(
            f"{where}[verify]: unknown key(s) {', '.join(bad)}; known: "
            + "; ".join(f"{k} ({v})" for k, v in _KEYS.items())
        )
    if cycles is not None:
        table["cycles"] = cycles
    if "cycles" not in table:
        raise ParameterError(f"{where}[verify] has no cycles: give cycles = N or --cycles N")
    try:
        if "levels" in table:
            return VerifySpec(**table)
        return VerifySpec.default(**table)
    except ParameterError as exc:
        raise ParameterError(f"{where}[verify] {exc}") from None
    except TypeError as exc:
        raise ParameterError(f"{where}[verify]: {exc}") from None


# --- the runs ------------------------------------------------------------------------------

#: Columns of the run table (the sweep's "parameter values" of each run).
_COLUMNS = ("wear.dn", "wear.initial_settle_cycles", "joint.n_layers", "joint.n_points")


def _run_table(spec: VerifySpec, sim: Any, wear: Any) -> tuple[np.ndarray, list[tuple]]:
    """Values of every run (rows, :data:`_COLUMNS`) and its place (kind, level, replicate)."""
    nl, nd = sim.joint.n_layers, sim.joint.n_points
    s0 = float(wear.initial_settle_cycles)
    phase = spec.start_phases()
    rows, where = [], []
    for i, dn in enumerate(spec.levels):
        for r in range(spec.replicates):
            rows.append((dn, s0 + phase[r], nl, nd))
            where.append(("level", i, r))
    for r in range(spec.grid_replicates):
        rows.append((spec.levels[0], s0 + phase[r], nl * spec.grid, nd * spec.grid))
        where.append(("grid", 0, r))
    return np.asarray(rows, dtype=float), where


def _sweep_spec(spec: VerifySpec, table: np.ndarray, wear: Any) -> Any:
    from jointwear.sim.sweep._params import ParameterSpec
    from jointwear.sim.sweep._spec import SweepSpec

    params = tuple(
        ParameterSpec(name, values=tuple(sorted(set(table[:, j].tolist()))))
        for j, name in enumerate(_COLUMNS)
    )
    # the fixed scheme simulates 1 + settle cycles per update: a budget that cannot bite
    per_update = 1.0 + float(wear.settle_cycles)
    budget = per_update * math.ceil(spec.cycles / spec.levels[0]) + table[:, 1].max() + 10
    return SweepSpec(
        run="wear",
        method="grid",
        parameters=params,
        cycles=spec.cycles,
        seed=0,
        outputs=tuple(QUANTITIES),
        keep=("wear_depth",),
        max_cycles_simulated=max(1000.0, budget),
    )


def study_tasks(spec: VerifySpec, sim: Any, wear: Any) -> tuple[np.ndarray, list[tuple], list]:
    """The runs of a study: values (:data:`_COLUMNS`), places (kind, level, replicate) and
    their :class:`~jointwear.sim.sweep._run.RunTask`, the longest first (so that no worker is
    left with a long run at the end). Run 0 is replicate 0 of the finest level."""
    from jointwear.sim.sweep._run import RunTask

    values, where = _run_table(spec, sim, wear)
    sweep = _sweep_spec(spec, values, wear)
    tasks = [
        RunTask(i, dict(zip(_COLUMNS, map(float, values[i]), strict=True)), i, sweep, sim, wear)
        for i in range(len(values))
    ]
    tasks.sort(key=lambda t: -_relative_cost(values[t.index], values[0]))
    return values, where, tasks


def _digest(record: Mapping[str, Any]) -> str:
    return hashlib.sha256(json.dumps(record, sort_keys=True, default=str).encode()).hexdigest()


def verify_wear(
    params: Any = None,
    *,
    cycles: float | None = None,
    spec: str | Path | Mapping[str, Any] | VerifySpec | None = None,
    levels: Sequence[int] | None = None,
    replicates: int | None = None,
    grid: int | None = None,
    seed: int | None = None,
    band: tuple[float, float] | None = None,
    wear: Any = None,
    workers: int | None = None,
    scheduler: str | Executor | None = None,
    out: str | Path | None = None,
    resume: bool = False,
    on_progress: Callable[[dict[str, Any]], None] | None = None,
) -> xr.Dataset:
    """Run a verification study of the wear simulation and return the study Dataset.

    Parameters
    ----------
    params : path or SimParameters, optional
        The rig (a ``--params`` TOML, possibly with a ``[wear]`` table; default ``zhang2023``).
    cycles : float, optional
        Wear cycles of every run (overrides the spec's).
    spec : path, mapping or VerifySpec, optional
        The study (``[verify]`` table, docs/sim-wear.md); default :meth:`VerifySpec.default`.
    levels, replicates, grid : optional
        Override the spec's ΔN levels [cycles], replicates per level, grid refinement factor.
    seed : int, optional
        Draw the replicates' start phases from this seed (overrides the spec's ``phases`` and
        ``seed``; :class:`VerifySpec`).
    band : (z_min, z_max), optional
        Axial band [m] whose maximum depth, volume and cylindricity are added as quantities
        (:func:`study_dataset`).
    wear : WearSettings, optional
        Base wear settings (kw, settling); the scheme is set to ``"fixed"`` with each level's ΔN.
    workers, scheduler :
        As for :func:`jointwear.sim.run_sweep` (0: in this process; N: a local dask cluster;
        an address: a running scheduler); ``scheduler`` may also be a
        :class:`concurrent.futures.Executor` of the caller's (``jointwear demo`` passes its
        pool of worker processes), which runs each run as one task.
    out : path, optional
        Study file (netCDF); runs go to ``<out>.parts/`` first, so an interrupted study resumes.
    resume : bool
        Continue an interrupted study writing ``out``.
    on_progress : callable, optional
        Called after each run with ``{"done", "failed", "total", "computed", "executor"}``.

    Returns
    -------
    Dataset
        The study (:func:`study_dataset`).

    Raises
    ------
    ParameterError, BadInputError
        A bad spec or parameter (named), an unwritable ``out``, resume of another study.
    """
    from jointwear.sim.sweep._driver import Execution, _base, run_and_save
    from jointwear.sim.sweep._params import apply_values

    if workers is not None and workers < 0:
        raise BadInputError(f"workers must be >= 0, got {workers}")
    if resume and out is None:
        raise BadInputError("resume needs the study's result file (out=/--out)")
    spec_file = [Path(spec)] if isinstance(spec, (str, Path)) else []
    if isinstance(spec, VerifySpec):
        vspec = dataclasses.replace(spec, cycles=cycles) if cycles is not None else spec
    elif spec is None:
        if cycles is None:
            raise BadInputError("verify_wear needs cycles (or a spec that gives them)")
        vspec = VerifySpec.default(cycles)
    else:
        vspec = read_verify_spec(spec, cycles=cycles)
    changes = {
        k: v
        for k, v in (("levels", levels), ("replicates", replicates), ("grid", grid))
        if v is not None
    }
    if seed is not None:
        changes.update(seed=seed, phases=None)
    if replicates is not None and "grid_replicates" not in changes:
        changes["grid_replicates"] = replicates
    if changes:
        vspec = dataclasses.replace(vspec, **changes)
    sim, base_wear, base_record, inputs = _base(_WearKind, params, wear)
    base_wear = dataclasses.replace(base_wear, scheme="fixed")
    base_record["wear"]["scheme"] = "fixed"
    values, where, tasks = study_tasks(vspec, sim, base_wear)
    for row in {tuple(r) for r in values}:  # refuse impossible runs before starting any
        apply_values(sim, base_wear, dict(zip(_COLUMNS, row, strict=True)))
    if band is not None:
        band = (float(band[0]), float(band[1]))
        _band_units(band)  # refuse a bad band before any run
        z = np.asarray(_grid_coords(sim)["z"].values)
        if np.sum((z >= band[0]) & (z <= band[1])) < 2:
            raise BadInputError(
                f"band {1e3 * band[0]:g} .. {1e3 * band[1]:g} mm holds fewer than two layers of "
                f"the wear grid (z = {1e3 * z.min():g} .. {1e3 * z.max():g} mm, "
                f"{z.size} layers); it needs two or more (widen it)"
            )
    record = {"study": vspec.describe(), "base": base_record, "band_m": band}
    digest = _digest(record)

    def build(results: dict[int, Any], lost: dict[int, str]) -> xr.Dataset:
        ds = study_dataset(vspec, sim, values, where, results, lost, band=band)
        ds.attrs["parameters_json"] = json.dumps(base_record, sort_keys=True)
        return ds

    how = Execution(out, resume, workers, scheduler, on_progress)
    inputs = [*spec_file, *inputs]
    return run_and_save(tasks, values, build, how, digest, record, inputs, "sim.sweep.verify")


def _relative_cost(row: np.ndarray, base: np.ndarray) -> float:
    """Relative cost of a run: its updates, times (grid points)^0.4 (measured: a 4x finer grid
    costs 1.7x per cycle, benchmarks/results/sim_cycle.json)."""
    points = row[2] * row[3] / (base[2] * base[3])
    return float(points**0.4 / row[0])


class _WearKind:
    """Stands for a ``run = "wear"`` sweep spec where :func:`jointwear.sim.sweep._driver._base` asks."""

    run = "wear"


# --- the study file ------------------------------------------------------------------------


def _units() -> dict[str, tuple[str, str]]:
    from jointwear.sim.sweep._outputs import available_outputs

    avail = available_outputs("wear")
    return {q: avail[q] for q in QUANTITIES}


def _grid_coords(sim: Any, suffix: str = "") -> dict[str, xr.DataArray]:
    from jointwear.sim.wearmap import BearingGrid, wear_map_dataset

    grid = BearingGrid.from_params(sim)
    empty = wear_map_dataset(np.zeros((1, *grid.shape)), np.ones(1), grid, cylindricity=False)
    z, th = empty["z"], empty["theta"]
    if not suffix:
        return {"z": z, "theta": th}
    return {
        "z" + suffix: xr.DataArray(z.values, dims="z" + suffix, attrs=z.attrs),
        "theta" + suffix: xr.DataArray(th.values, dims="theta" + suffix, attrs=th.attrs),
    }


def _study_coords(spec, qnames: list[str], values: np.ndarray) -> dict[str, xr.Variable]:
    """Coordinates of a study: ΔN levels (h), replicates, grid replicates, quantities."""
    nlev, nrep, ng = len(spec.levels), spec.replicates, spec.grid_replicates
    return {
        "level": xr.Variable("level", np.arange(nlev), {"units": "1", "long_name": "ΔN level"}),
        "h": xr.Variable(
            "level",
            np.asarray(spec.levels, dtype=float),
            {
                "units": "1",
                "long_name": "refinement parameter h: wear-update interval ΔN [crank cycles] "
                "(wear.dn, fixed update scheme)",
                "refinement_parameter": "wear.dn",
            },
        ),
        "replicate": xr.Variable(
            "replicate",
            np.arange(nrep),
            {
                "units": "1",
                "long_name": "replicate: run started at another phase of the motion",
            },
        ),
        "grid_replicate": xr.Variable(
            "grid_replicate",
            np.arange(ng),
            {"units": "1", "long_name": "replicate on the next grid (finest ΔN)"},
        ),
        "quantity": xr.Variable(
            "quantity", np.array(qnames), {"units": "1", "long_name": "studied quantity"}
        ),
        "initial_settle_cycles": xr.Variable(
            "replicate",
            values[:nrep, 1],
            {"units": "1", "long_name": "cycles discarded before the first measurement"},
        ),
    }


def _add_quantity_info(ds: xr.Dataset, qnames: list[str], units: dict, coords: dict) -> None:
    """Units, meaning, period and resolution of each studied quantity (in place)."""
    ds["quantity_units"] = ("quantity", np.array([units[q][0] for q in qnames], dtype=object))
    ds["quantity_units"].attrs = {"units": "1", "long_name": "units of each quantity"}
    ds["quantity_long_name"] = ("quantity", np.array([units[q][1] for q in qnames], dtype=object))
    ds["quantity_long_name"].attrs = {"units": "1", "long_name": "meaning of each quantity"}
    ds["quantity_period"] = (
        "quantity",
        np.array([QUANTITIES.get(q) or np.nan for q in qnames]),
        {"units": "1", "long_name": "period of a circular quantity (NaN: not circular)"},
    )
    step = {
        "max_wear_theta": 360.0 / coords["theta"].size,
        "max_wear_z": float(np.max(np.diff(coords["z"].values))) if coords["z"].size > 1 else 0.0,
    }
    ds["quantity_resolution"] = (
        "quantity",
        np.array([step.get(q, np.nan) for q in qnames]),
        {
            "units": "1",
            "long_name": "step of a quantised quantity (a location on the wear grid; NaN: "
            "continuous), units: quantity_units",
        },
    )


def study_dataset(
    spec: VerifySpec,
    sim: Any,
    values: np.ndarray,
    where: Sequence[tuple],
    results: Mapping[int, Any],
    lost: Mapping[int, str] | None = None,
    *,
    band: tuple[float, float] | None = None,
) -> xr.Dataset:
    """The study Dataset from the runs' results, with the u_num of every quantity.

    Parameters
    ----------
    spec : VerifySpec
    sim : SimParameters
        The base rig (its grid gives ``z``, ``theta``; ``grid`` times it ``z_grid``,
        ``theta_grid``).
    values : ndarray (runs, 4)
        Each run's ΔN, initial settling, n_layers, n_points.
    where : sequence of (kind, level, replicate)
        ``kind`` ``"level"`` or ``"grid"``.
    results : mapping run index -> RunResult
        ``status``, ``outputs`` (:data:`QUANTITIES`), ``fields["wear_depth"]`` (z, theta) [m].
    lost : mapping, optional
        Runs a cluster lost (index -> reason); they count as not run.
    band : (z_min, z_max), optional
        Axial band [m] (e.g. what the measurement covers): adds the quantities
        ``max_wear_depth_in_band``, ``worn_volume_in_band`` and ``cylindricity_in_band``,
        computed from every run's final wear map within it.
    """
    from jointwear.params import replace_nested
    from jointwear.refinement import COVERAGE_K

    lost = dict(lost or {})
    units = _units()
    band_units = _band_units(band) if band is not None else {}
    qnames = [*QUANTITIES, *band_units]
    units.update(band_units)
    nq, nlev, nrep, ng = len(qnames), len(spec.levels), spec.replicates, spec.grid_replicates
    fine = replace_nested(
        sim,
        **{
            "joint.n_layers": sim.joint.n_layers * spec.grid,
            "joint.n_points": sim.joint.n_points * spec.grid,
        },
    )
    coords = {**_grid_coords(sim), **_grid_coords(fine, "_grid")}
    rv = np.full((nq, nlev, nrep), np.nan)
    gv = np.full((nq, ng), np.nan)
    maps = np.full((nlev, nrep, coords["z"].size, coords["theta"].size), np.nan)
    gmaps = np.full((ng, coords["z_grid"].size, coords["theta_grid"].size), np.nan)
    status = np.full(len(where), 2, dtype=np.int8)  # not run
    errors = np.full(len(where), "", dtype=object)
    for i, (kind, lev, rep) in enumerate(where):
        res = results.get(i)
        if res is None:
            errors[i] = f"not run: {lost[i]}" if i in lost else "not run"
            continue
        status[i] = 0 if res.status == "ok" else 1
        errors[i] = res.error
        if res.status != "ok":
            continue
        depth = res.fields.get("wear_depth")
        outputs = dict(res.outputs)
        if band is not None and depth is not None:
            sfx = "" if kind == "level" else "_grid"
            outputs.update(
                band_quantities(
                    depth, coords["z" + sfx], coords["theta" + sfx], band, sim.joint.bearing_radius
                )
            )
        out = np.array([outputs.get(q, np.nan) for q in qnames], dtype=float)
        if kind == "level":
            rv[:, lev, rep] = out
            if depth is not None:
                maps[lev, rep] = depth
        else:
            gv[:, rep] = out
            if depth is not None:
                gmaps[rep] = depth
    coords.update(_study_coords(spec, qnames, values))
    ds = xr.Dataset(coords=coords)
    dims = ("quantity", "level", "replicate")
    _put(ds, "replicate_value", dims, rv, "value of each run")
    _put(
        ds,
        "grid_replicate_value",
        ("quantity", "grid_replicate"),
        gv,
        "value of each run on the next grid",
    )
    _add_quantity_info(ds, qnames, units, coords)
    ds["wear_depth_run"] = (
        ("level", "replicate", "z", "theta"),
        maps,
        {"units": "m", "long_name": "final wear map of each run"},
    )
    ds["wear_depth_grid_run"] = (
        ("grid_replicate", "z_grid", "theta_grid"),
        gmaps,
        {"units": "m", "long_name": "final wear map of each run on the next grid"},
    )
    ds["run_status"] = xr.Variable(
        "run",
        status,
        {
            "units": "1",
            "long_name": "outcome of each run (levels x replicates, then the grid runs)",
            "flag_values": np.array([0, 1, 2], dtype=np.int8),
            "flag_meanings": "ok failed not_run",
        },
    )
    ds["run_error"] = xr.Variable(
        "run", errors.astype(str), {"units": "1", "long_name": "error of a failed run"}
    )
    ds = ds.assign_coords(
        warning_kind=xr.Variable(
            "warning_kind", np.array(KINDS), {"units": "1", "long_name": "kind of run warning"}
        )
    )
    warn_vars, warn_attrs = warning_variables(where, results, spec)
    for name, (dims, arr, attrs) in warn_vars.items():
        ds[name] = xr.Variable(dims, arr, attrs)
    ds.attrs.update(
        {
            "title": "jointwear verification study: u_num from replicates, ΔN levels and a grid run",
            "jointwear_file": "verification_study",
            "data_origin": "simulated",
            "cycles": spec.cycles,
            "formal_order": spec.formal_order,
            "grid_ratio": float(spec.grid),
            "grid_order": 1.0,
            "grid_level": 0,
            "grid_n_layers": int(fine.joint.n_layers),
            "grid_n_points": int(fine.joint.n_points),
            "study_spec": json.dumps(spec.describe(), sort_keys=True),
            **({"band_z_m": [float(band[0]), float(band[1])]} if band is not None else {}),
            "n_runs": len(where),
            "n_ok": int(np.sum(status == 0)),
            "n_failed": int(np.sum(status == 1)),
            "n_not_run": int(np.sum(status == 2)),
            **warn_attrs,
            "method": "Eça & Hoekstra (2014) least squares on replicate means "
            "(jointwear.refinement); grid term: Roache two-grid, Fs = 3, assumed order 1; "
            f"u_refinement = U_phi / {COVERAGE_K:g}",
        }
    )
    return _add_fits(ds, units)


def _put(ds: xr.Dataset, name: str, dims: tuple[str, ...], values: Any, long_name: str) -> None:
    """``ds[name]``: values of the studied quantities, each in its ``quantity_units``."""
    ds[name] = (dims, values, {"units": "1", "long_name": f"{long_name} (units: quantity_units)"})


def _band_units(band: tuple[float, float]) -> dict[str, tuple[str, str]]:
    lo, hi = band
    if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
        raise BadInputError(f"band = {band!r}: expected (z_min, z_max) [m] with z_min < z_max")
    where = f"within the axial band z = {1e3 * lo:g} .. {1e3 * hi:g} mm"
    return {
        "max_wear_depth_in_band": ("m", f"largest wear depth {where}"),
        "worn_volume_in_band": ("m3", f"worn volume {where} (trapezoid in z)"),
        "cylindricity_in_band": ("m", f"cylindricity (minimum zone) of the worn bore {where}"),
    }


def band_quantities(
    depth: np.ndarray,
    z: xr.DataArray,
    theta: xr.DataArray,
    band: tuple[float, float],
    radius: float,
) -> dict[str, float]:
    """Maximum depth [m], volume [m³] and cylindricity [m] of a wear map within an axial band.

    Parameters
    ----------
    depth : ndarray (z, theta)
        Final wear map [m].
    z, theta : DataArray
        Its coordinates [m], [degree] (with their convention attributes).
    band : (z_min, z_max)
        The band [m]; at least two layers must lie in it.
    radius : float
        Bore radius [m].
    """
    from jointwear.sim.wearmap import bore_cylindricity, bore_radius

    zv = np.asarray(z.values, dtype=float)
    inside = (zv >= band[0]) & (zv <= band[1])
    if inside.sum() < 2:
        raise BadInputError(
            f"band {1e3 * band[0]:g} .. {1e3 * band[1]:g} mm holds {int(inside.sum())} layer(s) "
            "of the wear grid; it needs two or more (widen it)"
        )
    h = np.asarray(depth, dtype=float)[inside]
    ring = h.sum(axis=1) * radius * 2 * np.pi / h.shape[1]  # wear area of each layer's ring
    wear = xr.DataArray(
        h,
        dims=("z", "theta"),
        coords={
            "z": ("z", zv[inside], dict(z.attrs)),
            "theta": ("theta", np.asarray(theta.values), dict(theta.attrs)),
        },
    )
    return {
        "max_wear_depth_in_band": float(h.max()),
        "worn_volume_in_band": float(np.trapezoid(ring, zv[inside])),
        "cylindricity_in_band": bore_cylindricity(bore_radius(wear, radius)),
    }


def _add_fits(ds: xr.Dataset, units: Mapping[str, tuple[str, str]]) -> xr.Dataset:
    """Per quantity: level statistics and the fit (value, u_num and its parts, order, branch)."""
    from jointwear.refinement import level_statistics, study_uncertainty

    qnames = [str(q) for q in ds["quantity"].values]
    fits = [study_uncertainty(ds, q) for q in qnames]
    periods = [QUANTITIES.get(q) for q in qnames]
    lm = np.full((len(qnames), ds.sizes["level"]), np.nan)
    ls = np.full_like(lm, np.nan)
    for k, q in enumerate(qnames):
        vals = ds["replicate_value"].sel(quantity=q).transpose("level", "replicate").values
        lm[k], ls[k], _ = level_statistics(vals, period=periods[k])
    _put(ds, "level_mean", ("quantity", "level"), lm, "mean of the replicates per level")
    _put(ds, "level_sem", ("quantity", "level"), ls, "standard error of the level mean")
    u_attrs = {
        "units": "1",
        "coverage_factor": 1,
        "comment": "standard uncertainty (k = 1) in the units of quantity_units",
    }
    for name, long in (
        ("u_num", "numerical uncertainty sqrt(u_stat^2 + u_refinement^2 + u_grid^2)"),
        ("u_stat", "statistical part: standard error of the finest level's mean"),
        ("u_refinement", "refinement part: Eça-Hoekstra U_phi / 2"),
        ("u_grid", "grid part: Roache two-grid estimate from the runs on the next grid"),
        (
            "u_num_run",
            "numerical uncertainty of ONE run at the finest level: sqrt(sd_run^2 + "
            "u_refinement^2 + u_grid^2) (u_num is that of the finest level's mean, value)",
        ),
        ("sd_run", "standard deviation of one run at the finest level (replicate scatter)"),
    ):
        ds[name] = (
            "quantity",
            np.array([getattr(f, name) for f in fits]),
            {**u_attrs, "long_name": long},
        )
    ds["value"] = (
        "quantity",
        np.array([f.value for f in fits]),
        {
            "units": "1",
            "long_name": "best estimate: mean of the finest level (units: quantity_units)",
            "ancillary_variables": "u_num",
        },
    )
    ds["extrapolated"] = (
        "quantity",
        np.array([f.extrapolated for f in fits]),
        {"units": "1", "long_name": "phi_0 of the fit used (units: quantity_units)"},
    )
    for name, long in (
        ("order", "observed order p of the fit phi = phi_0 + alpha h^p"),
        ("order_sd", "standard deviation of the observed order"),
        ("safety_factor", "safety factor Fs of the branch taken"),
    ):
        ds[name] = (
            "quantity",
            np.array([getattr(f, name) for f in fits]),
            {"units": "1", "long_name": long},
        )
    for name, long in (
        ("branch", "Eça-Hoekstra branch taken and why"),
        ("reason", "why not assessed / notes"),
    ):
        ds[name] = ("quantity", np.array([getattr(f, name) for f in fits], dtype=object))
        ds[name].attrs = {"units": "1", "long_name": long}
    ds["assessed"] = (
        "quantity",
        np.array([f.assessed for f in fits], dtype=np.int8),
        {
            "units": "1",
            "long_name": "u_num assessed",
            "flag_values": np.array([0, 1], dtype=np.int8),
            "flag_meanings": "not_assessed assessed",
        },
    )
    return ds
