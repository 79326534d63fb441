"""Eça-Hoekstra least-squares refinement procedure (jointwear.refinement) against hand values."""

from __future__ import annotations

import math

import numpy as np
import pytest

from jointwear.errors import BadInputError
from jointwear.refinement import (
    eca_hoekstra,
    grid_term,
    level_statistics,
)

H = np.array([1.0, 2.0, 4.0, 8.0])


def _fixed_fit_u(h, phi, orders, fs=3.0, w_stat=None):
    """Independent re-computation of the fixed-order branch (numpy polyfit-free normal eqs.)."""
    best = None
    x = h / h.min()
    ws = np.ones_like(x) if w_stat is None else w_stat
    for w in (np.ones_like(x) * ws, ws / x):
        w = w / w.sum()
        for cols in orders:
            a = np.column_stack([np.ones_like(x)] + [x**k for k in cols])
            # weighted normal equations
            coef = np.linalg.solve(a.T @ (a * w[:, None]), a.T @ (w * phi))
            fit = a @ coef
            us = math.sqrt(np.sum(x.size * w * (phi - fit) ** 2) / (x.size - a.shape[1]))
            if best is None or us < best[0]:
                best = (us, coef[0], fit)
    us, phi0, fit = best
    i = int(np.argmin(h))
    eps = abs(fit[i] - phi0)
    resid = abs(phi[i] - fit[i])
    drange = np.ptp(phi) / (phi.size - 1)
    if us < drange:
        return (fs * eps + us + resid) / 2, False
    return 3 * us / drange * (eps + us + resid) / 2, True


def test_monotone_first_order_exact():
    # phi = 1 + 0.5 h: p = 1, phi0 = 1, U_s = 0, eps = 0.5 at h = 1 -> U = 1.25 * 0.5
    fit = eca_hoekstra(H, 1 + 0.5 * H, quantity="q")
    assert fit.assessed
    assert fit.branch.startswith("p credible")
    assert fit.order == pytest.approx(1.0, abs=1e-6)
    assert fit.extrapolated == pytest.approx(1.0, abs=1e-9)
    assert fit.safety_factor == 1.25
    assert fit.value == 1.5
    assert fit.u_refinement == pytest.approx(0.625 / 2, rel=1e-6)
    assert fit.u_stat == 0.0
    assert fit.u_num == pytest.approx(0.3125, rel=1e-6)
    assert math.isnan(fit.u_grid)


def test_order_above_formal_uses_fixed_order_and_fs3():
    phi = 1 + 0.1 * H**2  # p = 2
    fo1 = eca_hoekstra(H, phi, formal_order=1.0)
    assert fo1.order == pytest.approx(2.0, abs=1e-4)
    assert fo1.branch.startswith("p >= 1.05: fit with fixed order 1")
    assert fo1.safety_factor == 3.0
    want, scattered = _fixed_fit_u(H, phi, [(1,)])
    assert not scattered
    assert fo1.u_refinement == pytest.approx(want, rel=1e-9)
    # the same data for a second-order method: p = 2 < 2.1 is credible, eps = 0.1, U = 0.125
    fo2 = eca_hoekstra(H, phi, formal_order=2.0)
    assert fo2.branch.startswith("p credible")
    assert fo2.u_refinement == pytest.approx(0.125 / 2, rel=1e-6)


def test_oscillatory_series_is_scattered_data_range_times_3():
    phi = np.array([1.1, 0.9, 1.1, 0.9])  # fine to coarse, no convergence
    fit = eca_hoekstra(H, phi)
    assert fit.assessed
    assert fit.branch.startswith("scattered")
    assert fit.safety_factor == 3.0
    orders = [(1,), (2,), (1, 2)] if fit.order < 0.5 else [(1,)]
    want, scattered = _fixed_fit_u(H, phi, orders)
    assert scattered
    assert fit.u_refinement == pytest.approx(want, rel=1e-9)
    # larger than the whole spread of the solutions: the data say nothing about convergence
    assert fit.u_num > np.ptp(phi)


def test_scattered_series_hand_value():
    phi = np.array([1.0, 1.3, 0.8, 1.2])
    fit = eca_hoekstra(H, phi)
    orders = [(1,), (2,), (1, 2)] if fit.order < 0.5 else [(1,)]
    want, scattered = _fixed_fit_u(H, phi, orders)
    assert scattered and fit.branch.startswith("scattered")
    assert fit.u_refinement == pytest.approx(want, rel=1e-9)


def test_units_and_offsets_do_not_change_the_procedure():
    rng = np.random.default_rng(3)
    phi = 1 + 0.05 * H + rng.normal(0, 0.01, 4)
    s = np.full(4, 0.01)
    ref = eca_hoekstra(H, phi, s)
    # metres instead of micrometres, an offset, and dN in cycles instead of thousands
    scaled = eca_hoekstra(H * 5000, 1e-6 * phi + 3e-5, 1e-6 * s)
    assert scaled.branch == ref.branch
    assert scaled.u_num == pytest.approx(1e-6 * ref.u_num, rel=1e-6)
    assert scaled.order == pytest.approx(ref.order, rel=1e-6)


def test_standard_errors_weight_the_fit_and_give_u_stat():
    phi = 2 + 0.3 * H
    s = np.array([0.01, 0.02, 0.02, 0.5])
    fit = eca_hoekstra(H, phi, s)
    assert fit.u_stat == 0.01
    assert "x 1/s²" in fit.branch
    assert fit.u_num == pytest.approx(math.hypot(0.01, 1.25 * 0.3 / 2), rel=1e-6)
    # the order's standard deviation comes from the standard errors (exact data: finite, small)
    assert 0 < fit.order_sd < 0.5


def test_noise_without_trend_is_not_a_small_uncertainty():
    # the wrong answer: a noise-only series fitted as "converged" with u_num << the noise
    rng = np.random.default_rng(7)
    sem = 0.05
    for _ in range(20):
        phi = 1 + rng.normal(0, sem, 4)
        fit = eca_hoekstra(H, phi, np.full(4, sem))
        assert fit.assessed
        assert fit.u_num >= sem


def test_inert_refinement_parameter_is_not_assessed():
    fit = eca_hoekstra(H, [3.0, 3.0, 3.0, 3.0])
    assert not fit.assessed
    assert "inert" in fit.reason
    assert math.isnan(fit.u_num)


def test_too_few_levels_and_failed_levels():
    fit = eca_hoekstra(H[:3], [1.0, 1.1, 1.3])
    assert not fit.assessed and "at least 4" in fit.reason
    fit = eca_hoekstra(H, [1.0, np.nan, 1.2, 1.4])
    assert not fit.assessed and "1 level(s) without a value" in fit.reason
    # without the finest level the figures would belong to another level: refused
    fit = eca_hoekstra(H, [1.0, 1.1, 1.2, 1.4, 1.7][:4], [np.nan, 0.1, 0.1, 0.1])
    assert not fit.assessed and "finest level" in fit.reason
    fit = eca_hoekstra([0.5, *H], [0.9, 1.0, 1.1, 1.2, 1.4], [np.nan, 0.1, 0.1, 0.1, 0.1])
    assert not fit.assessed and "h = 0.5" in fit.reason


@pytest.mark.parametrize(
    ("h", "m", "s", "match"),
    [
        ([1, 2, 3], [1, 2], None, "refinement values"),
        ([1, 2, 2, 4], [1, 2, 3, 4], None, "share the refinement value"),
        ([0, 1, 2, 4], [1, 2, 3, 4], None, "must be finite and > 0"),
        ([1, 2, 3, 4], [1, 2, 3, 4], [0.1, -0.1, 0.1, 0.1], "negative"),
        ([1, 2, 3, 4], [1, 2, 3, 4], [0.1, 0.1], "standard errors"),
    ],
)
def test_bad_input(h, m, s, match):
    with pytest.raises(BadInputError, match=match):
        eca_hoekstra(h, m, s)


def test_with_grid_adds_in_quadrature_and_missing_grid_is_not_assessed():
    fit = eca_hoekstra(H, 1 + 0.5 * H, np.full(4, 0.1))
    g = fit.with_grid(0.2)
    assert g.u_num == pytest.approx(math.sqrt(0.1**2 + fit.u_refinement**2 + 0.2**2))
    n = fit.with_grid(float("nan"), "grid runs failed")
    assert not n.assessed and n.reason == "grid runs failed" and math.isnan(n.u_num)
    assert "grid runs failed" in n.describe()


def test_grid_term_hand_value():
    # Roache two-grid, Fs = 3, r = 2, p = 1: U = 3 sqrt(0.4^2 + 0.3^2 + 0.4^2) / 1, u = U / 2
    u = grid_term((10.0, 0.3), (10.4, 0.4), ratio=2.0, order=1.0)
    assert u == pytest.approx(1.5 * math.sqrt(0.41))
    # angles: 359 deg vs 1 deg differ by 2 deg, not 358
    u = grid_term((359.0, 0.0), (1.0, 0.0), ratio=2.0, period=360.0)
    assert u == pytest.approx(3.0)
    with pytest.raises(BadInputError, match="ratio"):
        grid_term((1, 0), (1, 0), ratio=1.0)


def test_level_statistics_linear_and_circular():
    mean, sem, n = level_statistics(np.array([[1.0, 2.0, 3.0, np.nan]]))
    assert mean[0] == 2.0 and n[0] == 3 and sem[0] == pytest.approx(1 / math.sqrt(3))
    mean, sem, n = level_statistics(np.array([359.0, 1.0]), period=360.0)
    assert float(mean) == pytest.approx(0.0, abs=1e-9) or float(mean) == pytest.approx(360.0)
    assert float(sem) == pytest.approx(1.0)
    mean, sem, n = level_statistics(np.array([5.0]))
    assert math.isnan(float(sem))


def _hand_study(rng, *, grid_ok=True):
    """A small study in the file format of ``jointwear sim verify``, built by hand."""
    import xarray as xr

    h = np.array([1000.0, 2000.0, 4000.0, 8000.0])
    n_rep, z, th = 3, np.array([-1e-3, 0.0, 1e-3]), np.array([0.0, 90.0, 180.0, 270.0])
    depth = 1e-5 * (1 + 2e-5 * h)[:, None] + 1e-8 * rng.normal(size=(4, n_rep))
    maps = np.zeros((4, n_rep, z.size, th.size))
    maps[:, :, 1, 1] = depth
    gdepth = 1e-5 * (1 + 2e-5 * h[0]) * 1.001 + 1e-8 * rng.normal(size=n_rep)
    gmaps = np.zeros((n_rep, 5, 8))
    gmaps[:, 2, 2] = gdepth if grid_ok else np.nan
    theta = np.stack([np.full(n_rep, 359.5), np.full(n_rep, 0.5), np.full(n_rep, 1.0), [1, 2, 3]])
    qs = ["max_wear_depth", "max_wear_theta"]
    ds = xr.Dataset(
        {
            "replicate_value": (("quantity", "level", "replicate"), np.stack([depth, theta])),
            "grid_replicate_value": (
                ("quantity", "grid_replicate"),
                np.stack([gdepth if grid_ok else np.full(n_rep, np.nan), np.full(n_rep, 0.2)]),
            ),
            "quantity_period": ("quantity", [np.nan, 360.0]),
            "wear_depth_run": (("level", "replicate", "z", "theta"), maps),
            "wear_depth_grid_run": (("grid_replicate", "z_grid", "theta_grid"), gmaps),
        },
        coords={
            "level": np.arange(4),
            "h": ("level", h),
            "quantity": qs,
            "z": z,
            "theta": th,
            "z_grid": np.linspace(-1e-3, 1e-3, 5),
            "theta_grid": np.arange(8) * 45.0,
        },
        attrs={"jointwear_file": "verification_study", "grid_ratio": 2.0, "grid_level": 0},
    )
    return ds, depth, gdepth


def test_study_uncertainty_stored_values_and_wear_map_function_agree():
    from jointwear.refinement import study_uncertainty

    ds, depth, gdepth = _hand_study(np.random.default_rng(0))
    a = study_uncertainty(ds, "max_wear_depth")
    b = study_uncertainty(ds, "peak", lambda w: float(w.max()))
    assert a.assessed and b.assessed
    assert a.u_num == pytest.approx(b.u_num, rel=1e-12)
    m, s, _ = level_statistics(depth)
    gm, gs, _ = level_statistics(gdepth)
    assert a.value == pytest.approx(m[0])
    assert a.u_stat == pytest.approx(s[0])
    assert a.u_grid == pytest.approx(grid_term((m[0], s[0]), (gm, gs), ratio=2.0))
    assert a.u_num == pytest.approx(math.sqrt(a.u_stat**2 + a.u_refinement**2 + a.u_grid**2))
    # one run scatters by the replicates' standard deviation, not by the mean's standard error
    assert a.sd_run == pytest.approx(np.std(depth[0], ddof=1))
    assert a.u_num_run == pytest.approx(math.sqrt(a.sd_run**2 + a.u_refinement**2 + a.u_grid**2))
    assert a.u_num_run > a.u_num


def test_study_uncertainty_of_an_angle_wraps():
    from jointwear.refinement import study_uncertainty

    ds, _, _ = _hand_study(np.random.default_rng(0))
    fit = study_uncertainty(ds, "max_wear_theta")
    # means 359.5, 0.5, 1, 2 deg: a trend of a few degrees, not a jump of 359
    assert fit.assessed
    assert fit.u_num < 10.0


def test_study_uncertainty_refuses_and_reports_missing_grid():
    from jointwear.refinement import study_uncertainty

    ds, _, _ = _hand_study(np.random.default_rng(0), grid_ok=False)
    fit = study_uncertainty(ds, "max_wear_depth")
    assert not fit.assessed and "finer grid failed" in fit.reason
    with pytest.raises(BadInputError, match="no quantity 'volume'"):
        study_uncertainty(ds, "volume")
    ds.attrs["jointwear_file"] = "sweep"
    with pytest.raises(BadInputError, match="not a verification study"):
        study_uncertainty(ds, "max_wear_depth")


def test_quantised_location_without_change_is_one_step_not_inert():
    fit = eca_hoekstra(H, [90.0] * 4, [0.0] * 4, resolution=4.0)
    assert fit.assessed and fit.branch.startswith("no change")
    assert fit.u_refinement == pytest.approx(4.0 / math.sqrt(12))
    assert fit.u_num == pytest.approx(4.0 / math.sqrt(12))


def test_a_maximum_jumping_between_peaks_is_not_assessed():
    from jointwear.refinement import location_jump, study_uncertainty

    ds, _, _ = _hand_study(np.random.default_rng(0))
    ds["quantity_resolution"] = ("quantity", [np.nan, 1.8])
    assert study_uncertainty(ds, "max_wear_theta").assessed  # 359.5 .. 3 degree: one peak
    # one run of the coarsest level finds its maximum on the opposite peak (the reference rig)
    ds["replicate_value"].loc[{"quantity": "max_wear_theta", "level": 3, "replicate": 2}] = 124.2
    fit = study_uncertainty(ds, "max_wear_theta")
    assert not fit.assessed and "separate wear peaks" in fit.reason and "h = 8000" in fit.reason
    assert math.isnan(fit.u_num)
    # a drift of the location with refinement is not a jump; 359 and 1 degree are neighbours
    lv = np.array([[359.0, 1.0], [4.0, 5.0], [8.0, 9.0], [12.0, 13.0]])
    assert location_jump(lv, np.array([0.5, 359.5]), H, resolution=1.8, period=360.0) == ""
