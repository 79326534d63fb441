"""Bayesian calibration of the simulator's uncertain inputs on measured data (``sim calibrate``).

:func:`calibrate` runs a Latin-hypercube design over the prior through the sweep driver (dask,
resumable: ``<out>.design-<cycles>.nc``), reduces every training run to the calibration
quantities (:mod:`jointwear.sim.calibrate._data`), trains the emulator
(:mod:`~jointwear.sim.calibrate._emulator`), and samples the posterior
(:mod:`~jointwear.sim.calibrate._sampler`) of the Gaussian likelihood

    ln L = -1/2 [r(x)ᵀ Σ(x)⁻¹ r(x) + ln det Σ(x)],   r = y - η(x),
    Σ_ij = δ_ij (u_D,i² + u_emulator,i²) + T_ij (ρ_ij s_i s_j + b_i b_j),

with u_D the datum's own uncertainty, u_emulator the emulator's cross-validated error, s the
training runs' scatter (start phase, update intervals), and b = sqrt(max(u_num² - s², 0)) the
numerical uncertainty beyond it (u_num: a ``sim verify`` study on the datum's band, or the
stated ``u_num_rel``; the same sources compare uses). T_ij is 1 for two quantities of the same
map, else 0 (different maps independent); within a map the scatter is correlated as the
training runs' residuals are (ρ: a start phase that deepens the maximum adds less to the
volume, measured 0.6-0.75), the rest fully. The emulator is trusted only inside its training range: the
posterior is cut there (and refused where it would need more room than an unbounded prior
allows). It refuses (``CalibrationRefused``, exit 3), naming the figure and the fix: an emulator
error above ``emulator_max_fraction`` of a datum's u, a chain that did not converge, a datum
outside its posterior predictive interval.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from jointwear.errors import BadInputError
from jointwear.sim.calibrate._data import Band, Datum, file_record, on_band
from jointwear.sim.calibrate._spec import CalibrationSpec, read_calibration_spec

__all__ = ["calibrate", "CalibrationRefused", "design_path"]

#: the start phase of a wear run, drawn for every training run (not emulated: its scatter)
PHASE = "mechanism.initial_crank_angle_deg"


class CalibrationRefused(BadInputError):
    """The calibration cannot be trusted: the message names the figure and the fix (exit 3)."""


def design_path(out: str | Path, cycles: float) -> Path:
    """The training runs' file beside ``out`` (kept: ``--resume`` reuses it)."""
    out = Path(out)
    return out.with_name(f"{out.stem}.design-{cycles:.0f}.nc")


def _sweep_mapping(spec: CalibrationSpec, cycles: float, outputs: list[str], keep: bool) -> dict:
    sweep: dict[str, Any] = {
        "run": spec.run,
        "method": "lhs",
        "samples": spec.samples,
        "seed": spec.seed,
        "outputs": outputs,
    }
    if spec.run == "wear":
        sweep.update(cycles=cycles, max_cycles_simulated=spec.max_cycles_simulated)
        if keep:
            sweep["keep"] = ["wear_depth"]
    else:
        sweep.update(function=spec.function, function_args=spec.function_args)
    params = {}
    for p in spec.parameters:
        d = p.describe()
        d.pop("name")
        params[p.name] = d
    if spec.run == "wear" and PHASE not in params:
        # each training run starts at its own crank angle: the runs' scatter about the emulator
        # is then the cycle-to-cycle variability of one run (a floor of u_num), not hidden
        params[PHASE] = {"distribution": "uniform", "bounds": [0.0, 360.0]}
    return {"sweep": sweep, "parameters": params}


def _scale(spec: CalibrationSpec) -> tuple[np.ndarray, np.ndarray]:
    """(low, high) of each parameter's emulator range: its bounds, or its 0.01..99.99 % quantiles."""
    lo, hi = [], []
    for p in spec.parameters:
        a, b = p.bounds if p.bounded else p.ppf(np.array([1e-4, 1 - 1e-4]))
        lo.append(float(a))
        hi.append(float(b))
    return np.array(lo), np.array(hi)


def _training(
    spec: CalibrationSpec, data: list[Datum], bands: list[Band], radius: float, run: Callable
) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """Design values (n, n_p) and each datum's simulated value (n, n_d) of the finished runs."""
    x_all, notes = [], []
    by_cycles: dict[float, list[int]] = {}
    for i, d in enumerate(data):
        by_cycles.setdefault(d.cycles, []).append(i)
    columns: dict[int, np.ndarray] = {}
    ok_all = None
    for cycles, idx in sorted(by_cycles.items()):
        maps = any(data[i].band >= 0 for i in idx)
        outputs = sorted({data[i].quantity for i in idx if data[i].band < 0}) or (
            ["max_wear_depth"] if spec.run == "wear" else []
        )
        ds = run(_sweep_mapping(spec, cycles, outputs, maps), cycles)
        reduced: dict[tuple[int, int], dict[str, float]] = {}
        ok = np.asarray(ds["status"].values) == 0
        if not ok.all():
            first = str(ds["error"].values[np.flatnonzero(~ok)[0]])
            notes.append(f"{int((~ok).sum())} training run(s) at {cycles:g} cycles failed: {first}")
        ok_all = ok if ok_all is None else ok_all & ok
        x_all.append(np.column_stack([ds[n].values for n in spec.names]))
        for i in idx:
            d = data[i]
            if d.band < 0:
                columns[i] = np.asarray(ds[d.quantity].values, dtype=float)
                continue
            col = np.full(ds.sizes["run"], np.nan)
            for r in np.flatnonzero(ok):
                if (d.band, r) not in reduced:  # a band's quantities once per run
                    b = bands[d.band]
                    h = on_band(ds["wear_depth"].isel(run=r), b)
                    reduced[d.band, r] = b.quantities(h, radius)
                col[r] = reduced[d.band, r][d.quantity]
            columns[i] = col
    x = x_all[0]
    y = np.column_stack([columns[i] for i in range(len(data))])
    keep = ok_all & np.all(np.isfinite(y), axis=1)
    if keep.sum() < 4:
        raise CalibrationRefused(
            f"only {int(keep.sum())} of {len(x)} training runs finished with every quantity; "
            "the emulator needs at least 4: see the errors in the design file(s) "
            f"({'; '.join(notes) or 'no error recorded'}) and narrow the prior or fix their cause"
        )
    return x[keep], y[keep], notes


def _u_num(spec: CalibrationSpec, data: list[Datum], verification: Sequence[Any], bands, radius):
    """Relative u_num of every datum (fraction of the simulated value) and its basis."""
    rel = np.zeros(len(data))
    basis = []
    for i, d in enumerate(data):
        if spec.run == "function":
            basis.append("analytic function: no numerical error")
            continue
        found = None
        if verification and d.band >= 0:
            from jointwear.refinement import study_uncertainty

            band = bands[d.band]

            def fn(run: xr.DataArray, band=band, q=d.quantity) -> float:
                return band.quantities(on_band(run, band), radius)[q]

            fit = study_uncertainty(verification[0], d.quantity, fn)
            u_run = float(getattr(fit, "u_num_run", np.nan))
            if fit.assessed and np.isfinite(u_run) and fit.value:
                found = (u_run / abs(float(fit.value)), "verification study (sim verify), band")
        if found is None and spec.u_num_rel is not None:
            found = (spec.u_num_rel, f"stated u_num_rel = {spec.u_num_rel:g}")
        if found is None:
            raise _no_u_num(d.label)
        rel[i] = found[0]
        basis.append(found[1])
    return rel, basis


def _no_u_num(label: str) -> CalibrationRefused:
    return CalibrationRefused(
        f"u_num of {label} is not known: the likelihood needs it; give a verification study "
        "(--verification STUDY.nc from 'jointwear sim verify') or state u_num_rel = <fraction> "
        "in [calibrate]"
    )


def _check_emulator(emu, data: list[Datum], rel_num: np.ndarray, limit: float) -> None:
    """Refuse an emulator whose error (of the emulated mean) is too large beside a datum's u."""
    y = np.array([d.value for d in data])[None, :]
    u_emu = emu.error_sd(y)[0]
    u_sim = np.maximum(rel_num * np.abs(y), emu.scatter_sd(y))[0]
    u_data = np.sqrt(np.array([d.u_d for d in data]) ** 2 + u_sim**2)
    for i, d in enumerate(data):
        if u_emu[i] > limit * u_data[i]:
            raise CalibrationRefused(
                f"the emulator's cross-validated error of {d.label} is {u_emu[i]:.3g} "
                f"({u_emu[i] / u_data[i]:.2f} of the datum's u {u_data[i]:.3g}, limit "
                f"emulator_max_fraction = {limit:g}): the emulator would decide the posterior; "
                f"raise [calibrate] samples (now {len(emu.cv_residuals)} finished runs) or "
                "narrow the prior"
            )


def calibrate(
    spec: str | Path | CalibrationSpec,
    *,
    out: str | Path,
    params: Any = None,
    base: str | None = None,
    workers: int | None = None,
    scheduler: Any = None,
    resume: bool = False,
    verification: Sequence[str | Path] = (),
    on_progress: Callable[[dict[str, Any]], None] | None = None,
) -> xr.Dataset:
    """Calibrate the spec's parameters on its data and write the posterior to ``out``.

    Parameters
    ----------
    spec : path or CalibrationSpec
        The calibration spec (TOML; docs/calibration.md).
    out : path
        posterior.nc (the training runs go to ``<out stem>.design-<cycles>.nc`` beside it).
    params, base
        The rig: ``--params`` TOML over the named set ``base`` (as ``sim sweep``).
    workers, scheduler, resume, on_progress
        The training runs' execution (as :func:`jointwear.sim.run_sweep`).
    verification : sequence of path
        A ``jointwear sim verify`` study: u_num of each map quantity on its band.

    Returns
    -------
    Dataset
        The posterior as written (``sample``, ``parameter`` and ``datum`` dimensions).

    Raises
    ------
    CalibrationRefused
        Emulator error too large, chain not converged, data outside the predictive interval.
    """
    from jointwear import io
    from jointwear._version import source_attribute
    from jointwear.sim.sweep import parameter_units, read_spec
    from jointwear.sim.sweep._driver import _base, run_sweep

    spec_file = [Path(spec)] if isinstance(spec, (str, Path)) else []
    spec = spec if isinstance(spec, CalibrationSpec) else read_calibration_spec(spec)
    io.check_writable(out, what="--out")
    sim, _, base_record, param_files = _base(
        read_spec(_sweep_mapping(spec, spec.cycles[0], _probe_outputs(spec), False)),
        params,
        None,
        base,
    )
    radius = float(sim.joint.bearing_radius) if sim is not None else 1.0
    studies = [io.load(p, validate=False) for p in verification]
    data, bands, read_notes = _read_data(spec, radius)

    def run(mapping: dict, cycles: float) -> xr.Dataset:
        return run_sweep(
            mapping,
            out=design_path(out, cycles),
            params=params,
            workers=workers,
            scheduler=scheduler,
            resume=resume,
            on_progress=on_progress,
            base=base,
        )

    if spec.run == "wear" and spec.u_num_rel is None and not studies:  # before any run
        raise _no_u_num(data[0].label)
    x, y, notes = _training(spec, data, bands, radius, run)
    lo, hi = _scale(spec)
    from jointwear.sim.calibrate._emulator import fit_emulator

    emu = fit_emulator((x - lo) / (hi - lo), y, seed=spec.seed)
    rel_num, num_basis = _u_num(spec, data, studies, bands, radius)
    _check_emulator(emu, data, rel_num, spec.emulator_max_fraction)
    result = _sample(spec, data, emu, rel_num, lo, hi)
    chain, ident, ppc, u_num, u_emu = result
    record = {
        "calibration_data": json.dumps([file_record(p) for p in spec.data]),
        "calibration_values": json.dumps([v.source for v in spec.values]),
        "calibration_cycles": json.dumps(sorted({d.cycles for d in data})),
        "base_parameters": json.dumps(base_record, default=str),
        "base_set": base or "",
        "u_num_basis": json.dumps(num_basis),
        "u_d_basis": json.dumps([d.u_d_basis or d.source for d in data]),
        "calibration_notes": "\n".join(read_notes + notes),
        "run": spec.run,
    }
    from jointwear.sim.calibrate._posterior import to_dataset

    ds = to_dataset(
        names=spec.names,
        units=[parameter_units(n) if spec.run == "wear" else "1" for n in spec.names],
        chain=chain,
        ident=ident,
        data=data,
        u_num=u_num,
        u_emulator=u_emu,
        ppc=ppc,
        emulator=emu,
        record=record,
    )
    io.save(
        ds,
        out,
        inputs=[*spec_file, *spec.data, *param_files, *verification],
        parameters={"calibration": spec.describe(), "base": base_record},
        source=source_attribute("sim.calibrate"),
    )
    return ds


def _probe_outputs(spec: CalibrationSpec) -> list[str]:
    if spec.run == "function":
        return sorted({v.quantity for v in spec.values})
    return ["max_wear_depth"]


def _read_data(spec: CalibrationSpec, radius: float) -> tuple[list[Datum], list[Band], list[str]]:
    """The data (measured maps, reported files, inline values), their bands and notes."""
    from jointwear import io
    from jointwear.reported import is_reported
    from jointwear.sim.calibrate._data import map_data
    from jointwear.sim.calibrate._reported import reported_data

    data: list[Datum] = []
    bands: list[Band] = []
    notes: list[str] = []
    for i, path in enumerate(spec.data):
        if path.suffix.lower() == ".toml":  # a reported-measurement file itself
            from jointwear.reported import read_reported

            ds = read_reported(path)
        else:
            ds = io.load(path, validate=False)
        if is_reported(ds):
            new_bands, rows, why = reported_data(ds, path, len(bands))
            bands += new_bands
            notes += why
        else:
            band, rows = map_data(
                ds,
                path,
                len(bands),
                spec.cycles_of(i),
                spec.quantities,
                radius,
                (spec.field_bins_z, spec.field_bins_theta),
            )
            bands.append(band)
        data += rows
    for v in spec.values:
        band = -1
        if v.z:  # measured on these layers: the simulated map reduced there, every 1 degree
            nan = np.full((len(v.z), 360), np.nan)
            bands.append(Band(np.array(v.z), np.arange(360.0), nan, nan, None))
            band = len(bands) - 1
        data.append(Datum(v.quantity, spec.cycles[0], v.value, v.u, v.source, band, v.source))
    return data, bands, notes


def _sample(spec: CalibrationSpec, data: list[Datum], emu, rel_num, lo, hi):
    """Sample the posterior, check the chain, the domain and the predictive; the pieces."""
    from jointwear.sim.calibrate._posterior import identifiability, predictive_check
    from jointwear.sim.calibrate._sampler import sample

    priors = [p._scipy() for p in spec.parameters]
    y_d = np.array([d.value for d in data])
    u_d2 = np.array([d.u_d for d in data]) ** 2
    # the quantities of one map share a run: its scatter (start phase, update intervals) moves
    # them together as the training runs' residuals say (their correlation), and u_num beyond
    # that scatter (a stated or verified discretisation error) moves them fully together
    group = np.array([d.band if d.band >= 0 else -1 - i for i, d in enumerate(data)])
    together = (group[:, None] == group[None, :]).astype(float)
    rho = together * emu.correlation

    def noise_cov(y: np.ndarray) -> np.ndarray:
        scatter = emu.scatter_sd(y)
        beyond = np.sqrt(np.maximum((rel_num * np.abs(y)) ** 2 - scatter**2, 0.0))
        diag = u_d2 + emu.error_sd(y) ** 2
        cov = rho * scatter[:, :, None] * scatter[:, None, :]
        cov = cov + together * beyond[:, :, None] * beyond[:, None, :]
        return cov + diag[:, :, None] * np.eye(len(y_d))

    def log_prob(x: np.ndarray) -> np.ndarray:
        inside = np.all((x >= lo) & (x <= hi), axis=1)
        out = np.full(len(x), -np.inf)
        if not inside.any():
            return out
        xi = x[inside]
        lp = sum(p.logpdf(xi[:, k]) for k, p in enumerate(priors))
        y = emu.predict((xi - lo) / (hi - lo))
        cov = noise_cov(y)
        r = y - y_d
        _, logdet = np.linalg.slogdet(cov)
        out[inside] = lp - 0.5 * (
            np.sum(r * np.linalg.solve(cov, r[..., None])[..., 0], 1) + logdet
        )
        return out

    rng = np.random.default_rng(spec.seed)
    start = lo + (hi - lo) * (0.25 + 0.5 * rng.random((spec.walkers, len(lo))))
    chain = sample(
        log_prob, start, max_steps=spec.max_steps, seed=spec.seed, rhat_max=spec.rhat_max
    )
    _check_domain(chain.samples, spec, lo, hi)  # a cut posterior first: more steps do not help
    _check_chain(chain, spec)
    ident = identifiability(chain.samples, priors, spec.names)
    y_s = emu.predict((chain.samples - lo) / (hi - lo))
    ppc = predictive_check(y_s, noise_cov(y_s), y_d, spec.ppc_level, spec.seed)
    for i in ppc.failed:
        d = data[i]
        raise CalibrationRefused(
            f"posterior predictive check failed for {d.label}: measured {d.value:.4g} ± "
            f"{d.u_d:.2g}, outside the {100 * spec.ppc_level:g} % predictive interval "
            f"{ppc.lo[i]:.4g} .. {ppc.hi[i]:.4g}: no parameters the prior allows fit this "
            "datum together with the others; check the data and the prior ranges, or the "
            "model form"
        )
    y_mean = emu.predict(((ident.mean - lo) / (hi - lo))[None, :])
    u_num = np.maximum(rel_num * np.abs(y_mean), emu.scatter_sd(y_mean))[0]
    return chain, ident, ppc, u_num, emu.error_sd(y_mean)[0]


def _check_chain(chain, spec: CalibrationSpec) -> None:
    worst = int(np.argmax(chain.rhat))
    if not chain.long_enough or not chain.rhat[worst] <= spec.rhat_max:
        need = int(60 * np.max(chain.tau))
        raise CalibrationRefused(
            f"the posterior chain did not converge: {chain.steps} steps of {chain.walkers} "
            f"walkers for an autocorrelation time of {np.max(chain.tau):.0f} steps (50 needed "
            f"per time), split-R-hat of {spec.names[worst]} = {chain.rhat[worst]:.3f} (limit "
            f"rhat_max = {spec.rhat_max:g}); raise [calibrate] max_steps to about "
            f"{max(need, 4 * chain.steps)} (or more walkers)"
        )


def _check_domain(samples: np.ndarray, spec: CalibrationSpec, lo, hi) -> None:
    """Refuse a posterior cut by the emulator's range where the prior goes on beyond it."""
    for k, p in enumerate(spec.parameters):
        if p.bounded:
            continue
        edge = 0.02 * (hi[k] - lo[k])
        share = float(np.mean((samples[:, k] < lo[k] + edge) | (samples[:, k] > hi[k] - edge)))
        if share > 0.01:
            raise CalibrationRefused(
                f'[parameters."{p.name}"]: {share:.0%} of the posterior lies at the edge of the '
                f"emulator's training range {lo[k]:.4g} .. {hi[k]:.4g} (the prior's 0.01..99.99 % "
                "quantiles): the data pull it beyond what was simulated; widen the prior"
            )
