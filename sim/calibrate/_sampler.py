"""Posterior sampling with emcee and the diagnostics that say whether the chain can be trusted.

emcee's affine-invariant ensemble sampler (Goodman & Weare 2010; Foreman-Mackey et al. 2013)
needs no tuning and is invariant to the parameters' scales (kw ~ 1e-15 m²/N beside an offset
~ 1e-3 m), which is why it serves here: a handful of parameters, a cheap emulated likelihood.
The walkers advance in chunks until the chain is long enough: at least ``50 τ`` steps (τ the
largest integrated autocorrelation time, emcee's estimator) with τ stable to 5 % between
chunks, or ``max_steps``. Reported: the mean acceptance fraction, τ and the effective sample
size per parameter (walkers × kept steps / τ), and the split-R̂ across walkers (Gelman & Rubin's
potential scale reduction over each walker's two halves after burn-in; Vehtari et al. 2021
recommend < 1.01). Walkers of one ensemble are not independent chains, so R̂ is a necessary
check, not a proof.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

__all__ = ["Chain", "sample", "split_rhat"]

#: steps per chunk between convergence checks, and the chain length in autocorrelation times
CHUNK, TAU_FACTOR = 500, 50
#: largest relative change of τ between two checks of a chain that is long enough
TAU_CHANGE = 0.05


@dataclass(frozen=True)
class Chain:
    """Posterior samples and diagnostics.

    Attributes
    ----------
    samples : ndarray (n_samples, n_p)
        Kept samples (after burn-in, thinned), parameter units.
    acceptance : float
        Mean acceptance fraction of the walkers.
    tau : ndarray (n_p,)
        Integrated autocorrelation time per parameter [steps].
    ess : ndarray (n_p,)
        Effective sample size per parameter.
    rhat : ndarray (n_p,)
        Split-R̂ across walkers per parameter.
    steps, burn, thin, walkers : int
        Steps per walker run, discarded at the start, thinning, number of walkers.
    long_enough : bool
        Whether steps >= 50 τ with τ stable between the last two checks (the split-R̂ is
        checked by the caller).
    """

    samples: np.ndarray
    acceptance: float
    tau: np.ndarray
    ess: np.ndarray
    rhat: np.ndarray
    steps: int
    burn: int
    thin: int
    walkers: int
    long_enough: bool


def split_rhat(chains: np.ndarray) -> np.ndarray:
    """Split-R̂ of chains (n_chains, n_steps, n_p): each chain halved, Gelman-Rubin on the halves."""
    n = chains.shape[1] // 2
    halves = np.concatenate([chains[:, :n], chains[:, n : 2 * n]], axis=0)
    mean = halves.mean(axis=1)
    var_within = halves.var(axis=1, ddof=1).mean(axis=0)
    var_between = n * mean.var(axis=0, ddof=1)
    var_plus = (n - 1) / n * var_within + var_between / n
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.sqrt(var_plus / var_within)


def sample(
    log_prob: Callable[[np.ndarray], np.ndarray],
    start: np.ndarray,
    *,
    max_steps: int,
    seed: int,
    rhat_max: float = 1.01,
) -> Chain:
    """Sample ``log_prob`` (vectorised: (n, n_p) -> (n,)) from walkers at ``start`` (W, n_p).

    Runs until the chain is long enough (50 τ, τ stable) and its split-R̂ is at most
    ``rhat_max`` for every parameter, or ``max_steps`` steps per walker.
    """
    import emcee

    walkers, n_p = start.shape
    sampler = emcee.EnsembleSampler(walkers, n_p, log_prob, vectorize=True)
    state = emcee.State(start, random_state=np.random.RandomState(seed).get_state())
    old = np.full(n_p, np.inf)
    long_enough = False
    steps = 0
    while steps < max_steps:
        n = min(CHUNK, max_steps - steps)
        state = sampler.run_mcmc(state, n, progress=False)
        steps += n
        tau = sampler.get_autocorr_time(tol=0)
        long_enough = steps >= TAU_FACTOR * np.max(tau) and np.all(
            np.abs(old - tau) < TAU_CHANGE * tau
        )
        old = tau
        if long_enough:
            burn = min(int(np.ceil(2 * np.max(tau))), steps // 2)
            chain = np.swapaxes(sampler.get_chain(discard=burn), 0, 1)
            if np.all(split_rhat(chain) <= rhat_max):
                break
    tau = sampler.get_autocorr_time(tol=0)
    burn = min(int(np.ceil(2 * np.max(tau))), steps // 2)
    thin = max(1, int(0.5 * np.min(tau)))
    chain = sampler.get_chain(discard=burn)  # (steps, walkers, n_p)
    kept = steps - burn
    return Chain(
        samples=sampler.get_chain(discard=burn, thin=thin, flat=True),
        acceptance=float(np.mean(sampler.acceptance_fraction)),
        tau=np.asarray(tau, dtype=float),
        ess=walkers * kept / np.asarray(tau, dtype=float),
        rhat=split_rhat(np.swapaxes(chain, 0, 1)),
        steps=steps,
        burn=burn,
        thin=thin,
        walkers=walkers,
        long_enough=long_enough,
    )
