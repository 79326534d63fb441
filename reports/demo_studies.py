"""The demo's verification studies and its input-uncertainty ensemble (used by :mod:`.demo`)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
import xarray as xr

from jointwear.datasets.reference_study import ENSEMBLE_INPUTS
from jointwear.errors import JointwearError

if TYPE_CHECKING:
    from jointwear.reports.demo import DemoSize

__all__ = [
    "DEMO_STUDY_UPDATES",
    "ENSEMBLE_INPUTS",
    "MOTION_RTOLS",
    "demo_study",
    "ensemble_spec",
    "is_compared_run",
    "main_wear_settings",
    "motion_verification",
    "run_ensemble",
    "wear_verification",
]


def _say(msg: str) -> None:
    import typer

    typer.echo(msg, err=True)


#: The demo's verification study: ΔN levels as a fraction of the demo's cycles, replicates per
#: level and runs on the grid refined 2x (a reduced :meth:`jointwear.sim.VerifySpec.default`).
#: A fixed-scheme run costs its number of updates (each simulates 1 + settle cycles), whatever
#: its cycles: the finest level and the grid runs dominate the study, which dominated the demo
#: (phase 1 took 109 s of 147 s with 40 updates, 51 s of 82 s with 16 = 16, 8, 4, 2 per level;
#: benchmarks/results/compare_report.json, docs/compare-report.md). The compared run is the
#: finest level's replicate 0, so its coarser update shows in the study's u_num, not hidden.
DEMO_STUDY_UPDATES = 16  # updates of the finest level
DEMO_STUDY_GRID_REPLICATES = 2


def demo_study(size: DemoSize) -> Any:
    """The demo's verification study (``jointwear sim verify`` spec) at demo size.

    ΔN = cycles/16 x (1, 2, 4, 8), ``size.verification_replicates`` runs per level starting at
    different phases of the motion, and 2 runs on the grid refined 2x at the finest ΔN.
    """
    from jointwear.sim import VerifySpec

    finest = max(1, round(size.cycles / DEMO_STUDY_UPDATES))
    return VerifySpec(
        cycles=size.cycles,
        levels=tuple(finest * 2**k for k in range(4)),
        replicates=size.verification_replicates,
        grid_replicates=DEMO_STUDY_GRID_REPLICATES,
    )


def main_wear_settings(size: DemoSize) -> Any:
    """Wear settings of the demo's compared wear run.

    With a verification study the compared run is the verified configuration: the fixed update
    scheme at the study's finest ΔN (replicate 0 of its finest level), so the study's
    ``u_num_run`` is its numerical uncertainty. Without one (``--quick``): the default adaptive
    scheme.
    """
    from jointwear.sim import WearSettings

    if not size.verification_replicates:
        return WearSettings()
    return WearSettings(scheme="fixed", dn=demo_study(size).levels[0])


def wear_verification(
    params: Any, size: DemoSize, folder: Any, *, scheduler: Any = None
) -> tuple[Any, xr.Dataset]:
    """The demo's verification study of the simulated wear (:func:`jointwear.sim.verify_wear`).

    Replicates at four wear-update intervals ΔN and runs on the next grid (:func:`demo_study`),
    in this process or on ``scheduler`` (the demo's pool of worker processes, see
    :mod:`jointwear.reports.demo_pool`); :func:`jointwear.refinement.study_uncertainty` turns the study into u_num of
    any wear quantity (Eça & Hoekstra 2014 on the replicate means, plus the grid term), so max
    depth, volume and cylindricity are assessed with a value (the earlier refinement of the
    adaptive update's ``tol`` was inert: the noise floor, not ``tol``, set the interval).

    Returns
    -------
    (Path, Dataset)
        The study file ``sim_verification.nc`` in ``folder`` and the study.
    """
    from pathlib import Path

    from jointwear.sim import verify_wear

    path = Path(folder) / "sim_verification.nc"
    study = verify_wear(params, spec=demo_study(size), workers=0, scheduler=scheduler, out=path)
    return path, study


#: solver tolerances of the motion verification study (the default 1e-6 is the finest): nine
#: levels, for Eça & Hoekstra's least squares, which covers the scatter of a motion with impacts
#: over the tolerance (three would go to the GCI, which refuses it). Checked against the RMS at
#: rtol 1e-8..1e-9 from 40 initial crank angles, both components: 2 u_num covers 96 % of the 80
#: cases with these nine levels, 82 % with five (1e-4, 3e-5, 1e-5, 3e-6, 1e-6)
#: (benchmarks/bench_motion_verification.py); tests/reports/test_motion_verification.py repeats
#: it on 20 angles (100 % and 88 %).
MOTION_RTOLS = (1e-4, 5e-5, 3e-5, 2e-5, 1e-5, 5e-6, 3e-6, 2e-6)


def _rms_window(motion: xr.Dataset, duration: float) -> dict[str, float]:
    """RMS of each in-plane follower velocity component over the first ``duration`` seconds
    (the stereo footage's length; 0: the whole record), on the simulation's own samples. The
    comparison takes the RMS at the footage's frames, shifted by the crank-angle alignment,
    and this study's u_num relative to it (``u_num_rel·|S|``)."""
    t = np.asarray(motion["time"].values, dtype=float)
    window = t <= t[0] + duration if duration > 0 else np.ones(t.shape, bool)
    v = motion["follower_velocity"]
    return {
        f"follower_velocity_{c}_rms": float(
            np.sqrt(np.mean(np.asarray(v.sel(axis=c).values, dtype=float)[window] ** 2))
        )
        for c in ("x", "y")
    }


def motion_verification(params: Any, size: DemoSize, main: xr.Dataset) -> xr.Dataset:
    """Numerical uncertainty of the simulated in-plane follower velocity RMS: the solver tolerance.

    The motion is repeated with ``solver.rtol`` = :data:`MOTION_RTOLS` (the main run uses the
    default, the finest level); the RMS of each in-plane component over the footage's length
    ``size.rig_duration`` is the studied quantity. With impacts the RMS does not
    converge smoothly with the tolerance (it scatters by about 1e-4 of itself down to rtol =
    1e-9), so :func:`jointwear.compare.compare` takes Eça & Hoekstra's least squares over the nine
    levels (:func:`jointwear.compare.verification.refinement_study`), whose data-range branch
    covers the scatter. ``formal_order`` 1: DOPRI5's step control keeps the global error
    proportional to the tolerance. A level whose simulation fails is NaN and left out by the
    study (with fewer than four left, the GCI of three; with fewer, not assessed).
    """
    from jointwear.params import replace_nested
    from jointwear.sim import run_cycles

    rtols = [*MOTION_RTOLS, float(params.solver.rtol)]
    window = float(size.rig_duration)
    finest = _rms_window(main, window)
    failed = dict.fromkeys(finest, np.nan)
    rows = []
    for rtol in MOTION_RTOLS:
        p = replace_nested(params, **{"solver.rtol": rtol})
        try:
            rows.append(_rms_window(run_cycles(p, cycles=size.motion_cycles).dataset, window))
        except JointwearError as exc:  # a level that fails is left out (NaN), the study goes on
            _say(f"      motion at solver.rtol = {rtol:g} failed: {exc}")
            rows.append(failed)
    rows.append(finest)
    what = f"the first {window:g} s" if window > 0 else "the record"
    data = {
        name: (
            "solver_rtol",
            [r[name] for r in rows],
            {"units": "m s-1", "long_name": f"RMS of {name[: -len('_rms')]} over {what}"},
        )
        for name in rows[0]
    }
    return xr.Dataset(
        data,
        coords={
            "solver_rtol": (
                "solver_rtol",
                rtols,
                {
                    "units": "1",
                    "long_name": "relative tolerance of the ODE solver (solver.rtol)",
                    "formal_order": 1.0,
                },
            )
        },
    )


def ensemble_spec(
    params: Any, size: Any, *, kw: float | None = None, calibrated: tuple[str, ...] = ()
) -> dict[str, Any]:
    """The demo's sweep spec (``jointwear sim sweep`` format): LHS over :data:`ENSEMBLE_INPUTS`.

    ``size`` gives ``ensemble_cycles`` and ``ensemble_runs``; ``kw`` the nominal wear
    coefficient (default :data:`jointwear.sim.DEFAULT_KW`). An input whose nominal value is 0
    (e.g. a frictionless model) is not varied: a relative spread of 0 is no distribution; nor is
    an input in ``calibrated`` (its spread is the posterior prediction's).
    """
    from jointwear.sim import DEFAULT_KW

    parameters: dict[str, Any] = {}
    for name, (rel, _) in ENSEMBLE_INPUTS.items():
        if name in calibrated:
            continue
        section, field = name.split(".")
        if name == "wear.kw":
            mean = DEFAULT_KW if kw is None else float(kw)
        else:
            mean = float(getattr(getattr(params, section), field))
        if mean == 0:
            continue
        spec = {"distribution": "truncnormal", "mean": mean, "std": rel * mean}
        spec["bounds"] = [mean * (1 - 4 * rel), mean * (1 + 4 * rel)]
        parameters[name] = spec
    return {
        "sweep": {
            "run": "wear",
            "cycles": float(size.ensemble_cycles),
            "method": "lhs",
            "samples": int(size.ensemble_runs),
            "seed": 11,
            "outputs": ["max_wear_depth", "worn_volume", "cylindricity"],
            "keep": ["wear_depth"],
        },
        "parameters": parameters,
    }


def run_ensemble(
    params: Any,
    size: DemoSize,
    motion_time: np.ndarray,
    *,
    progress: bool = True,
    calibrated: tuple[str, ...] = (),
) -> xr.Dataset:
    """A small real ensemble over the uncertain inputs, through :func:`jointwear.sim.run_sweep`.

    The wear runs are a Latin-hypercube sweep (:func:`ensemble_spec`; fixed update interval,
    reduced cycles, in this process) keeping each run's final wear map; each member's motion is
    then simulated with the same sampled inputs and its follower velocity
    ``(run, time, axis)`` added on ``motion_time``, so that the compared in-plane velocity RMS
    has an ensemble spread too (the sweep's own motion output is the speed RMS). The inputs in
    ``calibrated`` are not varied (:func:`ensemble_spec`).
    """
    from jointwear import conventions
    from jointwear.params import replace_nested
    from jointwear.sim import WearSettings, run_cycles, run_sweep

    dn = int(size.ensemble_cycles // size.ensemble_updates)

    def report(state: dict[str, Any]) -> None:
        if progress and state["done"]:
            _say(
                f"      wear runs done {state['done']}/{state['total']}"
                + (f", failed {state['failed']}" if state.get("failed") else "")
            )

    ds = run_sweep(
        ensemble_spec(params, size, calibrated=calibrated),
        params=params,
        wear=WearSettings(scheme="fixed", dn=dn),
        workers=0,
        on_progress=report,
    )
    vel, crank = [], []
    for r in range(ds.sizes["run"]):
        changes = {
            k: float(ds[k].values[r])
            for k in ENSEMBLE_INPUTS
            if not k.startswith("wear.") and k in ds
        }
        try:
            m = run_cycles(replace_nested(params, **changes), cycles=size.motion_cycles).dataset
        except JointwearError as exc:
            _say(f"      motion of run {r + 1} failed: {exc}")
            vel.append(np.full((motion_time.size, 3), np.nan))
            crank.append(np.full(motion_time.size, np.nan))
            continue
        t = np.asarray(m["time"].values, dtype=float)
        v = np.asarray(m["follower_velocity"].transpose("time", "axis").values, dtype=float)
        vel.append(np.stack([np.interp(motion_time, t, v[:, j]) for j in range(3)], axis=1))
        crank.append(np.interp(motion_time, t, np.unwrap(np.asarray(m["crank_angle"].values))))
    ds = ds.assign_coords(
        time=("time", motion_time, {"units": "s", "long_name": "time"}),
        axis=("axis", np.array(["x", "y", "z"]), {"long_name": "vector component"}),
    )
    ds["follower_velocity"] = (
        ("run", "time", "axis"),
        np.stack(vel),
        conventions.variable_attrs("follower_velocity"),
    )
    ds["crank_angle"] = (
        ("run", "time"),
        np.stack(crank),
        conventions.variable_attrs("crank_angle"),
    )
    ds.attrs.update(
        {
            "title": "demo ensemble over the uncertain model inputs",
            "data_origin": "simulated",
            "bearing_radius_m": float(params.joint.bearing_radius),
        }
    )
    return ds


def is_compared_run(task: Any, params: Any, size: DemoSize) -> bool:
    """True if the study run ``task`` is the demo's compared wear run: the same parameters,
    wear settings (:func:`main_wear_settings`), cycles and snapshots, so that one simulation
    serves both (replicate 0 of the finest level)."""
    from jointwear.sim.sweep import apply_values

    sim, wear = apply_values(task.sim_params, task.wear_settings, task.values)
    return (
        sim == params
        and wear == main_wear_settings(size)
        and task.spec.cycles == size.cycles
        and list(size.snapshots) == [size.cycles]
    )
