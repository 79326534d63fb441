"""u_num of the band criteria from a verification study written by ``jointwear sim verify``.

A study (``jointwear_file = "verification_study"``, the contract with
:mod:`jointwear.refinement`) stores the final wear map of every run: replicates at several
wear-update intervals ΔN and runs on a refined grid. The compared quantities are computed on the
*measured band* of every stored map (each map aligned with the measurement exactly like the
simulation), and :func:`jointwear.refinement.study_uncertainty` turns them into u_num (Eça &
Hoekstra 2014: replicate statistics, the ΔN refinement, the grid term; k = 1). The compared
simulation is one run, so its u_num is the study's ``u_num_run`` (the scatter of one run, not
the standard error of the replicate mean).

The study covers the wear-update interval, the cycle-to-cycle variability (replicates starting at
different phases) and, when its grid term is assessed, the wear grid. A study run for another
number of cycles than the compared simulation contributes its relative u_num, applied to the
compared value (the basis says so).
"""

from __future__ import annotations

import hashlib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import xarray as xr

from jointwear.compare.budget import Component

__all__ = ["StudyResult", "is_study", "band_study_uncertainty", "study_component"]

#: error sources a verification study accounts for
STUDY_COVERS = frozenset({"wear-update interval", "cycle-to-cycle variability"})
GRID = "wear grid"


def is_study(ds: object) -> bool:
    """True for a ``jointwear sim verify`` study file."""
    return isinstance(ds, xr.Dataset) and ds.attrs.get("jointwear_file") == "verification_study"


@dataclass(frozen=True)
class StudyResult:
    """The refinement fit of one band quantity and the cycles the study was run for."""

    fit: object  # jointwear.refinement.RefinementFit
    cycles: float
    name: str


def band_study_uncertainty(
    studies: Sequence[xr.Dataset],
    measured: xr.Dataset,
    quantities: Sequence[str],
    *,
    theta_step_deg: float | None = None,
    radius: float | None = None,
) -> dict[str, StudyResult]:
    """Per band quantity, the study's u_num computed on the measured band of every stored run.

    Parameters
    ----------
    studies : sequence of Dataset
        Verification studies (``jointwear sim verify``).
    measured : Dataset
        The measured wear map (defines the band, as in :func:`compare`).
    quantities : sequence of str
        Names among ``max_wear_depth``, ``worn_volume``, ``cylindricity``.
    theta_step_deg : float, optional
        As given to :func:`compare`.
    radius : float, optional
        Bore radius [m] for the volume when the study's parameters do not state it.
    """
    from jointwear.compare._wear import sim_quantities
    from jointwear.compare.align import align_wear_maps
    from jointwear.refinement import study_uncertainty

    out: dict[str, StudyResult] = {}
    for i, study in enumerate(studies):
        own = _radius(study)
        r_study = own if own is not None else radius
        cache: dict[str, dict[str, float]] = {}

        def band_values(run: xr.DataArray, r_study=r_study, cache=cache):
            key = hashlib.sha1(np.ascontiguousarray(run.values).tobytes()).hexdigest()
            if key not in cache:
                ds = run.to_dataset(name="wear_depth")
                ds.attrs = {"data_origin": "simulated"}
                if r_study is not None:
                    ds.attrs["bearing_radius_m"] = float(r_study)
                al = align_wear_maps(ds, measured, theta_step_deg=theta_step_deg)
                cache[key] = sim_quantities(al)
            return cache[key]

        for q in quantities:
            if q in out:
                continue
            fit = study_uncertainty(study, q, lambda run, q=q: band_values(run).get(q, np.nan))
            name = str(study.attrs.get("title", f"verification study {i + 1}"))
            out[q] = StudyResult(fit, float(study.attrs.get("cycles", np.nan)), name)
    return out


def _radius(study: xr.Dataset) -> float | None:
    """The bore radius [m] from the study's ``bearing_radius_m`` or its ``parameters_json``."""
    import json

    if "bearing_radius_m" in study.attrs:
        return float(study.attrs["bearing_radius_m"])
    try:
        record = json.loads(str(study.attrs.get("parameters_json", "{}")))
    except ValueError:
        return None
    stack = [record]
    while stack:
        item = stack.pop()
        if isinstance(item, Mapping):
            if isinstance(item.get("bearing_radius"), (int, float)):
                return float(item["bearing_radius"])
            stack.extend(item.values())
    return None


def study_component(res: StudyResult, s: float, compared_cycles: float | None) -> Component:
    """The study's u_num of a band quantity as a budget component, scaled to ``s`` if needed."""
    fit = res.fit
    covers = STUDY_COVERS | ({GRID} if np.isfinite(getattr(fit, "u_grid", np.nan)) else set())
    if not fit.assessed:
        return Component(None, f"verification study (sim verify): {fit.reason}", covers)
    # the compared simulation is one run: its u_num has the scatter of one run (sd_run), not the
    # standard error of the replicate mean
    u = float(getattr(fit, "u_num_run", np.nan))
    if not np.isfinite(u):
        return Component(
            None,
            "verification study: the u_num of one run (u_num_run) is not available - the study "
            "needs replicates at its finest level",
            covers,
        )
    note = (
        f"verification study (sim verify, on the measured band), u_num of one run = "
        f"{u:.3g} (sd_run {fit.sd_run:.3g}; the mean's: {fit.describe()})"
    )
    same = compared_cycles is None or np.isclose(res.cycles, compared_cycles, rtol=1e-6)
    if not same:
        if not (np.isfinite(res.cycles) and fit.value):
            return Component(
                None, "verification study: its cycles are not stated, cannot be matched", covers
            )
        u = u / abs(float(fit.value)) * abs(s)
        note += (
            f"; run for {res.cycles:g} cycles: relative u_num {u / abs(s):.3g} applied to the "
            f"compared value at {compared_cycles:g} cycles"
        )
    return Component(u, note, covers, relative=not same)
