"""Benchmark: does the calibration recover kw on a truth that is not the default rig?

Truth: the rig with ``joint.tilt_stiffness = 1000`` N m/rad and kw = 1.15 x the default (on a
reduced bore grid and few cycles, so that the whole study fits a shared 2-core machine: the
size is stated in the JSON). Each replicate starts the truth at another crank angle (phase)
and adds its own measurement noise (1 % of the peak depth per point, stated as the map's
``wear_depth_u``); kw is calibrated (prior uniform ±50 % around the default, the model's form
right) on the early snapshot's band quantities. Figures:

* coverage: the share of replicates whose 95 % posterior interval holds the true kw;
* the posterior's sd/mean of kw (median over replicates) against the prior's;
* U_val of the band's maximum depth relative to D, validating at the later snapshot: "before"
  with the prior's ensemble as u_input (the model at the prior mean), "after" with the
  posterior prediction (``sim predict``), both with the same stated u_num;
* the wrong model form (tilt stiffness 0 against the tilt-1000 truth) calibrated and validated
  the same way: refused by the calibration's predictive check, or the criteria that fail;
* the CPU time of the training design, of one calibration and of one prediction.

Run: ``python benchmarks/bench_calibration.py`` (``--quick``: 3 replicates, CI size; results
go to benchmarks/results/calibration.json, or calibration_quick.json with --quick).
"""

from __future__ import annotations

import dataclasses
import json
import shutil
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _common import write_results  # noqa: E402

from jointwear import io  # noqa: E402

QUICK = "--quick" in sys.argv
SIZE = {
    "replicates": 3 if QUICK else 10,
    "n_layers": 5 if QUICK else 7,
    "n_points": 24 if QUICK else 36,
    "calibration_cycles": 200 if QUICK else 400,
    "validation_cycles": 400 if QUICK else 800,
    "training_runs": 40,
    "prediction_runs": 4 if QUICK else 8,
    "wear_update": "fixed dn = 100 cycles",
}
TILT, KW_FACTOR, NOISE, U_NUM_REL = 1000.0, 1.15, 0.01, 0.02


def base_toml(size: dict[str, Any], tilt: float = TILT) -> str:
    return (
        f"[joint]\nn_layers = {size['n_layers']}\nn_points = {size['n_points']}\n"
        f"tilt_stiffness = {tilt}\n"
        '[wear]\nscheme = "fixed"\ndn = 100\nsettle_cycles = 0.25\ninitial_settle_cycles = 0.5\n'
    )


def truth_maps(folder: Path, size: dict[str, Any], rep: int, kw: float) -> tuple[Path, Path]:
    """The truth's measured maps (early, late) of replicate ``rep``: own phase, own noise."""
    from jointwear.params import from_mapping, read_toml
    from jointwear.sim import WearSettings, load_parameters, simulate_wear

    base = folder / "base.toml"
    p = load_parameters(base)
    p = dataclasses.replace(
        p, mechanism=dataclasses.replace(p.mechanism, initial_crank_angle_deg=37.0 * rep)
    )
    w = dataclasses.replace(
        from_mapping(WearSettings, read_toml(base)["wear"], where="wear"), kw=kw
    )
    c1, c2 = size["calibration_cycles"], size["validation_cycles"]
    ds = simulate_wear(p, cycles=c2, settings=w, snapshots=[c1, c2])
    paths = []
    for c in (c1, c2):
        m = ds.sel(cycles=c)[["wear_depth"]].drop_vars("cycles")
        u = NOISE * float(m["wear_depth"].max())
        rng = np.random.default_rng([rep, int(c)])
        noisy = m["wear_depth"] + u * rng.standard_normal(m["wear_depth"].shape)
        m["wear_depth"] = noisy.assign_attrs(ds["wear_depth"].attrs)
        m["wear_depth_u"] = (m["wear_depth"] * 0 + u).assign_attrs(
            units="m", long_name="standard uncertainty of wear_depth", coverage_factor=1
        )
        m.attrs = {"data_origin": "synthetic", "cycles": c, "bearing_radius_m": 8e-3}
        path = folder / f"truth-{rep}-{c}.nc"
        io.save(m, path)
        paths.append(path)
    return paths[0], paths[1]


def spec_text(early: Path, size: dict[str, Any], kw0: float) -> str:
    return (
        f'[calibrate]\ndata = ["{early.name}"]\ncycles = {size["calibration_cycles"]}\n'
        f"samples = {size['training_runs']}\nseed = 1\nu_num_rel = {U_NUM_REL}\n"
        '[parameters."wear.kw"]\ndistribution = "uniform"\n'
        f"bounds = [{0.5 * kw0!r}, {1.5 * kw0!r}]\n"
    )


def compared(folder: Path, sim: Path, meas: Path, ens: list[Path], cycles: float):
    """``jointwear compare`` of ``sim`` (with the ensembles ``ens``) and ``meas``."""
    from jointwear.compare import compare_files

    crit = folder / "criteria.toml"
    crit.write_text(f"wear_u_num_rel = {U_NUM_REL}\n")
    return compare_files([sim], [meas], folder / "m.nc", criteria=crit, cycles=cycles, ensemble=ens)


def u_val_ratio(folder: Path, sim: Path, meas: Path, ens: list[Path], cycles: float) -> float:
    """U_val / |D| of the band's maximum depth from ``jointwear compare``."""
    res = compared(folder, sim, meas, ens, cycles)
    return res.value("max_wear_depth", "U_val") / abs(res.value("max_wear_depth", "value_meas"))


def wrong_form(folder: Path, size: dict[str, Any], early: Path, late: Path, kw0: float) -> dict:
    """The model with tilt stiffness 0 (the wrong form) calibrated and validated the same way."""
    from jointwear.errors import BadInputError
    from jointwear.sim.calibrate import calibrate, predict

    wrong = folder / "wrong"
    wrong.mkdir()
    for f in (early, late):
        shutil.copy(f, wrong / f.name)
    (wrong / "base.toml").write_text(base_toml(size, tilt=0.0))
    spec = wrong / "spec.toml"
    spec.write_text(spec_text(early, size, kw0))
    out: dict[str, Any] = {"joint.tilt_stiffness": 0.0}
    try:
        ds = calibrate(spec, out=wrong / "post.nc", params=wrong / "base.toml", workers=0)
    except BadInputError as exc:  # refused: the wrong form cannot fit the calibration data
        return out | {"calibration": f"refused: {exc}", "failed": None}
    out["posterior_kw_mean"] = float(ds["posterior_mean"][0])
    c2 = size["validation_cycles"]
    pred = wrong / "prediction.nc"
    predict(wrong / "post.nc", cycles=c2, out=pred, samples=size["prediction_runs"], workers=0)
    res = compared(wrong, pred, wrong / late.name, [], c2)
    return out | {"calibration": "ok", "failed": res.failed(), "summary": res.summary()}


def prior_side(folder: Path, size: dict[str, Any], kw0: float) -> tuple[Path, Path]:
    """The model at the prior mean and the prior's ensemble, both at the validation cycles."""
    from jointwear.sim import run_sweep, simulate_wear
    from jointwear.sim.sweep._driver import _base

    c2 = size["validation_cycles"]
    sweep = {
        "sweep": {
            "run": "wear",
            "method": "lhs",
            "samples": size["prediction_runs"],
            "seed": 7,
            "cycles": c2,
            "keep": ["wear_depth"],
        },
        "parameters": {"wear.kw": {"distribution": "uniform", "bounds": [0.5 * kw0, 1.5 * kw0]}},
    }
    ens = folder / "prior-ensemble.nc"
    run_sweep(sweep, out=ens, params=folder / "base.toml", workers=0)
    from jointwear.sim.sweep._spec import read_spec

    sim, wear, record, _ = _base(read_spec(sweep), folder / "base.toml", None)
    ds = simulate_wear(sim, cycles=c2, settings=wear, snapshots=[c2])
    path = folder / "prior-mean.nc"
    io.save(ds, path, parameters={"parameters": record["parameters"], "wear": record["wear"]})
    return path, ens


def run(size: dict[str, Any], folder: Path) -> dict[str, Any]:
    from jointwear.sim.calibrate import calibrate, predict
    from jointwear.sim.calibrate._run import design_path
    from jointwear.sim.wear._settings import DEFAULT_KW

    (folder / "base.toml").write_text(base_toml(size))
    kw_true = KW_FACTOR * DEFAULT_KW
    covered, widths, cpu_cal, means = [], [], [], []
    design_cpu = float("nan")
    first_design = None
    reps = []
    for rep in range(size["replicates"]):
        early, late = truth_maps(folder, size, rep, kw_true)
        spec = folder / f"spec-{rep}.toml"
        spec.write_text(spec_text(early, size, DEFAULT_KW))
        post = folder / f"post-{rep}.nc"
        design = design_path(post, size["calibration_cycles"])
        if first_design is not None:  # the training runs do not depend on the data
            shutil.copy(first_design, design)
        t0 = time.process_time()
        ds = calibrate(spec, out=post, params=folder / "base.toml", workers=0, resume=True)
        cpu = time.process_time() - t0
        if first_design is None:
            first_design, design_cpu = design, cpu
        else:
            cpu_cal.append(cpu)
        lo, hi = float(ds["posterior_q025"][0]), float(ds["posterior_q975"][0])
        covered.append(lo <= kw_true <= hi)
        widths.append(float(ds["posterior_sd"][0] / ds["posterior_mean"][0]))
        means.append(float(ds["posterior_mean"][0]))
        reps.append({"kw_q025": lo, "kw_q975": hi, "covered": covered[-1], "late": late})
    # validation at the later snapshot of replicate 0: prior ensemble vs posterior prediction
    late = reps[0].pop("late")
    for r in reps[1:]:
        r.pop("late")
    mean_run, prior_ens = prior_side(folder, size, DEFAULT_KW)
    c2 = size["validation_cycles"]
    before = u_val_ratio(folder, mean_run, late, [prior_ens], c2)
    t0 = time.process_time()
    pred = folder / "prediction.nc"
    predict(folder / "post-0.nc", cycles=c2, out=pred, samples=size["prediction_runs"], workers=0)
    cpu_pred = time.process_time() - t0
    after = u_val_ratio(folder, pred, late, [], c2)
    early0 = folder / f"truth-0-{size['calibration_cycles']}.nc"
    wrong = wrong_form(folder, size, early0, late, DEFAULT_KW)
    prior_sd_over_mean = (1.0 / np.sqrt(3)) * 0.5  # uniform ±50 %: sd = width / sqrt(12)
    return {
        "size": size,
        "truth": {"joint.tilt_stiffness": TILT, "wear.kw": kw_true, "kw_factor": KW_FACTOR},
        "coverage_95": float(np.mean(covered)),
        "replicates_covered": int(np.sum(covered)),
        "posterior_sd_over_mean_median": float(np.median(widths)),
        "posterior_sd_over_mean_max": float(np.max(widths)),
        "posterior_mean_over_truth_median": float(np.median(means) / kw_true),
        "prior_sd_over_mean": prior_sd_over_mean,
        "u_val_over_d_max_depth": {"before_prior_ensemble": before, "after_posterior": after},
        "wrong_form": wrong,
        "cpu_s": {
            "training_design_and_first_calibration": design_cpu,
            "calibration_median": float(np.median(cpu_cal)) if cpu_cal else float("nan"),
            "prediction": cpu_pred,
        },
        "replicates": [
            {k: v for k, v in r.items() if k != "late"} | {"covered": bool(r["covered"])}
            for r in reps
        ],
        "note": "CPU times on a shared machine (see the load average); reduced rig and cycles",
    }


def main() -> None:
    folder = Path(tempfile.mkdtemp(prefix="bench-calibration-"))
    try:
        figures = run(SIZE, folder)
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    write_results("calibration_quick" if QUICK else "calibration", figures)
    json.dumps(figures)  # the figures are plain JSON


if __name__ == "__main__":
    main()
