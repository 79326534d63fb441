"""Power of the validation verdict, measured on known truth (issue 20).

A "truth" rig (the reference parameters, ``zhang2023``) is simulated and *measured* through
virtual roundness scans on the reference study's layout (13 layers 1 mm apart, z = -6…+6 mm of
the 15-mm bearing; instrument noise, set-up eccentricity/tilt, form errors; imported with
:func:`jointwear.metrology.readers.read_talyrond` and made a wear map with
:func:`jointwear.metrology.wear_map` against a before-wear scan), as a user would. Candidate
models are then compared with each measurement, each with its own uncertainties:

* the right model: an independent run (another tolerance of the adaptive wear update, so
  another sequence of update intervals and start cycles), u_num from its own ``wear_depth_u``;
* wrong models: the wear coefficient doubled, the joint offset 0, friction 0;
* the right model's map turned by 180 degree (a wrong angle zero).

u_input of each candidate is the spread of a Latin-hypercube ensemble around *its own* nominal
inputs (:data:`jointwear.datasets.reference_study.ENSEMBLE_INPUTS`; an input whose nominal value is
0, friction 0, is not varied), u_D comes from the measured map. Every measurement replicate has
its own instrument noise; every right-model replicate its own update tolerance.

The targets (issue 20): the right model never fails and passes >= 3 wear criteria; each wrong
model fails >= 1 wear criterion; the 180-degree map exits 1.
"""

from __future__ import annotations

import tempfile
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import xarray as xr

__all__ = ["PowerSize", "CI_SIZE", "FULL_SIZE", "WRONG_MODELS", "run_power"]

#: the wrong models: name -> parameter overrides (``simulate_wear(overrides=...)``)
WRONG_MODELS: dict[str, dict[str, float]] = {
    "kw x 2": {"wear.kw": 2.0},  # factor, applied to the nominal kw below
    "joint offset 0": {"mechanism.joint_offset": 0.0},
    "friction 0": {"friction.dynamic_coefficient": 0.0},
}


@dataclass(frozen=True)
class PowerSize:
    """Size of a power study.

    Attributes
    ----------
    cycles : float
        Wear cycles of every run.
    n_layers, n_points : int
        Simulation grid.
    instrument_points : int
        Points per scanned layer (the reference study: 18000).
    replicates : int
        Measurement replicates (instrument noise) = right-model replicates.
    tolerances : tuple of float
        Adaptive-update tolerance of each right-model replicate (the truth uses the default
        0.1); cycled when there are more replicates.
    ensemble_runs, ensemble_cycles, ensemble_updates :
        The input ensemble of each candidate: LHS members, reduced cycles, fixed updates.
    own_ensembles : bool
        True: every candidate has its own ensemble around its own inputs; False: the truth's
        ensemble serves all (its relative spread; a reduced-size shortcut).
    """

    cycles: float
    n_layers: int
    n_points: int
    instrument_points: int
    replicates: int
    tolerances: tuple[float, ...]
    ensemble_runs: int
    ensemble_cycles: float
    ensemble_updates: int
    own_ensembles: bool = True


#: reduced size for CI: one replicate, and one ensemble (around the truth's inputs) whose
#: relative spread serves every candidate
CI_SIZE = PowerSize(1e4, 10, 36, 1800, 1, (0.2,), 3, 4e3, 2, own_ensembles=False)
FULL_SIZE = PowerSize(5e4, 15, 72, 18000, 5, (0.2, 0.05, 0.15, 0.3, 0.07), 8, 2e4, 4)


def _params(size: PowerSize) -> Any:
    from jointwear.params import replace_nested
    from jointwear.sim import PARAMETER_SETS

    return replace_nested(
        PARAMETER_SETS["zhang2023"],
        **{"joint.n_layers": size.n_layers, "joint.n_points": size.n_points},
    )


def _overrides(name: str | None) -> dict[str, float]:
    from jointwear.sim import DEFAULT_KW

    if name is None:
        return {}
    out = dict(WRONG_MODELS[name])
    if "wear.kw" in out:
        out["wear.kw"] = out["wear.kw"] * DEFAULT_KW
    return out


def _simulate(size: PowerSize, overrides: dict[str, float], tol: float | None) -> xr.Dataset:
    from jointwear.sim import WearSettings, simulate_wear

    settings = WearSettings(tol=tol) if tol is not None else WearSettings()
    ds = simulate_wear(
        _params(size),
        cycles=size.cycles,
        snapshots=[size.cycles],
        settings=settings,
        overrides=overrides or None,
    )
    ds.attrs["data_origin"] = "simulated"
    return ds


def _ensemble(size: PowerSize, overrides: dict[str, float]) -> xr.Dataset:
    from jointwear.reports.demo_studies import ensemble_spec
    from jointwear.sim import WearSettings, apply_overrides, run_sweep

    params, settings = apply_overrides(_params(size), WearSettings(), overrides or None)
    spec = ensemble_spec(params, size, kw=settings.kw)
    dn = int(size.ensemble_cycles // size.ensemble_updates)
    return run_sweep(spec, params=params, wear=WearSettings(scheme="fixed", dn=dn), workers=0)


def _measure(truth: xr.Dataset, size: PowerSize, seed: int, folder: Path) -> xr.Dataset:
    """Virtual scans of the truth (worn and before wear), imported and made a wear map."""
    from jointwear.datasets import instruments
    from jointwear.datasets.simulated_wear import wear_from_simulation
    from jointwear.metrology import wear_map
    from jointwear.metrology.readers import read_talyrond

    convention = ("+y", "counterclockwise")
    radius = float(truth.attrs.get("bearing_radius_m", 8e-3))
    common = {"n_layers": 13, "n_points": size.instrument_points, "radius": radius}
    worn = instruments.generate(
        **common,
        wear=wear_from_simulation(truth),
        convention=convention,
        seed=2023,
        noise_seed=1000 + seed,
    )
    before = instruments.generate(
        **common,
        wear=None,
        convention=convention,
        eccentricity=(-5e-6, 12e-6),
        tilt=(0.5e-3, 1.0e-3),
        seed=2023,
        noise_seed=2000 + seed,
    )
    paths = []
    for name, scan in (("worn", worn), ("before", before)):
        path = folder / f"{name}_{seed}"
        instruments.write(scan, path, layout="folder")
        paths.append(read_talyrond(path, convention=convention))
    wm = wear_map(*paths)
    wm.attrs["cycles"] = float(size.cycles)
    return wm


def _turned(ds: xr.Dataset) -> xr.Dataset:
    th = ds["theta"]
    out = ds.assign_coords(theta=(th + 180.0) % 360.0).sortby("theta")
    out["theta"].attrs = th.attrs
    return out


def _outcome(c: Any) -> dict[str, Any]:
    """Wear-criterion states of a comparison, counts and the exit code compare would give."""
    import jointwear.compare.verdicts as vd

    wear = c.decisions[
        c.decisions.key.isin(["wear_depth", "max_wear_depth", "worn_volume", "cylindricity"])
    ]
    states = {
        str(q).split(" within ")[0]: str(s) for q, s in zip(wear.quantity, wear.state, strict=True)
    }
    budget = {}
    for q in ("max_wear_depth", "worn_volume", "cylindricity"):
        rows = c.metrics[c.metrics.quantity == q].set_index("metric")["value"]
        if not rows.empty:
            budget[q] = {
                m: float(rows[m])
                for m in ("value_sim", "value_meas", "E", "u_num", "u_input", "u_D", "U_val")
                if m in rows
            }
    return {
        "states": states,
        "budget": budget,
        "n_pass": int((wear.state == vd.PASS).sum()),
        "n_fail": int((wear.state == vd.FAIL).sum()),
        "n_not_assessed": int((wear.state == vd.NOT_ASSESSED).sum()),
        "exit_code": 1 if c.any_failed else 0,
    }


def run_power(
    size: PowerSize = FULL_SIZE,
    *,
    folder: str | Path | None = None,
    progress: Callable[[str], None] | None = None,
    keep: dict[str, Any] | None = None,
) -> dict[str, Any]:
    """Run the power study and return its results (JSON-ready).

    ``keep``, a dict, receives the last replicate's datasets (``measurement``, ``right``,
    ``turned``, ``ensemble``) for a check through the command line.

    Returns
    -------
    dict
        ``right`` (per replicate outcomes, ``false_fail_rate``, ``min_passes``), ``wrong``
        (per model: outcomes, ``detection_rate``, which criteria failed), ``turned_180``
        (exit codes), ``targets_met`` and the timings.
    """
    from jointwear.compare import Criteria, compare

    say = progress or (lambda _m: None)
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(folder) if folder is not None else Path(tmp)
        work.mkdir(parents=True, exist_ok=True)
        truth = _simulate(size, {}, None)
        say(f"truth simulated ({time.perf_counter() - t0:.0f} s)")
        meas = [_measure(truth, size, r, work) for r in range(size.replicates)]
        say(f"{size.replicates} measurement replicates ({time.perf_counter() - t0:.0f} s)")
        ens = {None: _ensemble(size, {})}
        for name in WRONG_MODELS:
            ens[name] = _ensemble(size, _overrides(name)) if size.own_ensembles else ens[None]
        say(f"ensembles ({time.perf_counter() - t0:.0f} s)")
        wrong = {name: _simulate(size, _overrides(name), None) for name in WRONG_MODELS}
        say(f"wrong models ({time.perf_counter() - t0:.0f} s)")
        crit = Criteria()
        right, turned, wrong_out = [], [], {name: [] for name in WRONG_MODELS}
        coverage: list[dict[str, float]] = []
        for r, m in enumerate(meas):
            # the measurement against its own truth: E is the measurement error, to be set
            # against u_D (coverage of the measured map's stated uncertainty)
            own = _outcome(compare(truth, m, ensemble=[ens[None]], criteria=crit))["budget"]
            coverage.append({q: b["E"] / b["u_D"] for q, b in own.items() if b.get("u_D")})
            tol = size.tolerances[r % len(size.tolerances)]
            model = _simulate(size, {}, tol)
            c = compare(model, m, ensemble=[ens[None]], criteria=crit)
            right.append({"tolerance": tol, **_outcome(c), "summary": c.summary()})
            ct = compare(_turned(model), m, ensemble=[ens[None]], criteria=crit)
            turned.append(_outcome(ct))
            for name, w in wrong.items():
                cw = compare(w, m, ensemble=[ens[name]], criteria=crit)
                wrong_out[name].append(_outcome(cw))
            say(f"replicate {r + 1}/{size.replicates} ({time.perf_counter() - t0:.0f} s)")
            if keep is not None:
                keep.update(measurement=m, right=model, turned=_turned(model), ensemble=ens[None])
    n = len(right)
    result = {
        "size": asdict(size),
        "right": {
            "replicates": right,
            "false_fail_rate": sum(o["n_fail"] > 0 for o in right) / n,
            "min_passes": min(o["n_pass"] for o in right),
        },
        "wrong": {
            name: {
                "replicates": outs,
                "detection_rate": sum(o["n_fail"] > 0 for o in outs) / n,
                "failed_criteria": sorted(
                    {q for o in outs for q, s in o["states"].items() if s == "fail"}
                ),
            }
            for name, outs in wrong_out.items()
        },
        "measurement_error_over_u_D": {
            "definition": "(truth - D) / u_D of each band quantity, per noise replicate; the "
            "truth's own band value on the common grid",
            "replicates": coverage,
            "max_abs": {q: max(abs(c[q]) for c in coverage) for q in coverage[0]}
            if coverage
            else {},
        },
        "turned_180": {
            "exit_codes": [o["exit_code"] for o in turned],
            "failed_criteria": sorted(
                {q for o in turned for q, s in o["states"].items() if s == "fail"}
            ),
        },
        "seconds": time.perf_counter() - t0,
    }
    result["targets_met"] = bool(
        result["right"]["false_fail_rate"] == 0
        and result["right"]["min_passes"] >= 3
        and all(w["detection_rate"] == 1 for w in result["wrong"].values())
        and all(e == 1 for e in result["turned_180"]["exit_codes"])
    )
    return result
