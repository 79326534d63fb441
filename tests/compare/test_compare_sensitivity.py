"""The sensitivity column: SRC² against SALib's Sobol estimator on known functions."""

from __future__ import annotations

import _jw_synth as syn
import numpy as np
import pytest
import xarray as xr
from SALib.analyze import sobol as sobol_analyze
from SALib.sample import sobol as sobol_sample
from scipy.stats import qmc

from jointwear.compare import compare
from jointwear.compare.sensitivity import src_squared

A = np.array([1.0, 2.0, 0.5])  # y = A · x, x uniform on [0, 1]^3


def _salib_s1(fn, bounds, n=2048):
    problem = {"num_vars": len(bounds), "names": [f"x{i}" for i in range(3)], "bounds": bounds}
    x = sobol_sample.sample(problem, n, calc_second_order=False, seed=1)
    return sobol_analyze.analyze(problem, fn(x), calc_second_order=False, seed=1)


def _lhs(n, seed):
    return qmc.LatinHypercube(d=3, seed=seed).random(n)


def test_src2_of_a_linear_model_matches_salib_and_the_closed_form():
    salib = _salib_s1(lambda x: x @ A, [[0.0, 1.0]] * 3)
    exact = A**2 / np.sum(A**2)  # S1 of a linear model of independent uniform inputs
    assert salib["S1"] == pytest.approx(exact, abs=0.03)
    x = _lhs(400, seed=2)
    src2, r2, corr = src_squared(x, x @ A)
    assert r2 == pytest.approx(1.0) and corr < 0.1
    assert src2 == pytest.approx(salib["S1"], abs=0.03)
    assert src2 == pytest.approx(exact, abs=0.03)


def test_src2_of_ishigami_is_only_a_ranking_and_says_so():
    """Ishigami (a = 7, b = 0.1): S1 = 0.31, 0.44, 0 - x2 acts through sin², which a linear fit
    cannot see (SRC² ~ 0), so R² is far below 1 and the method must not call SRC² Sobol indices."""

    def ishigami(x):
        return np.sin(x[:, 0]) + 7 * np.sin(x[:, 1]) ** 2 + 0.1 * x[:, 2] ** 4 * np.sin(x[:, 0])

    salib = _salib_s1(ishigami, [[-np.pi, np.pi]] * 3)
    assert salib["S1"] == pytest.approx([0.314, 0.442, 0.0], abs=0.05)
    x = -np.pi + 2 * np.pi * _lhs(400, seed=3)
    src2, r2, _ = src_squared(x, ishigami(x))
    assert r2 < 0.5 and src2[1] < 0.05 < salib["S1"][1]  # the linear fit misses x2 entirely
    c = _compare(x, ishigami(x))
    assert c.sensitivity.method.str.contains("NOT variance shares").all()


def _compare(x, y):
    """compare() with a random ensemble of max_wear_depth = 32 µm (1 + 0.01 y)."""
    depth = 32e-6 * (1 + 0.01 * (y - y.mean()) / y.std())
    ens = xr.Dataset(
        {"max_wear_depth": ("run", depth, {"units": "m"})},
        coords={"run": np.arange(len(y)), **{f"x{i}": ("run", x[:, i]) for i in range(3)}},
        attrs={"cycles": 4e5},
    )
    return compare(syn.sim_wear(), syn.meas_wear(u=1e-6, n_layers=16), ensemble=ens)


def test_the_sensitivity_column_names_its_estimator_and_flags_correlated_inputs():
    x = _lhs(200, seed=4)
    c = _compare(x, x @ A)
    rows = c.sensitivity[c.sensitivity.quantity == "max_wear_depth"].set_index("parameter")
    assert (rows.estimator == "SRC²").all()
    assert rows.S1.to_numpy() == pytest.approx(A**2 / np.sum(A**2), abs=0.03)
    assert rows.method.iloc[0].endswith("≈ first-order Sobol indices (near-linear, nearly "
                                        "uncorrelated inputs)")  # fmt: skip
    # 8 runs with two strongly correlated inputs: SRC² can exceed 1 and are no variance shares
    rng = np.random.default_rng(5)
    x8 = rng.uniform(size=(8, 3))
    x8[:, 1] = x8[:, 0] + 0.05 * rng.standard_normal(8)
    c8 = _compare(x8, x8 @ A)
    m = c8.sensitivity.method.iloc[0]
    assert "NOT variance shares" in m and "|r| = 0.9" in m
    # the stored file keeps the estimator
    again = c8.to_dataset()
    from jointwear.compare.storage import load_comparison

    assert (load_comparison(again).sensitivity.estimator == "SRC²").all()
