"""The reference study's reported measurements, and its validation claim re-decided with a verdict.

Zhang et al. (2023) report the cylindricity of their brass bearing before wear, after 4e5 and
after 1.2e6 cycles, and where the maximum wear lies (near 90 degree at the first layer, 310
degree at the last), and conclude that the model is "well in line" with the test. The shipped
file ``zhang2023_reported.toml`` (:func:`reference_file`) holds those numbers with their
sources; :func:`run_reference_study` simulates the default rig (``PARAMETER_SETS["zhang2023"]``)
and decides every reported quantity with :func:`jointwear.compare.compare`:

1. a verification study of the wear update: the wear run with a fixed update interval dN at
   ``size.levels`` (coarse to fine), every level's map kept at the reported cycles
   (``verification.nc``: ``wear_depth`` over ``(dn, cycles, z, theta)``); the finest level is
   the compared simulation (``sim_wear.nc``), the GCI of the others its u_num;
2. an ensemble over the uncertain inputs (a Latin hypercube over
   :data:`ENSEMBLE_INPUTS`: the wear coefficient +-15 %, the bore
   radius +-0.4 %, the friction coefficient +-20 %, truncated normal at 4 standard deviations),
   each member's maps kept at the reported cycles (``ensemble.nc``); its spread is u_input;
3. the comparison (``metrics.nc``).

The command chain with the command line is in docs/compare-report.md.
"""

from __future__ import annotations

from collections.abc import Callable
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from jointwear.datasets._study_size import FULL, REDUCED, StudySize

__all__ = [
    "StudySize",
    "FULL",
    "REDUCED",
    "ENSEMBLE_INPUTS",
    "reference_file",
    "run_reference_study",
    "update_study",
]

#: The reference rig's uncertain model inputs (this study's ensemble and the demo's): dotted parameter name -> (relative standard deviation,
#: what it stands for). The wear coefficient has to be calibrated (the reference study's value
#: cannot be used as printed), the radial clearance and the friction coefficient are not
#: measured on the rig.
ENSEMBLE_INPUTS: dict[str, tuple[float, str]] = {
    "wear.kw": (0.15, "Archard wear coefficient, calibrated to about 15 %"),
    "joint.bearing_radius": (0.004, "bore radius (radial clearance 0.5 mm +- 32 µm)"),
    "friction.dynamic_coefficient": (0.2, "dynamic friction coefficient, +- 20 %"),
}


def reference_file() -> Path:
    """Path of the shipped ``zhang2023_reported.toml``."""
    return Path(str(resources.files("jointwear.datasets") / "data" / "zhang2023_reported.toml"))


def _run(params: Any, cycles: list[float], dn: int, overrides: dict[str, float]) -> xr.Dataset:
    from jointwear.sim import WearSettings, simulate_wear

    return simulate_wear(
        params,
        cycles=max(cycles),
        snapshots=cycles,
        settings=WearSettings(scheme="fixed", dn=dn),
        overrides=overrides,
    )


def update_study(
    params: Any,
    cycles: list[float],
    size: StudySize,
    overrides: dict[str, float],
    say: Callable[[str], None] = lambda _: None,
) -> tuple[xr.Dataset, xr.Dataset]:
    """The wear run at every update interval of ``size.levels`` (coarse to fine), maps kept at
    ``cycles``: (the finest run, the study ``wear_depth(dn, cycles, z, theta)``)."""
    maps = []
    for dn in size.levels:
        say(f"verification level dN = {dn}")
        maps.append(_run(params, cycles, dn, overrides))
    study = xr.Dataset({"wear_depth": xr.concat([m["wear_depth"] for m in maps], dim="dn")})
    study = study.assign_coords(
        dn=(
            "dn",
            np.asarray(size.levels, float),
            {"units": "1", "long_name": "wear-update interval dN (refinement parameter h)"},
        )
    )
    study.attrs.update(
        {"title": "verification: wear maps versus the update interval", "data_origin": "simulated"}
    )
    return maps[-1], study


def _inputs(params: Any, size: StudySize) -> dict[str, np.ndarray]:
    """Latin-hypercube sample of the uncertain inputs (truncated normal, +-4 sd)."""
    from scipy.stats import qmc, truncnorm

    from jointwear.sim import DEFAULT_KW

    unit = qmc.LatinHypercube(d=len(ENSEMBLE_INPUTS), seed=size.seed).random(size.ensemble_runs)
    out = {}
    for j, (name, (rel, _)) in enumerate(ENSEMBLE_INPUTS.items()):
        section, field = name.split(".")
        mean = DEFAULT_KW if name == "wear.kw" else float(getattr(getattr(params, section), field))
        out[name] = mean * (1 + rel * truncnorm.ppf(unit[:, j], -4.0, 4.0))
    return out


def run_reference_study(
    out: str | Path,
    size: StudySize = FULL,
    *,
    say: Callable[[str], None] = lambda _: None,
) -> Any:
    """Simulate the default rig and decide every reported quantity of the reference study.

    Parameters
    ----------
    out : path
        Folder (created) for ``reported.nc``, ``sim_wear.nc``, ``verification.nc``,
        ``ensemble.nc`` and ``metrics.nc``.
    size : StudySize
        :data:`FULL` (benchmark) or :data:`REDUCED` (CI).
    say : callable
        Receives progress lines.

    Returns
    -------
    Comparison
        The decision card (one or two decisions per reported quantity).
    """
    from jointwear import io
    from jointwear.compare import as_ensemble, compare, save_comparison
    from jointwear.params import read_toml
    from jointwear.reported import reported_dataset
    from jointwear.sim import PARAMETER_SETS

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    src = reference_file()
    rep = reported_dataset(read_toml(src), src)
    rep_path = io.save(rep, out / "reported.nc", inputs=[src], parameters={"reported": str(src)})
    cycles = sorted(
        {float(v.attrs["cycles"]) for v in rep.data_vars.values() if v.attrs.get("cycles")}
    )
    params = PARAMETER_SETS["zhang2023"]
    grid = {"joint.n_layers": size.layers, "joint.n_points": size.points}
    sim, study = update_study(params, cycles, size, grid, say)
    sim_path = io.save(sim, out / "sim_wear.nc", parameters={"size": size, "dn": size.levels[-1]})
    ver_path = io.save(study, out / "verification.nc", parameters={"size": size})
    ens = None
    paths = [rep_path, sim_path, ver_path]
    if size.ensemble_runs:
        values = _inputs(params, size)
        members = []
        for r in range(size.ensemble_runs):
            say(f"ensemble member {r + 1}/{size.ensemble_runs}")
            change = {k: float(v[r]) for k, v in values.items()}
            members.append(_run(params, cycles, size.ensemble_dn, {**grid, **change})["wear_depth"])
        ds = xr.Dataset({"wear_depth": xr.concat(members, dim="run")})
        ds = ds.assign_coords(
            run=np.arange(size.ensemble_runs),
            **{k: ("run", v, {"units": "1", "long_name": k}) for k, v in values.items()},
        )
        ds.attrs.update(
            {
                "title": "ensemble over the uncertain inputs (Latin hypercube)",
                "data_origin": "simulated",
                "cycles": max(cycles),
                "probabilistic_sample": "true",
                "sweep_method": "lhs",
                "sweep_parameters": list(values),
            }
        )
        paths.append(io.save(ds, out / "ensemble.nc", parameters={"size": size}))
        ens = as_ensemble([ds], ["ensemble.nc"])
    result = compare(sim, rep, ensemble=ens, verification=[study])
    save_comparison(result, out / "metrics.nc", inputs=paths, parents=[sim, rep])
    return result
