"""Benchmark: does the calibration recover kw on a truth that is not the default rig?

Truth: the rig with ``joint.tilt_stiffness = 1000`` N m/rad and kw = 1.15 x the default (on a
reduced bore grid and few cycles, so that the whole study fits a shared 2-core machine: the
size is stated in the JSON). Each replicate starts the truth at another crank angle (phase)
and adds its own measurement noise (1 % of the peak depth per point, independent from point to
point, stated as the map's ``wear_depth_u`` and ``wear_depth_u_random``); kw is calibrated (prior uniform ±50 % around the default, the model's form
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


def _arg(name: str, default: str) -> str:
    """``--name VALUE`` from the command line, else ``default``."""
    return sys.argv[sys.argv.index(name) + 1] if name in sys.argv else default


#: sizes: "quick" (CI), "reduced" (a 7 x 36 bore, fixed dn = 100, 400/800 cycles) and "full"
#: (the default bore and wear scheme, calibrated after 2e5 cycles, validated after 4e5: the
#: issue's size)
SIZES = {
    "quick": {
        "replicates": 3,
        "n_layers": 5,
        "n_points": 24,
        "calibration_cycles": 200,
        "validation_cycles": 400,
        "training_runs": 40,
        "prediction_runs": 4,
        "wear_update": "fixed dn = 100 cycles",
    },
    "reduced": {
        "replicates": 10,
        "n_layers": 7,
        "n_points": 36,
        "calibration_cycles": 400,
        "validation_cycles": 800,
        "training_runs": 40,
        "prediction_runs": 8,
        "wear_update": "fixed dn = 100 cycles",
    },
    "full": {
        "replicates": 10,
        "n_layers": None,
        "n_points": None,
        "calibration_cycles": 200000,
        "validation_cycles": 400000,
        "training_runs": 24,
        "prediction_runs": 4,
        "wear_update": "the default (adaptive)",
    },
}
SIZE_NAME = "quick" if QUICK else _arg("--size", "reduced")
SIZE = dict(SIZES[SIZE_NAME])
#: the truths (not the default rig): the rig each differs by, besides kw
TRUTHS = {
    "tilt1000": {"joint.tilt_stiffness": 1000.0},
    "clearance0.7": {"joint.journal_radius": 7.3e-3},  # radial clearance 0.7 mm (default 0.5)
}
TRUTH = _arg("--truth", "tilt1000")
KW_FACTOR, NOISE, U_NUM_REL = 1.15, 0.01, 0.02


def base_toml(size: dict[str, Any], truth: str = TRUTH, tilt: float | None = None) -> str:
    """The rig of ``truth`` at ``size`` (``tilt``: another tilt stiffness, the wrong form)."""
    import tomli_w

    joint: dict[str, Any] = {k.split(".")[1]: float(v) for k, v in TRUTHS[truth].items()}
    if tilt is not None:
        joint["tilt_stiffness"] = float(tilt)
    tables: dict[str, Any] = {"joint": joint}
    if size["n_layers"] is not None:
        joint.update(n_layers=int(size["n_layers"]), n_points=int(size["n_points"]))
        tables["wear"] = {
            "scheme": "fixed",
            "dn": 100,
            "settle_cycles": 0.25,
            "initial_settle_cycles": 0.5,
        }
    return tomli_w.dumps(tables)


def truth_maps(folder: Path, size: dict[str, Any], rep: int, kw: float) -> tuple[Path, Path]:
    """The truth's measured maps (early, late) of replicate ``rep``: own phase, own noise."""
    from jointwear.params import from_mapping, read_toml
    from jointwear.sim import WearSettings, load_parameters, simulate_wear

    c1, c2 = size["calibration_cycles"], size["validation_cycles"]
    done = [folder / f"truth-{rep}-{c}.nc" for c in (c1, c2)]
    if all(p.is_file() for p in done):  # a kept study folder (--folder): the truth as made
        return done[0], done[1]
    base = folder / "base.toml"
    p = load_parameters(base)
    p = dataclasses.replace(
        p, mechanism=dataclasses.replace(p.mechanism, initial_crank_angle_deg=37.0 * rep)
    )
    w = dataclasses.replace(
        from_mapping(WearSettings, read_toml(base).get("wear", {}), where="wear"), kw=kw
    )
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
        m["wear_depth_u_random"] = m["wear_depth_u"].assign_attrs(
            long_name="independent (point-to-point random) part of wear_depth_u"
        )  # the noise is independent from point to point: all of the u
        m.attrs = {"data_origin": "synthetic", "cycles": c, "bearing_radius_m": 8e-3}
        path = folder / f"truth-{rep}-{c}.nc"
        io.save(m, path)
        paths.append(path)
    return paths[0], paths[1]


def spec_text(early: Path, size: dict[str, Any], kw0: float) -> str:
    import tomli_w

    calibrate = {
        "data": [early.name],
        "cycles": int(round(float(size["calibration_cycles"]))),
        "samples": int(size["training_runs"]),
        "seed": 1,
        "u_num_rel": U_NUM_REL,
    }
    prior = {"distribution": "uniform", "bounds": [0.5 * kw0, 1.5 * kw0]}
    return tomli_w.dumps({"calibrate": calibrate, "parameters": {"wear.kw": prior}})


def compared(folder: Path, sim: Path, meas: Path, ens: list[Path], cycles: float):
    """``jointwear compare`` of ``sim`` (with the ensembles ``ens``) and ``meas``."""
    from jointwear.compare import compare_files

    crit = folder / "criteria.toml"
    crit.write_text(f"wear_u_num_rel = {U_NUM_REL}\n")
    return compare_files([sim], [meas], folder / "m.nc", criteria=crit, cycles=cycles, ensemble=ens)


def u_val_ratio(folder: Path, sim: Path, meas: Path, ens: list[Path], cycles: float):
    """U_val / |D| of the band's maximum depth from ``jointwear compare``, and its verdict
    (the failed criteria and the summary line)."""
    res = compared(folder, sim, meas, ens, cycles)
    ratio = res.value("max_wear_depth", "U_val") / abs(res.value("max_wear_depth", "value_meas"))
    return ratio, {"failed": res.failed(), "summary": res.summary()}


def wrong_form(folder: Path, size: dict[str, Any], early: Path, late: Path, kw0: float) -> dict:
    """The model with tilt stiffness 0 (the wrong form) calibrated and validated the same way."""
    from jointwear.errors import BadInputError
    from jointwear.sim.calibrate import calibrate, predict

    wrong = folder / "wrong"
    wrong.mkdir(exist_ok=True)
    for f in (early, late):
        shutil.copy(f, wrong / f.name)
    (wrong / "base.toml").write_text(base_toml(size, tilt=0.0))
    spec = wrong / "spec.toml"
    spec.write_text(spec_text(early, size, kw0))
    out: dict[str, Any] = {"joint.tilt_stiffness": 0.0}
    try:
        ds = calibrate(
            spec, out=wrong / "post.nc", params=wrong / "base.toml", workers=0, resume=True
        )
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
    run_sweep(sweep, out=ens, params=folder / "base.toml", workers=0, resume=True)
    from jointwear.sim.sweep._spec import read_spec

    sim, wear, record, _ = _base(read_spec(sweep), folder / "base.toml", None)
    ds = simulate_wear(sim, cycles=c2, settings=wear, snapshots=[c2])
    path = folder / "prior-mean.nc"
    io.save(ds, path, parameters={"parameters": record["parameters"], "wear": record["wear"]})
    return path, ens


def run(
    size: dict[str, Any], folder: Path, truth: str = TRUTH, with_wrong_form: bool = True
) -> dict[str, Any]:
    """The study at ``size`` on ``truth`` in ``folder`` (a kept folder's truths and design are
    reused: the training runs and the truth do not depend on the likelihood)."""
    from jointwear.sim.calibrate import calibrate, predict
    from jointwear.sim.calibrate._run import design_path
    from jointwear.sim.wear._settings import DEFAULT_KW

    (folder / "base.toml").write_text(base_toml(size, truth))
    kw_true = KW_FACTOR * DEFAULT_KW
    covered, widths, cpu_cal, means = [], [], [], []
    design_cpu = float("nan")
    master = folder / "design-master.nc"  # the training runs do not depend on the data
    master_cpu = folder / "design-master-cpu.json"  # its CPU, kept with it for a resumed study
    if master.is_file() and master_cpu.is_file():
        design_cpu = float(json.loads(master_cpu.read_text())["cpu_s"])
    reps = []
    for rep in range(size["replicates"]):
        early, late = truth_maps(folder, size, rep, kw_true)
        spec = folder / f"spec-{rep}.toml"
        spec.write_text(spec_text(early, size, DEFAULT_KW))
        post = folder / f"post-{rep}.nc"
        design = design_path(post, size["calibration_cycles"])
        if master.is_file():
            shutil.copy(master, design)
        t0 = time.process_time()
        ds = calibrate(spec, out=post, params=folder / "base.toml", workers=0, resume=True)
        cpu = time.process_time() - t0
        if not master.is_file():
            shutil.copy(design, master)
            design_cpu = cpu
            master_cpu.write_text(json.dumps({"cpu_s": cpu}))
        else:
            cpu_cal.append(cpu)
        lo, hi = float(ds["posterior_q025"][0]), float(ds["posterior_q975"][0])
        mean, sd = float(ds["posterior_mean"][0]), float(ds["posterior_sd"][0])
        covered.append(lo <= kw_true <= hi)
        widths.append(sd / mean)
        means.append(mean)
        reps.append(
            {
                "kw_q025": lo,
                "kw_q975": hi,
                "covered": bool(covered[-1]),
                "z": (mean - kw_true) / sd,
                "phase_deg": (37.0 * rep) % 360.0,
            }
        )
    # validation at the later snapshot of replicate 0: prior ensemble vs posterior prediction
    late = folder / f"truth-0-{size['validation_cycles']}.nc"
    mean_run, prior_ens = prior_side(folder, size, DEFAULT_KW)
    c2 = size["validation_cycles"]
    before, _ = u_val_ratio(folder, mean_run, late, [prior_ens], c2)
    t0 = time.process_time()
    pred = folder / "prediction.nc"
    predict(folder / "post-0.nc", cycles=c2, out=pred, samples=size["prediction_runs"], workers=0)
    cpu_pred = time.process_time() - t0
    after, verdict = u_val_ratio(folder, pred, late, [], c2)
    early0 = folder / f"truth-0-{size['calibration_cycles']}.nc"
    wrong = (
        wrong_form(folder, size, early0, late, DEFAULT_KW)
        if with_wrong_form and truth == "tilt1000"
        else "not run (--no-wrong-form, or a truth other than tilt1000)"
    )
    prior_sd_over_mean = (1.0 / np.sqrt(3)) * 0.5  # uniform ±50 %: sd = width / sqrt(12)
    return {
        "size": size,
        "truth": TRUTHS[truth] | {"name": truth, "wear.kw": kw_true, "kw_factor": KW_FACTOR},
        "coverage_95": float(np.mean(covered)),
        "replicates_covered": int(np.sum(covered)),
        "posterior_sd_over_mean_median": float(np.median(widths)),
        "posterior_sd_over_mean_max": float(np.max(widths)),
        "posterior_mean_over_truth_median": float(np.median(means) / kw_true),
        "prior_sd_over_mean": prior_sd_over_mean,
        "u_val_over_d_max_depth": {"before_prior_ensemble": before, "after_posterior": after},
        "right_model_validation": verdict,
        "wrong_form": wrong,
        "cpu_s": {
            "training_design_and_first_calibration": design_cpu,
            "calibration_median": float(np.median(cpu_cal)) if cpu_cal else float("nan"),
            "prediction": cpu_pred,
        },
        "replicates": reps,
        "z_rms": float(np.sqrt(np.mean([r["z"] ** 2 for r in reps]))),
        "note": "CPU times on a shared machine (see the load average); size as stated",
    }


def main() -> None:
    keep = _arg("--folder", "")
    folder = Path(keep) if keep else Path(tempfile.mkdtemp(prefix="bench-calibration-"))
    folder.mkdir(parents=True, exist_ok=True)
    try:
        figures = run(SIZE, folder, TRUTH, "--no-wrong-form" not in sys.argv)
    finally:
        if not keep:
            shutil.rmtree(folder, ignore_errors=True)
    write_results("calibration_quick" if QUICK else f"calibration_{SIZE_NAME}_{TRUTH}", figures)
    json.dumps(figures)  # the figures are plain JSON


if __name__ == "__main__":
    main()
