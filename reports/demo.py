"""``jointwear demo``: the whole chain on embedded default data, ending in a validation report.

Steps (each through the public API a user would call, each output a contract netCDF file):

1. **Simulate** the reference mechanism (Zhang et al. 2023 parameters): a wear run of joint C
   with cycle updates (:func:`jointwear.sim.simulate_wear`) and the motion over one and a half
   crank cycles (:func:`jointwear.sim.run_cycles`).
2. **Make the "measured" side** with the ground-truth generators of :mod:`jointwear.datasets`:
   the worn bearing as roundness-instrument text files (13 layers 1 mm apart, 18000 points per
   layer, the instrument's own angle convention, set-up eccentricity and tilt, form errors,
   probe noise) from a plausible measured wear map - the simulated map made 10 % deeper,
   turned by 6 degree, as a real bearing would differ from the model; and, when the DIC chain is installed, stereo footage of the virtual rig.
3. **Import and process** the measurement: :func:`jointwear.metrology.readers.read_talyrond`
   (angle convention stated, never guessed) for the worn scan and a scan of the same bearing
   before wear, and :func:`jointwear.metrology.wear_map`; the
   footage through :mod:`jointwear.dic`.
4. **Compare** (:func:`jointwear.compare.compare`) and **report**
   (:func:`jointwear.reports.build_report`).

Parts of the chain that are not installed are skipped and the report says so plainly.
"""

from __future__ import annotations

import time
from concurrent.futures import Executor, Future
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from jointwear import io
from jointwear.errors import JointwearError, ValidationFailed
from jointwear.reports.demo_measured import (  # noqa: F401 (the measured side's names, re-exported)
    INSTRUMENT_CONVENTION,
    MEASURED_ROTATION_DEG,
    MEASURED_SCALE,
    MOTION_SPEED_FACTOR,
    _available,
    _in_plane,
    _measure_motion,
    _measure_wear,
    _say,
    measured_wear_function,
    rig_speed_rpm,
)
from jointwear.reports.demo_studies import (
    ENSEMBLE_INPUTS,
    is_compared_run,
    main_wear_settings,
    motion_verification,
    run_ensemble,
    wear_verification,
)

__all__ = ["run_demo", "DemoSize", "DEMO_CRITERIA"]

#: Validation criteria of the demo: the defaults. Input uncertainty comes from the demo's ensemble
#: (full run) and is *not assessed* with --quick; no fraction is assumed.
DEMO_CRITERIA: dict[str, float] = {}


@dataclass(frozen=True)
class DemoSize:
    """Sizes of the demo run (full or ``--quick``)."""

    cycles: float
    snapshots: tuple[float, ...]
    n_layers: int
    n_points: int
    instrument_points: int
    motion_cycles: float
    rig_size: tuple[int, int] | None  # stereo footage (width, height) [px]; None = no footage
    rig_duration: float  # recorded time [s]
    verification_replicates: int  # runs per dN level of the verification study (0: none)
    ensemble_runs: int = 0  # members of the input-uncertainty ensemble (0: none)
    ensemble_cycles: float = 0.0  # wear cycles of each member (reduced)
    ensemble_updates: int = 4  # fixed wear updates per member
    calibration_cycles: float = 0.0  # snapshot the inputs are calibrated on (0: no calibration)
    training_runs: int = 0  # the calibration's training runs (emulator design)
    prediction_runs: int = 0  # simulations at posterior samples (the compared prediction)


FULL = DemoSize(2e5, (2e5,), 10, 90, 18000, 1.5, (640, 512), 0.6, 3, 8, 5e4, 4, 1e5, 16, 8)
QUICK = DemoSize(5e4, (5e4,), 8, 72, 3600, 1.2, None, 0.0, 0)


def _params(size: DemoSize) -> Any:
    from jointwear.params import replace_nested
    from jointwear.sim import DEFAULT_PARAMETER_SET, PARAMETER_SETS

    return replace_nested(
        PARAMETER_SETS[DEFAULT_PARAMETER_SET],
        **{"joint.n_layers": size.n_layers, "joint.n_points": size.n_points},
    )


def _save_wear(folder: Path, size: DemoSize, params: Any, wear: xr.Dataset, t0: float) -> Path:
    """The compared wear run of joint C, saved as ``sim_wear.nc``."""
    wear.attrs["data_origin"] = "simulated"
    path = io.save(
        wear,
        folder / "sim_wear.nc",
        parameters={"simulation": params, "cycles": size.cycles},
        source="jointwear (sim.wear) via jointwear demo",
    )
    u = float(wear["max_wear_depth_u"][-1]) * 1e6 if "max_wear_depth_u" in wear else float("nan")
    noise = (
        ", the wear rate's cycle-to-cycle noise included"
        if wear.attrs.get("accuracy_status") == "not reached"
        else ""
    )
    # a run of the verification study (fixed updates) states no accuracy of its own: the study's
    # u_num is the compared run's
    accuracy = f" ± {u:.1f} µm (k = 2{noise}; " if np.isfinite(u) else " µm (u_num: the study; "
    _say(
        f"  simulated wear: {size.cycles:g} cycles on {size.n_layers} x {size.n_points} points, "
        f"max depth {float(wear['max_wear_depth'][-1]) * 1e6:.1f}{accuracy}"
        f"{time.perf_counter() - t0:.0f} s)"
    )
    return path


def _wear_part(folder: Path, size: DemoSize, params: Any, metrology: bool) -> tuple[Path, Any]:
    """Worker part without a study (``--quick``): the compared wear run, then the virtual
    roundness scans made from it."""
    from jointwear.sim import simulate_wear

    t0 = time.perf_counter()
    wear = simulate_wear(
        params,
        cycles=size.cycles,
        snapshots=list(size.snapshots),
        settings=main_wear_settings(size),
    )
    sim_wear = _save_wear(folder, size, params, wear, t0)
    return sim_wear, *_measured(folder, sim_wear, size, params, metrology)


def _measured(
    folder: Path, sim_wear: Path, size: DemoSize, params: Any, metrology: bool
) -> tuple[Path | None, Path | None]:
    """The measured wear maps of the synthetic bore: at the compared cycles and, when the demo
    calibrates, at ``size.calibration_cycles`` (the calibration data: the model's map at those
    cycles made into the same bore's earlier snapshot, scanned against the same before-scan)."""
    if not metrology:
        return None, None
    validation = _measure_wear(folder, sim_wear, size)[0]
    if not size.calibration_cycles:
        return validation, None
    from jointwear.reports.demo_studies import main_wear_settings
    from jointwear.sim import simulate_wear

    cycles = size.calibration_cycles
    early = simulate_wear(
        params, cycles=cycles, snapshots=[cycles], settings=main_wear_settings(size)
    )
    early.attrs["data_origin"] = "simulated"
    path = io.save(
        early,
        folder / "sim_wear_calibration.nc",
        parameters={"simulation": params, "cycles": cycles},
        source="jointwear (sim.wear) via jointwear demo: the truth's earlier snapshot",
    )
    return validation, _measure_wear(folder, path, size, cycles=cycles, tag="_calibration")[0]


def _compared_study_run(
    task: Any, folder: Path, size: DemoSize, params: Any, metrology: bool
) -> tuple[Any, tuple[Path, Any]]:
    """Worker part with a study: its run that is the compared wear run (replicate 0 of the
    finest level, :func:`~jointwear.reports.demo_studies.is_compared_run`), simulated once: the
    study gets its result, ``sim_wear.nc`` its whole wear map; then the roundness scans."""
    from jointwear.errors import SimulationError
    from jointwear.sim.sweep import evaluate_run

    if not is_compared_run(task, params, size):
        raise SimulationError("demo: the study's run 0 is not the compared wear run")
    t0 = time.perf_counter()
    saved: list[Path] = []
    result = evaluate_run(
        task, on_dataset=lambda ds: saved.append(_save_wear(folder, size, params, ds, t0))
    )
    if result.status != "ok" or not saved:
        raise SimulationError(f"demo: the compared wear run failed: {result.error}")
    return result, (saved[0], *_measured(folder, saved[0], size, params, metrology))


class _StudyPool(Executor):
    """The study's view of the pool: every run is one task, except the compared run (index
    0), which runs as :func:`_compared_study_run`; ``wear`` receives that part's
    ``((sim_wear, metrology), text)`` as :func:`_wear_part` would give it."""

    def __init__(self, pool: Executor, *args: Any) -> None:
        self.pool, self.args = pool, args
        self.wear: Future = Future()

    def submit(self, fn: Any, /, *args: Any, **kwargs: Any) -> Future:
        (task,) = args
        if task.index != 0:
            return self.pool.submit(fn, task)
        from jointwear.reports.demo_pool import run_part

        inner = self.pool.submit(run_part, _compared_study_run, task, *self.args)
        outer: Future = Future()

        def split(fut: Future) -> None:
            if fut.cancelled():  # the demo was stopped
                self.wear.cancel()
                outer.cancel()
                return
            if fut.exception() is not None:
                self.wear.set_exception(fut.exception())
                if not outer.cancelled():
                    outer.set_exception(fut.exception())
                return
            (result, files), text = fut.result()
            self.wear.set_result((files, text))
            if not outer.cancelled():
                outer.set_result(result)

        inner.add_done_callback(split)
        return outer


#: Variables of the simulated motion the demo keeps.
MOTION_VARIABLES = (
    "follower_velocity",
    "follower_position",
    "journal_offset",
    "contact_force",
    "crank_angle",
)


def _simulate_motion(size: DemoSize, params: Any) -> xr.Dataset:
    """The motion over ``size.motion_cycles`` crank cycles (variables :data:`MOTION_VARIABLES`)."""
    from jointwear.sim import run_cycles

    motion = run_cycles(params, cycles=size.motion_cycles).dataset
    motion = motion[[v for v in MOTION_VARIABLES if v in motion]]
    motion.attrs["data_origin"] = "simulated"
    return motion


def _save_motion(folder: Path, size: DemoSize, params: Any, motion: xr.Dataset) -> Path:
    return io.save(
        motion,
        folder / "sim_motion.nc",
        parameters={"simulation": params, "cycles": size.motion_cycles},
        source="jointwear (sim.dynamics) via jointwear demo",
    )


def _motion_part(
    folder: Path, size: DemoSize, params: Any, sim_motion: Path, verify: bool
) -> tuple[Path | None, Path | None, str | None]:
    """Worker part: the motion's solver-tolerance study (``verify``), then the stereo footage.

    Returns the study file, the tracked motion and why the footage is missing (or None).
    """
    ver_path = None
    if verify:
        from jointwear.compare import numerical_uncertainty

        ver = motion_verification(params, size, io.load(sim_motion))
        ver_path = io.save(
            ver,
            folder / "sim_verification_motion.nc",
            parameters={"simulation": params, "solver_rtols": list(ver["solver_rtol"].values)},
            source="jointwear (sim.dynamics) via jointwear demo",
        )
        _say("  motion verification (solver tolerance):")
        for g in numerical_uncertainty(ver).values():
            _say(f"      {g.describe()}")
    try:
        dic_path, dic_missing = _measure_motion(folder, size, sim_motion)
    except JointwearError as exc:  # the footage chain failed: say so, keep the rest
        dic_path, dic_missing = None, f"motion: the stereo DIC chain failed ({exc})"
        _say(f"  {dic_missing}")
    return ver_path, dic_path, dic_missing


def _ensemble_part(folder: Path, size: DemoSize, params: Any, motion_time: np.ndarray) -> Path:
    """Worker part: the input-uncertainty ensemble, saved as ``ensemble.nc``."""
    t0 = time.perf_counter()
    fixed = _calibrated(size)
    ens = run_ensemble(params, size, motion_time, progress=False, calibrated=fixed)
    path = io.save(
        ens,
        folder / "ensemble.nc",
        parameters={"inputs": {k: v[0] for k, v in ENSEMBLE_INPUTS.items() if k not in fixed}},
        source="jointwear (sim.wear, sim.dynamics) ensemble via jointwear demo",
    )
    _say(
        f"  ensemble: {ens.sizes['run']} runs, {int(ens.attrs.get('n_failed', 0))} failed "
        f"({time.perf_counter() - t0:.0f} s)"
    )
    return path


def _calibrated(size: DemoSize) -> tuple[str, ...]:
    """The inputs the demo calibrates (none without a calibration step)."""
    from jointwear.reports.demo_calibration import CALIBRATED

    return tuple(CALIBRATED) if size.calibration_cycles else ()


def _study(folder: Path, size: DemoSize, params: Any, pool: Executor) -> Path:
    """The verification study of the wear, its runs on ``pool`` (a :class:`_StudyPool`);
    prints its u_num."""
    from jointwear.summary import describe_study

    t0 = time.perf_counter()
    path, study = wear_verification(params, size, folder, scheduler=pool)
    _say(f"  wear verification study ({time.perf_counter() - t0:.0f} s):")
    _say("      " + describe_study(study).replace("\n", "\n      "))
    return path


PHASES = 2

#: What the demo says about the measured side (every report carries it).
SYNTHETIC_NOTE = (
    "The measured side is SYNTHETIC, generated by jointwear.datasets with a known truth and then "
    "imported and processed like real measurements: the roundness scans from a 'true' wear map "
    "(the simulated map 10 % deeper, turned by 6 degree), the stereo footage from a virtual "
    "rig whose four-bar follows its analytic kinematics with the crank "
    f"{MOTION_SPEED_FACTOR - 1:.1%} faster than the simulated one (a drive speed within "
    "tolerance; joint C's out-of-plane motion is the simulation's first harmonic). The report "
    "shows the chain working; it does not validate the model against a real rig."
)


def _phase(k: int, text: str) -> None:
    _say(f"[{k}/{PHASES}] {text}")


@dataclass
class _Parts:
    """What the first phase made: files by role, and what is missing and why."""

    sims: list[Path] = field(default_factory=list)
    meas: list[tuple[str, Path]] = field(default_factory=list)
    ensemble: Path | None = None
    verification: list[Path] = field(default_factory=list)
    missing: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=lambda: [SYNTHETIC_NOTE])
    worker_cpu: list[float] = field(default_factory=list)  # CPU [s] of each worker process
    calibration: Any = None  # the calibrate -> predict step (demo_calibration.CalibrationStep)


def _echo_part(fut: Any) -> None:
    """Print what a finished part said (a failed part's error is raised where it is awaited)."""
    if not fut.cancelled() and fut.exception() is None and fut.result()[1]:
        import typer

        typer.echo(fut.result()[1], err=True, nl=False)


def _skipped(size: DemoSize, parts: _Parts, sim_ok: bool, metrology_ok: bool) -> None:
    """Record the parts this size or installation does not run (and say so)."""
    if not sim_ok:
        parts.missing.append("simulation: jointwear.sim is not available, nothing was simulated")
    elif not size.verification_replicates:
        parts.missing.append(
            "verification: the sim verify study is skipped with --quick; u_num of the wear is "
            "the simulation's own wear_depth_u (update interval and cycle-to-cycle "
            "variability; the wear grid is not assessed)"
        )
    if sim_ok and not size.calibration_cycles:
        parts.missing.append(
            "calibration: skipped with --quick (it needs the verification study's u_num and "
            "about 25 more wear runs); kw is the nominal one, not calibrated on the bore; run "
            "'jointwear demo' without --quick to calibrate on one snapshot and validate on another"
        )
    if not (size.ensemble_runs and sim_ok):
        _say("  ensemble skipped (--quick): u_input not assessed")
        parts.missing.append(
            "input uncertainty: no ensemble with --quick, so u_input is not assessed and the "
            "V&V 20 criteria are NOT ASSESSED; run 'jointwear demo' without --quick"
        )
    if not metrology_ok:
        parts.missing.append(
            "wear maps: the metrology chain (jointwear.metrology, jointwear.datasets.instruments) "
            "is not available, so no measured wear map was made"
        )


def _run_parts(out: Path, size: DemoSize, workers: int) -> _Parts:
    """Phase 1: simulate and measure, the independent parts side by side on ``workers``.

    The motion is simulated here first (it is short and every motion part needs it); then the
    pool runs the wear run with the roundness scans, the motion study with the footage, the
    ensemble, and the runs of the wear verification study, whose results this process gathers.
    """
    from jointwear.reports.demo_pool import run_part, worker_pool

    parts = _Parts()
    sim_ok = _available("jointwear.sim", "simulate_wear", "run_cycles", "PARAMETER_SETS")
    metrology_ok = _available("jointwear.metrology", "wear_map") and _available(
        "jointwear.datasets.instruments", "generate", "write"
    )
    _skipped(size, parts, sim_ok, metrology_ok)
    if not sim_ok:
        return parts
    params = _params(size)
    t0 = time.perf_counter()
    motion = _simulate_motion(size, params)  # before the fork: the workers inherit its kernels
    verify = bool(size.verification_replicates)
    with worker_pool(workers, parts.worker_cpu) as pool:
        sim_motion = _save_motion(out, size, params, motion)
        _say(f"  simulated motion: {size.motion_cycles:g} crank cycles")
        others = [pool.submit(run_part, _motion_part, out, size, params, sim_motion, verify)]
        if size.ensemble_runs:
            motion_time = np.asarray(motion["time"].values, dtype=float)
            others.append(pool.submit(run_part, _ensemble_part, out, size, params, motion_time))
        for fut in others:
            fut.add_done_callback(_echo_part)
        if verify:  # the compared wear run is one of the study's runs
            study_pool = _StudyPool(pool, out, size, params, metrology_ok)
            wear = study_pool.wear
            wear.add_done_callback(_echo_part)
            study = _study(out, size, params, study_pool)
        else:
            wear = pool.submit(run_part, _wear_part, out, size, params, metrology_ok)
            wear.add_done_callback(_echo_part)
            study = None
        sim_wear, metrology, early = wear.result()[0]
        if early is not None and study is not None:
            from jointwear.reports.demo_calibration import calibrate_and_predict

            parts.calibration = calibrate_and_predict(out, size, params, early, study, pool)
        motion_ver, dic_path, dic_missing = others[0].result()[0]
        parts.ensemble = others[1].result()[0] if size.ensemble_runs else None
    _say(f"  simulated and measured ({time.perf_counter() - t0:.0f} s)")
    parts.sims += [sim_wear, sim_motion]
    parts.verification += [p for p in (study, motion_ver) if p is not None]
    parts.meas += [("metrology", metrology)] if metrology is not None else []
    parts.meas += [("DIC", dic_path)] if dic_path is not None else []
    parts.missing += [dic_missing] if dic_missing else []
    if parts.ensemble is not None:
        parts.notes.append(
            f"Input uncertainty u_input: spread of a {size.ensemble_runs}-run ensemble over "
            + ", ".join(
                f"{k} (±{v[0]:.1%})"
                for k, v in ENSEMBLE_INPUTS.items()
                if k not in _calibrated(size)
            )
            + f", run for {size.ensemble_cycles:g} cycles (reduced; wear spreads are scaled "
            "relative to the compared run) - see the uncertainty budget."
        )
    if parts.calibration is not None:
        from jointwear.reports.demo_calibration import calibration_notes

        parts.notes += calibration_notes(parts.calibration, metrology, size)
    if dic_path is not None:
        parts.notes.append(
            "Motion: only the in-plane follower velocity (x, y) is a validation target (the "
            "default of jointwear compare). The virtual rig prescribes the out-of-plane motion of "
            "joint C as one sinusoid (the first harmonic of the simulated motion), so its z "
            "component is not a measurement of the mechanism; tracked positions are in the "
            "calibration's world frame (the board), not the mechanism frame, and are not compared."
        )
    return parts


def _compare_and_report(out: Path, size: DemoSize, quick: bool, parts: _Parts) -> Path:
    """Phase 2: compare, write ``metrics.nc`` and the report, print the outcome."""
    from jointwear.compare import as_ensemble, compare, save_comparison
    from jointwear.compare.outcome import card_lines, origin_line, outcome_lines
    from jointwear.reports.builder import ReportInput, build_report

    sims, meas = parts.sims, parts.meas
    sim_ds = [io.load(p) for p in sims]
    meas_ds = [io.load(p) for _, p in meas]
    motion = any(role == "DIC" for role, _ in meas)
    ens_paths = [parts.ensemble] if parts.ensemble is not None else []
    ens_ds = [io.load(p) for p in ens_paths]
    if parts.calibration is not None:  # the posterior prediction is the compared wear simulation
        from jointwear.reports.demo_calibration import with_prediction

        sims, sim_ds, ens_paths, ens_ds = with_prediction(
            parts.calibration, sims, [p for _, p in meas], ens_paths, ens_ds
        )
    ver_ds = [io.load(p) for p in parts.verification]
    result = compare(
        sim_ds,
        [_in_plane(d) if role == "DIC" else d for (role, _), d in zip(meas, meas_ds, strict=True)],
        variables=["follower_velocity"] if motion else None,
        ensemble=as_ensemble(ens_ds, [p.name for p in ens_paths]) if ens_ds else None,
        verification=ver_ds or None,
    )
    save_comparison(
        result,
        out / "metrics.nc",
        inputs=[*sims, *(p for _, p in meas), *ens_paths],
        parents=[*sim_ds, *meas_ds],
    )
    inputs = [ReportInput("simulation", p, d) for p, d in zip(sims, sim_ds, strict=True)]
    inputs += [ReportInput(role, p, d) for (role, p), d in zip(meas, meas_ds, strict=True)]
    inputs += [ReportInput("ensemble", p, d) for p, d in zip(ens_paths, ens_ds, strict=True)]
    inputs += [
        ReportInput("verification", p, d) for p, d in zip(parts.verification, ver_ds, strict=True)
    ]
    report = build_report(
        result,
        out / "report.html",
        inputs=inputs,
        verification=ver_ds,
        missing=parts.missing,
        notes=[*parts.notes, *_outcome_notes(result, parts)],
        title="jointwear demo: wear of the clearance joint, simulation against measurement",
        parameters={"demo": {"quick": quick, "size": size.__dict__}},
    )
    _say(origin_line(result))
    for line in card_lines(result):
        _say("  " + line)
    for line in outcome_lines(result):
        _say(line)
    if result.any_failed:
        failed = result.decisions[result.decisions.state == "fail"]
        why = "; ".join(f"{r.quantity}: {r.value} [{r.criterion}]" for r in failed.itertuples())
        n = len(failed)
        raise ValidationFailed(
            f"the report was written ({report}); exit code 1 because {n} "
            f"criteri{'on' if n == 1 else 'a'} failed - {why}. The measured side is synthetic: "
            "this is the honest outcome of the demo's data, see the report's decision card"
        )
    return report


def _outcome_notes(result: Any, parts: _Parts) -> list[str]:
    """What the comparison's outcome means for the demo's known truths: the resolution the
    calibrated comparison reached, and what the motion criteria decide about a rig running
    :data:`MOTION_SPEED_FACTOR` faster than the model."""
    rows = result.decisions[result.decisions.state.isin(["pass", "fail"])]
    notes = []
    wear = [r for r in rows.itertuples() if r.key in ("max_wear_depth", "wear_field")]
    if parts.calibration is not None and wear:
        notes.append(
            "Resolution reached with the calibrated prediction: "
            + "; ".join(f"{r.quantity} {r.state.upper()}, {r.resolution}" for r in wear)
            + ". The planted 10 % depth difference is absorbed by the calibrated kw (that is "
            "what calibration is for); the 6-degree turn remains the model error to find."
        )
    motion = [r for r in rows.itertuples() if str(r.key).startswith("follower_velocity")]
    if motion:
        notes.append(
            f"Motion truth: the rig's crank runs {MOTION_SPEED_FACTOR - 1:.1%} faster than the "
            "simulated one, a difference within the drive's tolerance that the model does not "
            "know; the motion criteria decide "
            + "; ".join(f"{r.quantity} {r.state.upper()} ({r.resolution})" for r in motion)
            + ". A criterion that passes has not seen the speed difference: it is below "
            "its resolution."
        )
    return notes


def run_demo(out: Path, *, quick: bool = False, workers: int | None = None) -> Path:
    """Run the whole chain on the embedded default data and write a validation report.

    Parameters
    ----------
    out : Path
        Output folder (created); receives the simulated and measured files, the ensemble,
        ``metrics.nc`` and ``report.html``.
    quick : bool
        Reduced size and no ensemble (u_input is then not assessed), in this process.
    workers : int, optional
        Worker processes of the full run (default: one per core, at most
        :data:`~jointwear.reports.demo_pool.MAX_WORKERS`); 1 runs everything in this process.

    Returns
    -------
    Path
        The HTML report.

    Raises
    ------
    ValidationFailed
        A validation criterion failed (exit code 1); the report is written first and the
        message says which criteria failed and where the report is.
    """
    from jointwear.reports.demo_pool import MAX_WORKERS, available_cores, quiet_wear_log

    quiet_wear_log()
    out = Path(out)
    size = QUICK if quick else FULL
    out.mkdir(parents=True, exist_ok=True)
    io.check_writable(out / "report.html", what="--out")
    if workers is None:
        workers = 1 if quick else min(available_cores(), MAX_WORKERS)
    _say(f"jointwear demo ({'quick' if quick else 'full'} size) -> {out}")
    where = f"{workers} worker processes" if workers > 1 else "this process"
    _phase(
        1,
        "simulating and measuring in "
        + where
        + (
            ": the wear run and virtual roundness scans, the motion"
            + ("" if quick else ", its stereo footage, the ensemble and the verification study")
        ),
    )
    parts = _run_parts(out, size, workers)
    if not parts.sims or not parts.meas:
        raise ValidationFailed("the demo could not compare anything: " + "; ".join(parts.missing))
    _phase(2, "comparing and writing the report")
    try:
        return _compare_and_report(out, size, quick, parts)
    finally:
        _say(_cpu_line(parts.worker_cpu))


def _cpu_line(each: list[float]) -> str:
    """CPU time (user + system) of this process and of the worker processes it has joined
    (``each``: of every worker, where known)."""
    try:
        import resource
    except ImportError:  # not POSIX
        return "CPU: not measured on this system"
    own, workers = (resource.getrusage(w) for w in (resource.RUSAGE_SELF, resource.RUSAGE_CHILDREN))
    return (
        f"CPU: {own.ru_utime + own.ru_stime:.1f} s in this process, "
        f"{workers.ru_utime + workers.ru_stime:.1f} s in worker processes"
        + (f" ({', '.join(f'{t:.1f}' for t in each)} s each)" if each else "")
    )
