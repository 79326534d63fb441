"""Benchmark: what moves a calibration datum besides kw - the start phase and the noise.

On the reduced tilt-1000 truth of ``bench_calibration.py`` (kw = 1.15 x the default, 400
cycles), the band quantities of the noise-free truth at ``phases`` start phases (18 degrees
apart) are compared with the emulated mean at the true kw (an emulator trained on the
calibration's training design); and the noise's bias of each quantity (1 % of the peak per
point, independent; the mean over 20 draws minus the noise-free value). Figures, per quantity
(max_wear_depth, worn_volume, cylindricity): the RMS, smallest and largest relative deviation
over the phases; their correlation between quantities; the training runs' scatter and its
correlation as the emulator estimates them; the noise's relative bias.

Run: ``python benchmarks/bench_calibration_phase.py [--design DESIGN.nc]`` (a kept training
design of the reduced tilt-1000 study, e.g. ``--folder``'s ``design-master.nc``; without it the
40 training runs are simulated). Results: benchmarks/results/calibration_phase.json.
"""

from __future__ import annotations

import dataclasses
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _common import write_results  # noqa: E402
from bench_calibration import KW_FACTOR, NOISE, SIZES, base_toml, spec_text  # noqa: E402

Q = ("max_wear_depth", "worn_volume", "cylindricity")
PHASES = 20


def main() -> None:
    from jointwear import io
    from jointwear.params import from_mapping, read_toml
    from jointwear.sim import WearSettings, load_parameters, run_sweep, simulate_wear
    from jointwear.sim.calibrate import read_calibration_spec
    from jointwear.sim.calibrate._data import band_quantities
    from jointwear.sim.calibrate._emulator import fit_emulator
    from jointwear.sim.calibrate._run import _sweep_mapping
    from jointwear.sim.wear._settings import DEFAULT_KW

    size = SIZES["reduced"]
    folder = Path(tempfile.mkdtemp(prefix="bench-calibration-phase-"))
    (folder / "base.toml").write_text(base_toml(size, "tilt1000"))
    kw = KW_FACTOR * DEFAULT_KW
    p0 = load_parameters(folder / "base.toml")
    wear = read_toml(folder / "base.toml")["wear"]
    w = dataclasses.replace(from_mapping(WearSettings, wear, where="wear"), kw=kw)
    c1 = size["calibration_cycles"]
    maps = []
    for k in range(PHASES):
        mech = dataclasses.replace(p0.mechanism, initial_crank_angle_deg=18.0 * k)
        ds = simulate_wear(dataclasses.replace(p0, mechanism=mech), cycles=c1, settings=w)
        maps.append(ds["wear_depth"].isel(cycles=-1).transpose("z", "theta"))
    z, th = (np.asarray(maps[0][c].values) for c in ("z", "theta"))
    r = float(p0.joint.bearing_radius)
    truth = np.array([[band_quantities(m.values, z, th, r)[q] for q in Q] for m in maps])
    rng = np.random.default_rng(0)
    bias = []
    for m in maps:
        h = m.values
        u = NOISE * float(h.max())
        draws = [band_quantities(h + u * rng.standard_normal(h.shape), z, th, r) for _ in range(20)]
        clean = band_quantities(h, z, th, r)
        bias.append([np.mean([d[q] for d in draws]) / clean[q] - 1 for q in Q])
    # the emulated mean at the true kw, from the calibration's training design
    early = folder / "truth.nc"
    io.save(maps[0].to_dataset(name="wear_depth").assign_attrs(bearing_radius_m=r), early)
    (folder / "spec.toml").write_text(spec_text(early, size, DEFAULT_KW))
    spec = read_calibration_spec(folder / "spec.toml")
    given = sys.argv[sys.argv.index("--design") + 1] if "--design" in sys.argv else None
    design = (
        io.load(given, validate=False)
        if given
        else run_sweep(
            _sweep_mapping(spec, c1, ["max_wear_depth"], True),
            out=folder / "design.nc",
            params=folder / "base.toml",
            workers=0,
        )
    )
    ok = np.asarray(design["status"].values) == 0
    y = np.array(
        [
            [band_quantities(design["wear_depth"].isel(run=i).values, z, th, r)[q] for q in Q]
            for i in np.flatnonzero(ok)
        ]
    )
    lo, hi = 0.5 * DEFAULT_KW, 1.5 * DEFAULT_KW
    x = (np.asarray(design["wear.kw"].values)[ok] - lo) / (hi - lo)
    emu = fit_emulator(x[:, None], y, seed=1)
    dev = truth / emu.predict(np.array([[(kw - lo) / (hi - lo)]]))[0] - 1
    corr = np.corrcoef(dev, rowvar=False)
    figures = {
        "size": size | {"phases": PHASES, "phase_step_deg": 18.0},
        "truth": {"joint.tilt_stiffness": 1000.0, "kw_factor": KW_FACTOR, "noise_rel": NOISE},
        "phase_deviation": {
            q: {
                "rms": float(np.sqrt(np.mean(dev[:, k] ** 2))),
                "min": float(dev[:, k].min()),
                "max": float(dev[:, k].max()),
            }
            for k, q in enumerate(Q)
        },
        "phase_correlation_max_depth_volume": float(corr[0, 1]),
        "phase_correlation_max_depth_cylindricity": float(corr[0, 2]),
        "emulator_scatter_rel": dict(zip(Q, map(float, emu.scatter), strict=True)),
        "emulator_correlation_max_depth_volume": float(emu.correlation[0, 1]),
        "noise_bias_rel": dict(zip(Q, map(float, np.mean(bias, axis=0)), strict=True)),
        "design": given or "simulated here",
    }
    write_results("calibration_phase", figures)


if __name__ == "__main__":
    main()
