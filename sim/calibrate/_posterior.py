"""The posterior's summaries, identifiability, predictive check, and its Dataset (posterior.nc).

Identifiability: per parameter, the posterior standard deviation over the prior's
(:data:`NOT_INFORMED_RATIO` or more: the data do not inform it, said in the summary); pairs whose
posterior correlation exceeds :data:`TRADE_OFF` in magnitude trade off (the data fix a
combination, not each).

Posterior predictive check: for every datum, the emulated value at each posterior sample plus a
draw of the likelihood's noise (u_D, u_num and the emulator's error, with their correlation) gives the predictive
distribution; the measured value must lie in its central ``ppc_level`` interval, otherwise the
model cannot fit that datum with any parameters the prior allows.
"""

from __future__ import annotations

import json
from dataclasses import dataclass

import numpy as np
import xarray as xr

__all__ = ["Identifiability", "identifiability", "Predictive", "predictive_check", "to_dataset"]

#: posterior sd / prior sd from which a parameter counts as not informed by the data
NOT_INFORMED_RATIO = 0.7
#: |posterior correlation| from which two parameters are said to trade off
TRADE_OFF = 0.8


@dataclass(frozen=True)
class Identifiability:
    """Prior and posterior widths, correlations, and what the data leave undetermined."""

    prior_mean: np.ndarray
    prior_sd: np.ndarray
    mean: np.ndarray
    sd: np.ndarray
    q025: np.ndarray
    q975: np.ndarray
    correlation: np.ndarray
    width_ratio: np.ndarray
    informed: np.ndarray
    pairs: tuple[tuple[str, str, float], ...]

    def lines(self, names: list[str]) -> list[str]:
        """One line per parameter and per trading-off pair (the summary)."""
        out = []
        for k, n in enumerate(names):
            state = "informed" if self.informed[k] else "NOT informed by the data"
            out.append(
                f"{n}: posterior {self.mean[k]:.4g} ± {self.sd[k]:.2g} (95 % "
                f"{self.q025[k]:.4g} .. {self.q975[k]:.4g}); posterior/prior sd "
                f"{self.width_ratio[k]:.2f}: {state}"
            )
        for a, b, r in self.pairs:
            out.append(f"{a} and {b} trade off (posterior correlation {r:+.2f})")
        return out


def identifiability(samples: np.ndarray, priors: list, names: list[str]) -> Identifiability:
    """Summaries of ``samples`` (n, n_p) against the priors (scipy frozen distributions)."""
    prior_mean = np.array([float(p.mean()) for p in priors])
    prior_sd = np.array([float(p.std()) for p in priors])
    sd = samples.std(axis=0, ddof=1)
    corr = np.atleast_2d(np.corrcoef(samples, rowvar=False))
    ratio = sd / prior_sd
    pairs = tuple(
        (names[i], names[j], float(corr[i, j]))
        for i in range(len(names))
        for j in range(i + 1, len(names))
        if abs(corr[i, j]) > TRADE_OFF
    )
    return Identifiability(
        prior_mean,
        prior_sd,
        samples.mean(axis=0),
        sd,
        np.quantile(samples, 0.025, axis=0),
        np.quantile(samples, 0.975, axis=0),
        corr,
        ratio,
        ratio < NOT_INFORMED_RATIO,
        pairs,
    )


@dataclass(frozen=True)
class Predictive:
    """The posterior predictive of every datum: mean, central interval, and where the data lie."""

    mean: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    p_below: np.ndarray
    level: float
    failed: tuple[int, ...]


def predictive_check(
    y_pred: np.ndarray, cov: np.ndarray, measured: np.ndarray, level: float, seed: int
) -> Predictive:
    """Predictive draws ``y_pred + N(0, cov)`` ((n, n_d), cov (n, n_d, n_d)) against the data."""
    rng = np.random.default_rng(seed)
    chol = np.linalg.cholesky(cov)
    draws = y_pred + (chol @ rng.standard_normal(y_pred.shape)[..., None])[..., 0]
    a = (1.0 - level) / 2
    lo, hi = np.quantile(draws, a, axis=0), np.quantile(draws, 1 - a, axis=0)
    p = np.mean(draws <= measured, axis=0)
    failed = tuple(int(i) for i in np.flatnonzero((measured < lo) | (measured > hi)))
    return Predictive(draws.mean(axis=0), lo, hi, p, level, failed)


def _var(dims, values, units, long_name, **attrs) -> xr.Variable:
    return xr.Variable(dims, values, {"units": units, "long_name": long_name, **attrs})


def to_dataset(
    *,
    names: list[str],
    units: list[str],
    chain,
    ident: Identifiability,
    data: list,
    u_num: np.ndarray,
    u_emulator: np.ndarray,
    ppc: Predictive,
    emulator,
    record: dict,
) -> xr.Dataset:
    """posterior.nc: samples along ``sample``, summaries along ``parameter``, data along ``datum``."""
    n_s = chain.samples.shape[0]
    ds = xr.Dataset(
        coords={
            "sample": _var("sample", np.arange(n_s), "1", "posterior sample"),
            "parameter": _var("parameter", np.array(names), "1", "calibrated parameter"),
            "parameter_2": _var("parameter_2", np.array(names), "1", "calibrated parameter"),
            "datum": _var("datum", np.array([d.label for d in data]), "1", "calibration datum"),
        }
    )
    for k, (n, u) in enumerate(zip(names, units, strict=True)):
        ds[n] = _var("sample", chain.samples[:, k], u, f"posterior sample of {n}")
    summaries = {
        "prior_mean": (ident.prior_mean, "prior mean"),
        "prior_sd": (ident.prior_sd, "prior standard deviation"),
        "posterior_mean": (ident.mean, "posterior mean"),
        "posterior_sd": (ident.sd, "posterior standard deviation"),
        "posterior_q025": (ident.q025, "posterior 2.5 % quantile"),
        "posterior_q975": (ident.q975, "posterior 97.5 % quantile"),
    }
    for key, (v, long) in summaries.items():
        ds[key] = _var("parameter", v, "parameter units (see each sample variable)", long)
    ds["width_ratio"] = _var(
        "parameter", ident.width_ratio, "1", "posterior sd / prior sd (identifiability)"
    )
    ds["informed"] = _var(
        "parameter",
        ident.informed.astype(np.int8),
        "1",
        f"1 if the data inform the parameter (width_ratio < {NOT_INFORMED_RATIO}), 0 if not",
    )
    ds["correlation"] = _var(("parameter", "parameter_2"), ident.correlation, "1", "posterior corr")
    ds["autocorrelation_time"] = _var(
        "parameter", chain.tau, "1", "integrated autocorrelation time (steps)"
    )
    ds["effective_sample_size"] = _var("parameter", chain.ess, "1", "effective sample size")
    ds["split_rhat"] = _var("parameter", chain.rhat, "1", "split-R-hat across walkers")
    du = [d.quantity for d in data]
    dunits = [
        "m3" if q == "worn_volume" else ("m" if q in _M or q.startswith("wear_field_") else "1")
        for q in du
    ]
    unit = dunits[0] if len(set(dunits)) == 1 else "see each datum's quantity"
    for key, v, long in (
        ("measured", [d.value for d in data], "measured value"),
        ("u_d", [d.u_d for d in data], "standard uncertainty of the measured value"),
        (
            "u_num",
            u_num,
            "numerical standard uncertainty at the posterior mean (at least the training "
            "runs' scatter)",
        ),
        ("u_emulator", u_emulator, "standard uncertainty of the emulated mean (cross-validated)"),
        ("ppc_mean", ppc.mean, "posterior predictive mean"),
        ("ppc_lo", ppc.lo, f"posterior predictive {(1 - ppc.level) / 2:.3%} quantile"),
        ("ppc_hi", ppc.hi, f"posterior predictive {(1 + ppc.level) / 2:.3%} quantile"),
    ):
        ds[key] = _var("datum", np.asarray(v, dtype=float), unit, long)
    for key, v, long in (  # dimensionless, one per datum
        ("ppc_p_below", ppc.p_below, "predictive probability below the datum"),
        ("datum_quantity", np.array(du), "quantity of the datum"),
        (
            "emulator_cv_error",
            emulator.cv_error,
            "leave-one-out RMS error of the emulator (relative where emulator_log = 1)",
        ),
        (
            "emulator_scatter",
            emulator.scatter,
            "the simulator's scatter between training runs (the emulator's white-noise term; "
            "relative where emulator_log = 1)",
        ),
        (
            "emulator_error",
            emulator.error,
            "error of the emulated mean, sqrt(cv_error^2 - scatter^2) (relative where "
            "emulator_log = 1)",
        ),
        ("emulator_log", emulator.log.astype(np.int8), "1: emulated in the logarithm"),
    ):
        ds[key] = _var("datum", v, "1", long)
    lines = ident.lines(names)
    ds.attrs.update(
        {
            "title": "jointwear calibration: posterior of the uncertain inputs",
            "jointwear_file": "posterior",
            "data_origin": "simulated",
            "calibrated_parameters": json.dumps(names),
            "not_informed": json.dumps(
                [n for n, i in zip(names, ident.informed, strict=True) if not i]
            ),
            "trade_offs": json.dumps([list(p) for p in ident.pairs]),
            "identifiability": "\n".join(lines),
            "acceptance_fraction": chain.acceptance,
            "sampler": (
                f"emcee EnsembleSampler (stretch move), {chain.walkers} walkers x {chain.steps} "
                f"steps, burn-in {chain.burn}, thinned by {chain.thin}"
            ),
            "ppc_level": ppc.level,
            **record,
        }
    )
    return ds


_M = ("max_wear_depth", "cylindricity")
