"""Calibration data never validate; a posterior prediction is compared as a simulation.

A prediction written by ``jointwear sim predict`` (``jointwear_file = "posterior_prediction"``:
an ensemble of simulations at posterior samples along ``run``) is split into the simulation
compared (the mean wear map over the runs, at the prediction's cycles) and the ensemble whose
spread is its input uncertainty u_input (the posterior predictive spread).

It also carries the calibration data of its posterior (``calibration_data``: path, sha256 and
the sha256 of each file's own provenance inputs). A measured file given to compare that *is*
one of them (same sha256), or is made from the same inputs (the same snapshot of the same bore
processed again), is refused (exit 3): agreement with the data the inputs were fitted to is not
validation. With ``calibration_check`` the comparison runs, every row is labelled
"calibration check, not validation", and a pass is never counted as validation (the summary,
the card, the file's ``validation_passed`` = 0).
"""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Sequence
from pathlib import Path

import xarray as xr

from jointwear.compare.comparison import Comparison
from jointwear.errors import BadInputError

__all__ = [
    "PREDICTION_FILE",
    "CALIBRATION_CHECK",
    "CalibrationCheck",
    "is_prediction",
    "split_prediction",
    "calibration_reuse",
    "as_calibration_check",
    "prepare",
    "posterior_note",
    "POSTERIOR_NOTE",
]

#: ``jointwear_file`` of a posterior prediction (the contract with ``jointwear sim predict``)
PREDICTION_FILE = "posterior_prediction"
#: the label of every row of a comparison with calibration data
CALIBRATION_CHECK = "calibration check, not validation"


#: the start of the note of a comparison whose simulation is a posterior prediction (the report's
#: power paragraph looks for it)
POSTERIOR_NOTE = "the simulation compared is the posterior prediction"


def posterior_note(names: Sequence[str]) -> str:
    """The comparison's note that its simulation is the posterior prediction ``names``."""
    return (
        f"{POSTERIOR_NOTE} {', '.join(names)} (jointwear sim predict): its mean map over the "
        "runs, their spread the input uncertainty of the calibrated inputs"
    )


def is_prediction(ds: xr.Dataset) -> bool:
    """True for a posterior prediction ensemble of ``jointwear sim predict``."""
    return ds.attrs.get("jointwear_file") == PREDICTION_FILE


def split_prediction(ds: xr.Dataset) -> tuple[xr.Dataset, xr.Dataset]:
    """(the simulation compared: mean map over the finished runs, the ensemble itself)."""
    if "wear_depth" not in ds or "run" not in ds["wear_depth"].dims:
        raise BadInputError("the prediction holds no wear maps over 'run' (wear_depth)")
    ok = ds["status"] == 0 if "status" in ds else xr.ones_like(ds["run"], dtype=bool)
    if int(ok.sum()) < 2:
        raise BadInputError(
            f"the prediction has {int(ok.sum())} finished run(s); its mean and spread need 2 "
            "(rerun 'jointwear sim predict' with --resume, or fix the failed runs' cause)"
        )
    cycles = float(ds.attrs["cycles"])
    mean = ds["wear_depth"].where(ok).mean("run").expand_dims(cycles=[cycles])
    mean.attrs = dict(ds["wear_depth"].attrs, long_name="mean wear depth over the posterior runs")
    sim = mean.to_dataset(name="wear_depth")
    sim["cycles"].attrs = {"units": "1", "long_name": "crank cycles"}
    sim.attrs = {
        "title": "posterior predictive mean wear map",
        "data_origin": "simulated",
        "cycles": cycles,
        "bearing_radius_m": float(ds.attrs["bearing_radius_m"]),
        "provenance": ds.attrs.get("provenance", "{}"),
    }
    return sim, ds


def _file_keys(path: str | Path) -> tuple[str, frozenset[str]]:
    """sha256 of a file and the sha256 of its own provenance inputs (empty if none)."""
    from jointwear import io

    digest, inputs = io.file_snapshot(path)
    return digest, frozenset(inputs)


def calibration_reuse(
    sims: Sequence[xr.Dataset], meas: Sequence[str | Path], *, calibration_check: bool
) -> list[str]:
    """The measured files that were calibration data of a simulation's posterior.

    Raises
    ------
    BadInputError
        A measured file was used in the calibration and ``calibration_check`` is not set.
    """
    records = []
    for ds in sims:
        records += json.loads(str(ds.attrs.get("calibration_data", "[]")))
    if not records:
        return []
    used = []
    for path in meas:
        digest, inputs = _file_keys(path)
        for r in records:
            same_file = r.get("sha256") == digest
            same_snapshot = bool(inputs) and inputs == frozenset(r.get("inputs_sha256", []))
            if same_file or same_snapshot:
                how = "is" if same_file else "is made from the same scans as"
                used.append(f"{path} {how} the calibration data {r.get('path')}")
    if used and not calibration_check:
        raise BadInputError(
            "calibration data never validate: "
            + "; ".join(used)
            + ". Compare with a measurement the posterior was not fitted to (another snapshot "
            "or bore), or pass --calibration-check to see how well the calibration fits (its "
            "rows are labelled 'calibration check, not validation')"
        )
    return used


@dataclasses.dataclass(frozen=True)
class CalibrationCheck(Comparison):
    """A comparison with calibration data: decided as usual, never a validation."""

    used: tuple[str, ...] = ()

    @property
    def passed(self) -> bool:
        """Never: agreement with the calibration data validates nothing."""
        return False

    def summary(self) -> str:
        """The usual summary, prefixed with :data:`CALIBRATION_CHECK`."""
        return f"{CALIBRATION_CHECK}: {super().summary()}"


def as_calibration_check(c: Comparison, used: Sequence[str]) -> CalibrationCheck:
    """``c`` with every row labelled :data:`CALIBRATION_CHECK` and a note naming the data."""
    decisions = c.decisions.copy()
    decisions["quantity"] = [f"{CALIBRATION_CHECK}: {q}" for q in decisions["quantity"]]
    note = f"{CALIBRATION_CHECK}: " + "; ".join(used)
    fields = {f.name: getattr(c, f.name) for f in dataclasses.fields(c)}
    fields.update(decisions=decisions, notes=(*c.notes, note), used=tuple(used))
    return CalibrationCheck(**fields)


def prepare(
    sims: list[xr.Dataset],
    sim_paths: Sequence[str | Path],
    meas_paths: Sequence[str | Path],
    ens: list[xr.Dataset],
    ens_names: list[str],
    calibration_check: bool,
) -> tuple[list[xr.Dataset], list[xr.Dataset], list[str], list[str]]:
    """What :func:`jointwear.compare.compare_files` compares: each prediction split into its
    mean map (a simulation) and its ensemble; the calibration data reused (refused unless
    ``calibration_check``). Returns (simulations, ensembles, their names, reuse notes)."""
    used = calibration_reuse(sims, meas_paths, calibration_check=calibration_check)
    out_sims, out_ens, names = [], list(ens), list(ens_names)
    for ds, path in zip(sims, sim_paths, strict=True):
        if is_prediction(ds):
            mean, ensemble = split_prediction(ds)
            out_sims.append(mean)
            out_ens.insert(0, ensemble)
            names.insert(0, Path(path).name)
        else:
            out_sims.append(ds)
    return out_sims, out_ens, names, used
