"""The reference study calibrated, then validated: the growth-ratio question (issue 35).

Zhang et al. (2023) measured the cylindricity of their bore growing 28.3 µm by 4e5 cycles and
41.6 µm by 1.2e6 (33.34 and 46.57 µm less the new bore's 5.02 µm): a ratio of 0.68. Before any
calibration the simulated ratio was 0.40-0.57 over every tilt stiffness and joint offset tried.
:func:`calibrate_reference` asks it the calibrate -> validate way:

1. **calibrate** the wear coefficient and the joint's tilt stiffness (:data:`PRIORS`) on the
   4e5 growth alone (:func:`jointwear.sim.calibrate.calibrate`, a ``[[calibrate.values]]``
   datum computed on the 13 measured layers of each simulated map, centred on the bore: the
   paper does not state where they lie, centred is its natural reading);
2. **predict** 1.2e6 cycles with the real simulator at posterior samples
   (:func:`jointwear.sim.calibrate.predict`);
3. **validate**: :func:`jointwear.compare.compare` of the prediction (its mean map, its spread
   as u_input) with the reported file read with the layers centred, u_num from the study's
   update-interval levels rerun at the posterior mean: the 1.2e6 growth is decided by ASME V&V 20.

One growth value carries one number: it fixes kw for a given stiffness but cannot tell the
stiffness apart; the posterior says which input the data leave undetermined
(``not_informed``), and :func:`reference_lines` states it.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

__all__ = ["PRIORS", "ReferenceCalibration", "calibrate_reference", "reference_lines"]

#: Calibrated inputs: dotted name -> bounds of the uniform prior, as factors of the nominal kw
#: for ``wear.kw`` and in N m/rad for the tilt stiffness (the default rig has none, 0; the
#: issue-35 trials went to 1000).
PRIORS: dict[str, tuple[float, float]] = {
    "wear.kw": (1.0, 12.0),
    "joint.tilt_stiffness": (0.0, 2000.0),
}
#: The reported quantities of the question: calibration at 4e5, validation at 1.2e6 cycles.
CALIBRATION_KEY, VALIDATION_KEY, BASELINE_KEY = (
    "cylindricity_4e5",
    "cylindricity_1_2e6",
    ("cylindricity_new"),
)


@dataclass(frozen=True)
class ReferenceCalibration:
    """The calibrate -> validate outcome: files, the posterior and the validation comparison."""

    posterior: xr.Dataset
    validation: Any  # Comparison of the prediction with the reported file (layers centred)
    measured_ratio: float
    predicted_ratio: float
    predicted_ratio_u: float
    u_num_basis: str  # of the calibration datum
    files: dict[str, Path]


def _layers(attrs: dict[str, Any]) -> list[float]:
    """The reported layers' positions [m], centred on the bore (the natural reading)."""
    n = int(attrs["layers_count"])
    dz = float(attrs["layers_spacing_m"])
    return [float((i - (n - 1) / 2) * dz) for i in range(n)]


def _growth(rep: xr.Dataset, key: str) -> tuple[float, float]:
    """The reported growth since new [m] and its u as compare takes it for a minimum-zone
    reading: the two readings' u and the new bore's form C0/sqrt(3) (cylindricity does not add)."""
    c0 = float(rep[BASELINE_KEY].values)
    u = math.sqrt(
        float(rep[f"{key}_u"].values) ** 2
        + float(rep[f"{BASELINE_KEY}_u"].values) ** 2
        + c0**2 / 3.0
    )
    return float(rep[key].values) - c0, u


def _spec(rep: xr.Dataset, size: Any, u_num_rel: float) -> str:
    import tomli_w

    from jointwear.sim import DEFAULT_KW

    value, u = _growth(rep, CALIBRATION_KEY)
    cycles = float(rep[CALIBRATION_KEY].attrs["cycles"])
    source = str(rep[CALIBRATION_KEY].attrs.get("source", CALIBRATION_KEY))
    datum = {
        "quantity": "cylindricity",
        "value": float(value),
        "u": float(u),
        "source": f"growth since new, Zhang et al. 2023 ({source}), 13 layers centred",
        "z": _layers(rep.attrs),
    }
    calibrate = {
        "cycles": int(round(cycles)),
        "samples": int(size.training_runs),
        "seed": 1,
        "u_num_rel": float(u_num_rel),
        "values": [datum],
    }
    priors = {}
    for name, (lo, hi) in PRIORS.items():
        scale = float(DEFAULT_KW) if name == "wear.kw" else 1.0
        priors[name] = {"distribution": "uniform", "bounds": [lo * scale, hi * scale]}
    return tomli_w.dumps({"calibrate": calibrate, "parameters": priors})


def _params_toml(size: Any) -> str:
    import tomli_w

    joint = {"n_layers": int(size.layers), "n_points": int(size.points)}
    return tomli_w.dumps({"joint": joint, "wear": {"scheme": "fixed", "dn": int(size.levels[-1])}})


def _centred(reported: dict[str, Any]) -> dict[str, Any]:
    """The reported file's table read with its layers centred on the bore (stated)."""
    layers = dict(reported["layers"], z_centre="0 mm")
    return {**reported, "layers": layers}


#: u_num / S stated for the calibration datum when the study's comparison assesses none for the
#: centred reading (the reduced study's update-interval levels may not converge).
FALLBACK_U_NUM_REL = 0.05


def _u_num_rel(prior: Any, key: str) -> tuple[float, str]:
    """u_num / S of a reported cylindricity under the centred reading, from the study's
    comparison (its update-interval levels, nominal inputs), and where it comes from."""
    m = prior.metrics
    q = m.quantity.astype(str)
    rows = m[q.str.startswith(key) & q.str.contains("centred at z = +0.00 mm")]
    try:
        u = float(rows[rows.metric == "u_num"]["value"].iloc[0])
        s = float(rows[rows.metric == "value_sim"]["value"].iloc[0])
    except IndexError:
        u, s = float("nan"), 0.0
    if np.isfinite(u) and s:
        return u / abs(s), "the update-interval study at nominal inputs"
    return FALLBACK_U_NUM_REL, (
        f"stated {FALLBACK_U_NUM_REL:.0%}: the update-interval study assesses none"
    )


def calibrate_reference(
    out: str | Path,
    size: Any,
    prior: Any,
    *,
    say: Callable[[str], None] = lambda _: None,
) -> ReferenceCalibration:
    """Calibrate on the 4e5 growth, predict and decide the 1.2e6 growth (module docstring).

    Parameters
    ----------
    out : path
        The reference study's folder (receives calibrate.toml, calibrate_params.toml,
        reported_centred.nc, posterior.nc, prediction.nc, metrics_calibrated.nc).
    size : StudySize
        Grid, finest update interval, ``training_runs`` and ``prediction_runs``.
    prior : Comparison
        The study's comparison before calibration (u_num of the 4e5 growth, relative).
    """
    from jointwear import io
    from jointwear.compare import as_ensemble, compare, save_comparison
    from jointwear.compare.calibration_use import split_prediction
    from jointwear.datasets.reference_study import reference_file, update_study
    from jointwear.params import read_toml
    from jointwear.reported import reported_dataset
    from jointwear.sim import PARAMETER_SETS
    from jointwear.sim.calibrate import calibrate, predict

    out = Path(out)
    src = reference_file()
    rep = reported_dataset(_centred(read_toml(src)), src)
    rep_path = io.save(
        rep, out / "reported_centred.nc", inputs=[src], parameters={"layers.z_centre": "0 mm"}
    )
    spec, base = out / "calibrate.toml", out / "calibrate_params.toml"
    u_num_rel, u_num_basis = _u_num_rel(prior, CALIBRATION_KEY)
    spec.write_text(_spec(rep, size, u_num_rel), encoding="utf-8")
    base.write_text(_params_toml(size), encoding="utf-8")
    say(f"calibration: {size.training_runs} training runs at 4e5 cycles")
    post = calibrate(spec, out=out / "posterior.nc", params=base, workers=0)
    names = json.loads(post.attrs["calibrated_parameters"])
    cycles = float(rep[VALIDATION_KEY].attrs["cycles"])
    say(f"prediction: {size.prediction_runs} runs at {cycles:g} cycles")
    pred_path = out / "prediction.nc"
    pred = predict(
        out / "posterior.nc", cycles=cycles, out=pred_path, samples=size.prediction_runs, workers=0
    )
    mean, ens = split_prediction(pred)
    # u_num of the calibrated model: its own update-interval levels at the posterior mean
    at_mean = {n: float(v) for n, v in zip(names, post["posterior_mean"].values, strict=True)}
    grid = {"joint.n_layers": size.layers, "joint.n_points": size.points}
    _, study = update_study(PARAMETER_SETS["zhang2023"], [cycles], size, {**grid, **at_mean}, say)
    ver_path = io.save(study, out / "verification_calibrated.nc", parameters={"at": at_mean})
    result = compare(mean, rep, ensemble=as_ensemble([ens], [pred_path.name]), verification=[study])
    save_comparison(
        result,
        out / "metrics_calibrated.nc",
        inputs=[pred_path, rep_path, ver_path],
        parents=[mean, rep],
    )
    measured = _growth(rep, CALIBRATION_KEY)[0] / _growth(rep, VALIDATION_KEY)[0]
    ppc = float(np.asarray(post["ppc_mean"].values)[0])
    s_val = result.value(VALIDATION_KEY, "value_sim")
    u_in = result.value(VALIDATION_KEY, "u_input")
    ratio = ppc / s_val
    files = {"posterior": out / "posterior.nc", "prediction": pred_path, "reported": rep_path}
    return ReferenceCalibration(
        post, result, measured, ratio, ratio * u_in / s_val, u_num_basis, files
    )


def reference_lines(cal: ReferenceCalibration) -> list[str]:
    """What the reference study prints about it: a heading, one line per calibrated input, and
    the validation's decision in at most three lines."""
    from jointwear.compare import verdicts as vd

    post = cal.posterior
    names = json.loads(post.attrs["calibrated_parameters"])
    lost = json.loads(post.attrs.get("not_informed", "[]"))
    width = max(len(v) for v in vd.LABELS.values())
    value, u = float(post["measured"].values[0]), float(post["u_d"].values[0])
    lines = [
        f"calibrated on the 4e5 cylindricity growth ({value * 1e6:.1f} ± {u * 1e6:.1f} µm, 13 "
        f"layers centred; u_num {cal.u_num_basis}), validated at 1.2e6 with the posterior "
        "prediction:"
    ]
    for k, name in enumerate(names):
        ratio = float(post["width_ratio"].values[k])
        state = "NOT INFORMED" if name in lost else "CALIBRATED"
        why = (
            ": one growth value fixes one combination of the inputs, the data cannot identify it"
            if name in lost
            else ""
        )
        lines.append(
            f"{state:<{width}}  {name}: {float(post['posterior_mean'].values[k]):.4g} ± "
            f"{float(post['posterior_sd'].values[k]):.2g} (posterior/prior sd {ratio:.2f}){why}"
        )
    row = cal.validation.decisions[cal.validation.decisions.key == VALIDATION_KEY].iloc[0]
    lines.append(f"{vd.LABELS[row.state]:<{width}}  {row.quantity}: {row.value}  [{row.criterion}]")
    lines.append(
        f"{'':<{width}}    growth ratio 4e5/1.2e6: measured {cal.measured_ratio:.2f}, calibrated "
        f"prediction {cal.predicted_ratio:.2f} ± {cal.predicted_ratio_u:.2f} (u_input)"
    )
    if row.resolution and row.state in (vd.PASS, vd.FAIL):
        lines.append(f"{'':<{width}}    resolution: {row.resolution}")
    return lines
