"""The measured map's u on the common grid: its independent part averages down over a cell.

Ground truth: a known wear map measured with white noise of known sigma on a dense trace
(3600 points per layer, 72 grid cells of 50 points). The scatter of the compared maximum depth
over independent noise seeds must match the stated u_D (issue 20/22).
"""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from jointwear.compare import align_wear_maps
from jointwear.compare._wear import _stated
from jointwear.conventions import theta_coord, z_coord

Z = (np.arange(5) - 2) * 1e-3
SIGMA = 0.2e-6  # per-point white noise [m]


def _wear(theta: np.ndarray) -> np.ndarray:
    peak = 5e-6 * np.exp(-0.5 * ((theta - 120.0) / 20.0) ** 2)
    return peak[None, :] * (1.0 - 0.1 * (Z[:, None] / 2e-3) ** 2)


def _map(theta: np.ndarray, values: np.ndarray, **extra) -> xr.Dataset:
    ds = xr.Dataset(
        {"wear_depth": (("z", "theta"), values, {"units": "m"}), **extra},
        coords={"z": z_coord(Z), "theta": theta_coord(theta)},
        attrs={"bearing_radius_m": 8e-3},
    )
    return ds


def _u_vars(shape: tuple, split: bool) -> dict:
    out = {"wear_depth_u": (("z", "theta"), np.full(shape, SIGMA), {"units": "m"})}
    if split:
        attrs = {"units": "m", "correlation_length_samples": 1.0}
        out["wear_depth_u_random"] = (("z", "theta"), np.full(shape, SIGMA), attrs)
    return out


def _compared_max(meas: xr.Dataset, sim: xr.Dataset) -> tuple[float, float]:
    al = align_wear_maps(sim, meas)
    s, d = al["wear_depth_sim"].values, al["wear_depth_meas"].values
    return float(np.nanmax(d)), _stated(al, s, d)["max_wear_depth"]["meas"][0]


@pytest.fixture(scope="module")
def maps():
    th_dense = np.arange(3600) * 0.1
    th_grid = np.arange(72) * 5.0
    sim = _map(th_grid, _wear(th_grid))
    truth = _map(th_dense, _wear(th_dense))
    return th_dense, sim, truth


def test_stated_u_of_the_maximum_matches_its_scatter(maps):
    th, sim, truth = maps
    true_max, _ = _compared_max(truth, sim)  # the truth's own value on the common grid
    z, stated = [], []
    for seed in range(20):
        noisy = _wear(th) + SIGMA * np.random.default_rng(seed).standard_normal((Z.size, th.size))
        d, u = _compared_max(_map(th, noisy, **_u_vars(noisy.shape, True)), sim)
        z.append((true_max - d) / u)
        stated.append(u)
    rms = float(np.sqrt(np.mean(np.square(z))))
    assert 0.6 <= rms <= 1.6, f"RMS (truth - D)/u_D = {rms:.2f} over 20 seeds"
    assert max(abs(v) for v in z) < 4
    # ~50 independent samples per 5-degree cell: the per-point u / sqrt(50)
    assert np.median(stated) == pytest.approx(SIGMA / np.sqrt(50), rel=0.05)


def test_correlated_noise_averages_down_less(maps):
    """A random part correlated over tau samples counts n / tau independent samples per cell."""
    th, sim, _ = maps
    ds = _map(th, _wear(th), **_u_vars((Z.size, th.size), True))
    ds["wear_depth_u_random"].attrs["correlation_length_samples"] = 10.0
    _, u = _compared_max(ds, sim)
    assert u == pytest.approx(SIGMA / np.sqrt(5), rel=0.05)


def test_without_the_random_part_the_per_point_u_is_used(maps):
    """Older files and simulated maps do not split their u: the per-point u, as before."""
    th, sim, _ = maps
    _, u = _compared_max(_map(th, _wear(th), **_u_vars((Z.size, th.size), False)), sim)
    assert u == pytest.approx(SIGMA, rel=1e-9)
    # a systematic part is not averaged: u^2 = sys^2 + (random / sqrt(n))^2
    ds = _map(th, _wear(th), **_u_vars((Z.size, th.size), True))
    ds["wear_depth_u"] = ds["wear_depth_u"] * np.sqrt(2.0)
    _, u = _compared_max(ds, sim)
    assert u == pytest.approx(SIGMA * np.sqrt(1 + 1 / 50), rel=0.02)


def test_unstated_random_part_in_some_cells_keeps_their_whole_u(maps):
    """A NaN random part (not stated there) is not a zero u: those cells keep the per-point u."""
    th, sim, _ = maps
    ds = _map(th, _wear(th), **_u_vars((Z.size, th.size), True))
    near_peak = (th > 100.0) & (th < 140.0)
    ds["wear_depth_u_random"][:, near_peak] = np.nan
    _, u = _compared_max(ds, sim)
    assert u == pytest.approx(SIGMA, rel=1e-9)
