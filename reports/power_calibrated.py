"""Power of the validation verdict with the calibrate-then-validate path (issue 36 item 5).

The question: when the wear coefficient kw is calibrated on an earlier measured snapshot of the
truth and the posterior prediction is validated at a later one, does calibrating kw absorb the
other errors of a wrong model (friction, speed, offset, clearance, the tilt form) so that the
criteria that saw them without calibration no longer do, and how much does the narrower U_val
raise the power for the rest? A kw-scaled model is absorbed by design (kw is what is
calibrated): one is included to show it.

Per truth (:data:`jointwear.reports.power.TRUTHS`), the truth is run once with both snapshots
(``calibration_cycles`` and ``base.cycles``) and each replicate scans both with its own noise
(one before-wear scan per replicate, as in a test), imported and made wear maps as a user
would (:func:`jointwear.reports.power._measure`). Per candidate (the right model or a graded
wrong model of :data:`~jointwear.reports.power.WRONG_MODELS`):

* **with calibration**: what ``jointwear sim calibrate`` / ``sim predict`` / ``compare`` do,
  through the library: a ``--params`` TOML of the candidate's rig, a calibration spec with kw
  uniform ±``prior_half_width`` around the candidate's own kw on the earlier map (every other
  key at the command's default: 12 training runs, seed 0, max depth, worn volume and
  cylindricity), u_num from the right model's own ``sim verify`` study (``--verification``) or,
  for a wrong model, its run's own max-depth u stated as ``u_num_rel``; then
  ``predict(--samples prediction_samples)`` at the later snapshot and ``compare_files`` of the
  prediction with the later map, with an ensemble of the inputs not calibrated (bore radius,
  friction) and the same u_num. The training design does not depend on the data: it is run
  once per candidate and reused by every replicate (``--resume`` on a copy), as a user with
  several bores would. A calibration refused by its posterior predictive check (no kw in the
  prior fits the data: the model cannot fit) is its own outcome, *refused at calibration*,
  counted as a detection in its own column; any other refusal (emulator, chain) is
  *not decided* and said so; neither is counted as a pass or a criterion fail.
* **without calibration**, on the same later maps: the candidate at its prior inputs with its
  own input ensemble (kw ± 15 %, bore radius, friction) and u_num, exactly as
  :func:`jointwear.reports.power.run_power` (the right model: its own start phase per replicate,
  its study), so that the two columns are paired.

The right model runs on its own grid (4 more points around the bore), the fixed update interval
of its study and a start phase of ``right_phase_deg`` (the truth's is 0); its training runs each
start at their own phase (the calibration draws it). The prediction's runs share the rig's start
phase, so its replicates differ by the measurement (noise, and through it the posterior), not by
the phase. Results per candidate: per-criterion fail rates with and without calibration, the
refused-at-calibration rate, the detection rate (any criterion failed or refused), the median
U_val/|D| of the maximum depth both ways and the posterior of kw relative to the truth's.
"""

from __future__ import annotations

import json
import shutil
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from jointwear.errors import JointwearError
from jointwear.reports import power as pw

__all__ = [
    "CalibratedSize",
    "CAL_CI_SIZE",
    "CAL_BENCH_SIZE",
    "CALIBRATED",
    "run_power_calibrated",
    "calibrated_rates",
    "kw_over_truth_median",
]

#: the calibrated input (the demo's and bench_calibration's choice: the depth scale)
CALIBRATED = "wear.kw"


@dataclass(frozen=True)
class CalibratedSize:
    """Size of the with-calibration power study.

    Attributes
    ----------
    base : PowerSize
        The runs' size (grid, validation cycles ``base.cycles``, ensembles, the right model's
        study): the same as :func:`jointwear.reports.power.run_power`'s, whose cached runs it
        reuses.
    calibration_cycles : float
        The earlier snapshot the calibration uses [cycles].
    prediction_samples : int
        Posterior samples simulated by ``sim predict`` (its ``--samples``).
    truths : tuple of str
        Keys of :data:`jointwear.reports.power.TRUTHS`.
    wrong : dict of str to tuple of str
        Per truth, the wrong models compared.
    replicates : dict of str to int
        Per truth, the right model's replicates.
    wrong_replicates : int
        Replicates of each wrong model (the first of the truth's).
    prior_half_width : float
        kw's uniform prior: ± this fraction of the candidate's own kw.
    right_phase_deg : float
        Start phase of the right model's rig [degree].
    training_runs : int
        The calibration's ``samples`` (training runs of the emulator).
    wear_updates : int
        Every candidate's rig runs the fixed wear update ``base.cycles / wear_updates`` (the
        right model's study's finest interval, ``STUDY_UPDATES``, when it has a study).
    paired : bool
        Also compare every candidate without calibration on the same maps.
    """

    base: pw.PowerSize
    calibration_cycles: float
    prediction_samples: int
    truths: tuple[str, ...]
    wrong: dict[str, tuple[str, ...]]
    replicates: dict[str, int]
    wrong_replicates: int
    prior_half_width: float = 0.5
    right_phase_deg: float = 37.0
    training_runs: int = 24
    wear_updates: int = pw.STUDY_UPDATES
    paired: bool = True

    def describe(self) -> dict[str, Any]:
        """JSON-ready record."""
        out = asdict(self)
        out["base"] = {
            k: v for k, v in out["base"].items() if k not in ("truths", "wrong", "truth_replicates")
        }
        return out


#: CI: the reference truth calibrated at 2e5 and validated at 4e5 cycles on 10 x 36 points (the
#: power CI size), 2 right-model replicates, kw x 1.5 (absorbed) and joint offset 0, 3 prediction
#: runs, 4-member ensembles, no study; about 100 CPU s, most of it the 24 training runs per candidate
CAL_CI_SIZE = CalibratedSize(
    pw.CI_SIZE, 2e5, 3, ("default",), {"default": ("kw x 1.5", "joint offset 0")},
    {"default": 2}, 1, wear_updates=8, paired=False,
)  # fmt: skip
#: the benchmark: the tilt-1000 truth (calibrated on 2e5, validated at 4e5 cycles, as issue 35's
#: benchmark) with every non-kw graded error of issue 36 and kw x 1.5; the runs' size is the
#: power benchmark's (10 x 36 points, 8-member ensembles, the right model's 4-level study);
#: 20 right-model replicates, 5 per wrong model (``--wrong-replicates`` of the benchmark: more
#: where the machine allowed, each candidate's count is in its results), 4 prediction runs (the CPU of the shared
#: 2-core machine: each replicate of each candidate calibrates and runs 4 predictions)
CAL_BENCH_SIZE = CalibratedSize(
    pw.BENCH_SIZE, 2e5, 4, ("tilt stiffness 1000",),
    {
        "tilt stiffness 1000": ("tilt stiffness 0", "kw x 1.5", "friction x 2", "speed -20 %",
                                "joint offset 0", "clearance +20 %"),
        # run with the benchmark's --truth (the other truths, where the machine allowed)
        "clearance 0.7 mm": ("kw x 1.5", "speed -20 %", "clearance +20 %", "friction x 2",
                             "joint offset 0"),
        "default": ("kw x 1.5", "speed -20 %", "clearance +20 %", "friction x 2",
                    "joint offset 0"),
    },
    {"tilt stiffness 1000": 20, "clearance 0.7 mm": 10, "default": 10}, 5,
)  # fmt: skip


def _rig_toml(overrides: dict[str, float], base: pw.PowerSize, extra: int, wear: Any) -> str:
    """The ``--params`` file of a candidate: its overrides, grid and wear-update scheme."""
    import tomli_w

    tables: dict[str, dict[str, Any]] = {
        "joint": {"n_layers": int(base.n_layers), "n_points": int(base.n_points + extra)}
    }
    for key, value in overrides.items():
        section, attr = key.split(".")
        tables.setdefault(section, {})[attr] = float(value)
    if wear is not None and wear.scheme == "fixed":
        tables.setdefault("wear", {}).update(scheme="fixed", dn=int(wear.dn))
    return tomli_w.dumps(tables)


def _spec_toml(data: Path, size: CalibratedSize, kw: float, u_num_rel: float | None) -> str:
    """The calibration spec: kw uniform ±``prior_half_width`` around ``kw`` on the map
    ``data``, ``training_runs`` samples; every other key at ``jointwear sim calibrate``'s
    default."""
    import tomli_w

    half = size.prior_half_width
    calibrate: dict[str, Any] = {
        "data": [data.name],
        "cycles": int(round(size.calibration_cycles)),
        "samples": int(size.training_runs),
    }
    if u_num_rel is not None:
        calibrate["u_num_rel"] = float(u_num_rel)
    prior = {"distribution": "uniform", "bounds": [(1 - half) * kw, (1 + half) * kw]}
    return tomli_w.dumps({"calibrate": calibrate, "parameters": {CALIBRATED: prior}})


def _own_u_num_rel(run: Any) -> float:
    """A wrong model's stated u_num: its adaptive run's own max-depth u / max depth (what the
    comparison without calibration used for it, as one fraction)."""
    u = float(run["max_wear_depth_u"].isel(cycles=-1))
    return u / float(run["max_wear_depth"].isel(cycles=-1))


@dataclass(frozen=True)
class _Candidate:
    """One candidate model of a truth: its rig and its uncertainty sources."""

    name: str
    overrides: dict[str, float]
    folder: Path
    extra_points: int
    wear: Any
    kw: float
    u_num_rel: float | None
    study: Path | None
    ensemble: Path
    prior_run: Callable[[int], Any]
    prior_ensemble: Callable[[], Any]


def _candidates(
    size: CalibratedSize, truth: str, runs: Path, only: tuple[str, ...] | None
) -> list[_Candidate]:
    """The right model and the wrong models of ``truth`` (their shared runs made or cached);
    ``only``: these of them."""
    from jointwear.sim import WearSettings, apply_overrides

    base, over = size.base, pw.TRUTHS[truth]
    right_settings, study = pw._study(base, over, runs)

    def ens_right() -> Any:
        return pw._cached(runs, "ensemble_right", lambda: pw._ensemble(base, over))

    fixed = WearSettings(scheme="fixed", dn=int(base.cycles // size.wear_updates))
    out = []
    for name in ("right", *size.wrong.get(truth, ())):
        if only is not None and name not in only:
            continue
        is_right = name == "right"
        o = dict(over) if is_right else pw._wrong_overrides(base, over, name)
        folder = _calibrated_folder(runs, size) / pw._slug(name)
        folder.mkdir(parents=True, exist_ok=True)
        cal_ens = f"ensemble_{pw._slug(name)}_not_calibrated"
        pw._cached(runs, cal_ens, lambda o=o: pw._ensemble(base, o, calibrated=(CALIBRATED,)))
        kw = float(apply_overrides(pw._params(base), WearSettings(), o or None)[1].kw)
        if is_right:

            def prior_run(r: int, o=o) -> Any:
                phase = float((37 + 97 * r) % 360)
                return pw._cached(
                    runs,
                    f"right_{r}",
                    lambda: pw._simulate(
                        base, {**o, "mechanism.initial_crank_angle_deg": phase}, right_settings, 4
                    ),
                )

            rel = None if study is not None else _own_u_num_rel(prior_run(0))
            o = {**o, "mechanism.initial_crank_angle_deg": size.right_phase_deg}
            wear = right_settings if study is not None else fixed
            cand = _Candidate(name, o, folder, 4, wear, kw, rel, runs / "study.nc" if study is not None else None,
                              runs / f"{cal_ens}.nc", prior_run, ens_right)  # fmt: skip
        else:
            run = pw._cached(runs, f"wrong_{pw._slug(name)}", lambda o=o: pw._simulate(base, o))

            def ens(name=name, o=o) -> Any:
                return pw._cached(runs, f"ensemble_{pw._slug(name)}", lambda: pw._ensemble(base, o))

            cand = _Candidate(name, o, folder, 0, fixed, kw, _own_u_num_rel(run), None,
                              runs / f"{cal_ens}.nc", lambda _r, run=run: run, ens)  # fmt: skip
        (folder / "rig.toml").write_text(
            _rig_toml(cand.overrides, base, cand.extra_points, cand.wear)
        )
        out.append(cand)
    return out


def _calibrated_folder(runs: Path, size: CalibratedSize) -> Path:
    """The folder of the calibrations at ``size`` (its own parts in the name: another prior,
    design or prediction size never reuses a posterior made for this one)."""
    import hashlib

    own = {k: v for k, v in size.describe().items() if k not in ("base", "truths", "wrong",
           "replicates", "wrong_replicates", "paired")}  # fmt: skip
    tag = hashlib.sha1(json.dumps(own, sort_keys=True).encode()).hexdigest()[:10]
    return runs / f"calibrated_{tag}"


def _refusal(exc: Exception) -> str:
    """The kind of a refused calibration: the predictive check (the model cannot fit the data:
    a detection) or another reason (not decided)."""
    return "refused_ppc" if "posterior predictive check failed" in str(exc) else "refused_other"


def _calibrated(
    size: CalibratedSize, cand: _Candidate, r: int, early: Path, late: Path, kw_truth: float
) -> dict[str, Any]:
    """Calibrate, predict and compare one replicate of one candidate (cached on disk)."""
    from jointwear import io
    from jointwear.compare import Criteria, compare_files
    from jointwear.sim.calibrate import CalibrationRefused, calibrate, design_path, predict

    f = cand.folder
    post, pred = f / f"posterior_{r}.nc", f / f"prediction_{r}.nc"
    refused = f / f"refused_{r}.json"
    master = f / "design-master.nc"
    spec = f / f"calibrate_{r}.toml"
    shutil.copy(early, f / early.name)
    spec.write_text(_spec_toml(early, size, cand.kw, cand.u_num_rel))
    ver = [cand.study] if cand.study is not None else []
    rec: dict[str, Any] = {"replicate": r}
    if refused.is_file():
        return {**rec, **json.loads(refused.read_text()), "outcome": None}
    if not post.is_file():
        design = design_path(post, size.calibration_cycles)
        if master.is_file() and not design.is_file():
            shutil.copy(master, design)
        t0 = time.process_time()
        try:
            calibrate(
                spec, out=post, params=f / "rig.toml", verification=ver, workers=0, resume=True
            )
            rec["calibrate_cpu_s"] = time.process_time() - t0
        except CalibrationRefused as exc:
            out = {"calibration": _refusal(exc), "message": str(exc)}
            refused.write_text(json.dumps(out))
            return {**rec, **out, "outcome": None}
        finally:
            if design.is_file() and not master.is_file():
                shutil.copy(design, master)
    ds = io.load(post, validate=False)
    rec["calibration"] = "ok"
    rec["kw_over_truth"] = {
        k: float(ds[f"posterior_{k}"][0]) / kw_truth for k in ("mean", "q025", "q975")
    }
    rec["kw_sd_over_mean"] = float(ds["posterior_sd"][0] / ds["posterior_mean"][0])
    if not pred.is_file():
        t0 = time.process_time()
        predict(
            post, cycles=size.base.cycles, out=pred, samples=size.prediction_samples, workers=0,
            resume=True,
        )  # fmt: skip
        rec["predict_cpu_s"] = time.process_time() - t0
    crit = Criteria(wear_u_num_rel=cand.u_num_rel) if cand.u_num_rel is not None else Criteria()
    c = compare_files(
        [pred], [late], f / f"metrics_{r}.nc", criteria=crit, cycles=size.base.cycles,
        ensemble=[cand.ensemble], verification=ver,
    )  # fmt: skip
    return {**rec, "outcome": pw._outcome(c), "summary": c.summary()}


def _without(size: CalibratedSize, cand: _Candidate, r: int, late: Any) -> dict[str, Any]:
    """The candidate at its prior inputs against the same later map (as run_power does)."""
    from jointwear import io
    from jointwear.compare import Criteria, compare

    ver = [io.load(cand.study, validate=False)] if cand.study is not None else None
    c = compare(cand.prior_run(r), late, ensemble=[cand.prior_ensemble()], verification=ver,
                criteria=Criteria())  # fmt: skip
    return pw._outcome(c)


def calibrated_rates(reps: list[dict[str, Any]]) -> dict[str, Any]:
    """Rates over the replicates of one candidate with calibration.

    ``fail_rate`` per criterion and ``any_fail`` count a replicate refused at calibration as not
    failed (it was not validated); ``refused_at_calibration`` is its own rate, ``detected`` the
    share failed or refused by the predictive check, ``not_decided`` the share refused for
    another reason (emulator, chain).
    """
    n = len(reps)
    outs = [x["outcome"] for x in reps if x["outcome"] is not None]
    ppc = sum(x["calibration"] == "refused_ppc" for x in reps)
    failed = sum(o["n_fail"] > 0 for o in outs)
    return {
        **pw._rates(outs, n),  # replicates, any_fail, fail_rate, decided_rate: shares of all n
        "validated": len(outs),
        "refused_at_calibration": ppc / n,
        "not_decided": sum(x["calibration"] == "refused_other" for x in reps) / n,
        "detected": (failed + ppc) / n,
    }


def kw_over_truth_median(reps: list[dict[str, Any]]) -> float | None:
    """Median over the calibrated replicates of kw's posterior mean / the truth's kw."""
    import numpy as np

    v = [x["kw_over_truth"]["mean"] for x in reps if x.get("kw_over_truth")]
    return float(np.median(v)) if v else None


def _u_val_over_d(outs: list[dict[str, Any]]) -> float | None:
    """Median U_val / |D| of the maximum depth over the outcomes that state it."""
    import numpy as np

    v = [
        o["budget"]["max_wear_depth"]["U_val"] / abs(o["budget"]["max_wear_depth"]["value_meas"])
        for o in outs
        if o is not None and "max_wear_depth" in o["budget"]
    ]
    return float(np.median(v)) if v else None


def _one_truth(
    size: CalibratedSize,
    name: str,
    work: Path,
    say: Callable[[str], None],
    only: tuple[str, ...] | None,
) -> dict:
    """Every candidate of one truth, with and without calibration, on the same later maps."""
    from jointwear.sim import WearSettings, apply_overrides

    t0 = time.process_time()
    base, over = size.base, pw.TRUTHS[name]
    runs = pw._cache_folder(work, base, name)
    c1, c2 = size.calibration_cycles, base.cycles
    truth = pw._cached(
        runs,
        f"truth_{c1:.0f}_{c2:.0f}",
        lambda: _two_snapshots(base, over, c1),
    )
    kw_truth = float(apply_overrides(pw._params(base), WearSettings(), over or None)[1].kw)
    cands = _candidates(size, name, runs, only)
    say(f"{name}: truth and candidates' shared runs ({time.process_time() - t0:.0f} s)")
    n_right = size.replicates.get(name, size.wrong_replicates)
    maps: dict[int, tuple[Path, Path, Any] | None] = {}
    refused_scans = []
    for r in range(n_right):
        try:
            pair = []
            for c in (c1, c2):
                key = f"cal_measured_{c:.0f}_{r}"
                ds = pw._cached(
                    runs, key, lambda c=c, r=r: pw._measure(truth, base, r, runs, cycles=c)
                )
                pair.append((runs / f"{key}.nc", ds))
            maps[r] = (pair[0][0], pair[1][0], pair[1][1])
        except JointwearError as err:  # the wear map refused a scan: counted, not compared
            maps[r] = None
            refused_scans.append({"replicate": r, "message": str(err)})
    result: dict[str, Any] = {}
    for cand in cands:
        t1 = time.process_time()
        n = n_right if cand.name == "right" else size.wrong_replicates
        with_cal, without = [], []
        for r in [r for r in range(n) if maps.get(r) is not None]:
            early, late, late_ds = maps[r]
            with_cal.append(_calibrated(size, cand, r, early, late, kw_truth))
            if size.paired:
                without.append(_without(size, cand, r, late_ds))
            say(f"{name}: {cand.name} replicate {r + 1}/{n} ({time.process_time() - t0:.0f} s)")
        entry = {
            "with_calibration": {
                **calibrated_rates(with_cal),
                "u_val_over_d_max_depth_median": _u_val_over_d([x["outcome"] for x in with_cal]),
                "kw_over_truth_median": kw_over_truth_median(with_cal),
                "replicates_detail": with_cal,
            },
            "without_calibration": {
                **pw._rates(without),
                "u_val_over_d_max_depth_median": _u_val_over_d(without),
                "outcomes": without,
            } if without else "not run (size.paired is False)",
            "u_num": (
                "own sim verify study" if cand.study is not None
                else f"stated u_num_rel {cand.u_num_rel:.3g} (own run's max-depth u)"
            ),
            "cpu_s": time.process_time() - t1,
        }  # fmt: skip
        if cand.name != "right":
            entry.update(input=pw.WRONG_MODELS[cand.name][0], change=pw.WRONG_MODELS[cand.name][1])
        result[cand.name] = entry
    return {
        "overrides": over,
        "kw_truth": kw_truth,
        "candidates": result,
        "measurements_refused": refused_scans,
        "cpu_s": time.process_time() - t0,
    }


def _two_snapshots(base: pw.PowerSize, over: dict[str, float], c1: float) -> Any:
    """The truth run with both snapshots (the calibration's and the validation's)."""
    from jointwear.sim import simulate_wear

    ds = simulate_wear(
        pw._params(base), cycles=base.cycles, snapshots=[c1, base.cycles], overrides=over or None
    )
    ds.attrs["data_origin"] = "simulated"
    return ds


def run_power_calibrated(
    size: CalibratedSize = CAL_BENCH_SIZE,
    *,
    folder: str | Path | None = None,
    progress: Callable[[str], None] | None = None,
    on_truth: Callable[[dict[str, Any]], None] | None = None,
    only: tuple[str, ...] | None = None,
) -> dict[str, Any]:
    """Run the with-calibration power study; return its results (JSON-ready).

    ``only``: these candidates ("right" and/or names of wrong models; parts run in separate
    processes once the first has made the truth's scans). ``folder`` keeps every run, scan, posterior and prediction (the same cache as
    :func:`jointwear.reports.power.run_power`'s: its runs are reused); ``on_truth`` receives the
    results so far after each truth.

    Returns
    -------
    dict
        ``size``; per truth (``truths``) and candidate (``candidates``): ``with_calibration``
        (:func:`calibrated_rates`, the posterior of kw and the verdict per replicate) and
        ``without_calibration`` (the rates of :func:`jointwear.reports.power.run_power` on the
        same maps); CPU seconds.
    """
    say = progress or (lambda _m: None)
    return pw._each_truth(
        size.describe(),
        size.truths,
        lambda name, work: _one_truth(size, name, work, say, only),
        folder,
        on_truth,
    )
