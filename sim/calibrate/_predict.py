"""Prediction with the posterior: the simulator itself run at posterior samples (``sim predict``).

:func:`predict` takes ``M`` posterior samples (evenly spaced through the thinned chain), runs one
wear simulation per sample through the sweep driver (dask, resumable, part files) on the rig
the calibration used (its base parameters, from the posterior file), and writes the ensemble:
per run the sampled parameters (coordinates), the wear map ``wear_depth(run, z, theta)`` at the
asked cycles and the scalar outputs. ``jointwear compare prediction.nc MEASURED.nc --cycles N``
takes it as the simulation: the mean map over the runs is compared, and the spread of the runs
is its input uncertainty u_input (the posterior predictive spread, not the prior's). The file
carries the calibration data of the posterior, so that compare refuses to validate on them.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from jointwear.errors import BadInputError
from jointwear.sim.calibrate._defaults import PREDICT_SAMPLES

__all__ = ["predict", "PREDICTION_FILE"]

#: ``jointwear_file`` attribute of a prediction ensemble (compare recognises it)
PREDICTION_FILE = "posterior_prediction"


def _rig(post: xr.Dataset, where: str) -> tuple[Any, Any]:
    """The calibration's base SimParameters and WearSettings, from the posterior file."""
    from jointwear.params import from_mapping
    from jointwear.sim.parameters import DEFAULT_PARAMETER_SET, PARAMETER_SETS
    from jointwear.sim.wear import WearSettings

    record = json.loads(str(post.attrs.get("base_parameters", "{}")))
    if "parameters" not in record or "wear" not in record:
        raise BadInputError(f"{where}: no base parameters of a wear calibration (run = wear)")
    kind = type(PARAMETER_SETS[str(post.attrs.get("base_set") or DEFAULT_PARAMETER_SET)])
    sim = from_mapping(kind, record["parameters"], where="base parameters")
    return sim, from_mapping(WearSettings, record["wear"], where="wear")


def _picks(n_total: int, samples: int) -> np.ndarray:
    if samples < 2:
        raise BadInputError(f"--samples {samples}: a spread needs at least 2 runs")
    if samples > n_total:
        raise BadInputError(f"--samples {samples}: the posterior holds only {n_total} samples")
    return np.linspace(0, n_total - 1, samples).round().astype(int)


def predict(
    posterior: str | Path,
    *,
    cycles: float,
    out: str | Path,
    samples: int = PREDICT_SAMPLES,
    workers: int | None = None,
    scheduler: Any = None,
    resume: bool = False,
    on_progress: Callable[[dict[str, Any]], None] | None = None,
) -> xr.Dataset:
    """Run the simulator at ``samples`` posterior samples for ``cycles`` cycles; write ``out``.

    Parameters
    ----------
    posterior : path
        posterior.nc of :func:`jointwear.sim.calibrate.calibrate` (a wear calibration).
    cycles : float
        Crank cycles to simulate (a whole number).
    out : path
        prediction.nc (each finished run first goes to ``<out>.parts/``).
    samples : int
        Number of posterior samples run (the ensemble's size).
    workers, scheduler, resume, on_progress
        As :func:`jointwear.sim.run_sweep`.

    Returns
    -------
    Dataset
        The ensemble along ``run`` (a sweep's layout) with ``jointwear_file = "posterior_prediction"``.
    """
    from jointwear import io
    from jointwear.sim.calibrate._data import file_record
    from jointwear.sim.sweep import (
        Design,
        Execution,
        RunTask,
        assemble,
        read_spec,
        run_and_save,
        spec_digest,
    )

    post = io.load(posterior, validate=False)
    where = str(posterior)
    if post.attrs.get("jointwear_file") != "posterior":
        raise BadInputError(
            f"{where} is not a posterior written by 'jointwear sim calibrate' "
            "(attribute jointwear_file = 'posterior')"
        )
    if post.attrs.get("run") != "wear":
        raise BadInputError(f"{where}: a calibration of run = {post.attrs.get('run')!r}, not wear")
    if not (float(cycles) > 0 and float(cycles).is_integer()):
        raise BadInputError(f"--cycles {cycles!r}: a wear run needs a whole number of cycles > 0")
    sim, wear = _rig(post, where)
    names = json.loads(post.attrs["calibrated_parameters"])
    prov = io.parse_provenance(post)
    priors = {p["name"]: p for p in prov["parameters"]["calibration"]["parameters"]}
    mapping = {
        "sweep": {
            "run": "wear",
            "method": "lhs",
            "samples": samples,
            "cycles": float(cycles),
            "keep": ["wear_depth"],
            "max_cycles_simulated": prov["parameters"]["calibration"]["max_cycles_simulated"],
        },
        "parameters": {n: {k: v for k, v in priors[n].items() if k != "name"} for n in names},
    }
    spec = read_spec(mapping)
    picks = _picks(post.sizes["sample"], samples)
    values = np.column_stack([np.asarray(post[n].values, dtype=float)[picks] for n in names])
    seeds = np.array(
        [np.random.SeedSequence([spec.seed, i]).generate_state(1)[0] for i in range(samples)],
        dtype=np.int64,
    )
    design = Design(values=values, unit=None, seeds=seeds)
    tasks = [
        RunTask(i, design.run_values(names, i), int(seeds[i]), spec, sim, wear)
        for i in range(samples)
    ]
    from jointwear.params import to_jsonable

    record = {
        "parameters": to_jsonable(sim),
        "wear": to_jsonable(wear),
        "spec": spec.describe(),
        "posterior": file_record(posterior),
        "samples": picks.tolist(),
    }

    def build(results, lost) -> xr.Dataset:
        ds = assemble(spec, design, results, lost, sim=sim)
        ds.attrs.update(
            {
                "title": f"jointwear prediction: {samples} simulations at posterior samples",
                "jointwear_file": PREDICTION_FILE,
                "cycles": float(cycles),
                "bearing_radius_m": float(sim.joint.bearing_radius),
                "posterior_file": str(posterior),
                "calibration_data": post.attrs.get("calibration_data", "[]"),
                "calibration_cycles": post.attrs.get("calibration_cycles", "[]"),
                "probabilistic_sample_note": "the runs are a sample of the posterior: the spread "
                "of an output over run is its posterior predictive (input) uncertainty",
            }
        )
        return ds

    digest = spec_digest(spec, {"posterior": record["posterior"], "samples": record["samples"]})
    how = Execution(out, resume, workers, scheduler, on_progress)
    return run_and_save(tasks, values, build, how, digest, record, [Path(posterior)], "sim.predict")
