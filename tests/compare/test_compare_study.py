"""compare --verification with a ``jointwear sim verify`` study (contract format, built by hand)."""

from __future__ import annotations

import _jw_synth as syn
import numpy as np
import pytest
import xarray as xr

from jointwear.compare import Criteria, compare
from jointwear.refinement import eca_hoekstra, grid_term, level_statistics, study_uncertainty

H = np.array([500.0, 1000.0, 2000.0, 4000.0])
QUANTITIES = ["max_wear_depth", "worn_volume", "cylindricity"]


def _factors(seed=5, n_rep=3, n_grid=3):
    """Scale factor of every run: first order in h plus replicate scatter (known)."""
    rng = np.random.default_rng(seed)
    lv = 1.0 + 2e-5 * H[:, None] + 0.004 * rng.standard_normal((H.size, n_rep))
    gv = 1.0 + 2e-5 * H[0] - 0.01 + 0.004 * rng.standard_normal(n_grid)
    return lv, gv


def study(cycles=4e5, seed=5) -> xr.Dataset:
    """A study whose every run is the synthetic map times a known factor."""
    base = syn.sim_wear().isel(cycles=-1)
    z, th = base["z"], base["theta"]
    field = base["wear_depth"].values
    lv, gv = _factors(seed)
    whole = np.array([field.max(), np.nan, np.nan])
    ds = xr.Dataset(
        coords={
            "h": ("level", H, {"units": "1", "long_name": "wear-update interval ΔN"}),
            "quantity": ("quantity", QUANTITIES),
            "z": z,
            "theta": th,
            "z_grid": ("z_grid", z.values, z.attrs),
            "theta_grid": ("theta_grid", th.values, th.attrs),
        }
    )
    ds["wear_depth_run"] = (
        ("level", "replicate", "z", "theta"),
        lv[:, :, None, None] * field[None, None],
        {"units": "m"},
    )
    ds["wear_depth_grid_run"] = (
        ("grid_replicate", "z_grid", "theta_grid"),
        gv[:, None, None] * field[None],
        {"units": "m"},
    )
    ds["replicate_value"] = (("quantity", "level", "replicate"), whole[:, None, None] * lv[None])
    ds["grid_replicate_value"] = (("quantity", "grid_replicate"), whole[:, None] * gv[None])
    # the per-quantity summary the study file carries (what the report plots)
    lm = whole[:, None] * lv.mean(axis=1)[None]
    ds["level_mean"] = (("quantity", "level"), lm)
    ds["level_sem"] = (("quantity", "level"), np.abs(lm) * 0.002)
    ds["quantity_units"] = ("quantity", ["m", "m3", "m"])
    ds["value"] = ("quantity", lm[:, 0])
    ds["u_num"] = ("quantity", np.abs(lm[:, 0]) * 0.01)
    ds["assessed"] = ("quantity", np.array([1, 0, 0], dtype=np.int8))
    ds.attrs.update(
        {
            "jointwear_file": "verification_study",
            "data_origin": "simulated",
            "cycles": cycles,
            "formal_order": 1.0,
            "grid_ratio": 2.0,
            "grid_order": 1.0,
            "grid_level": 0,
            "bearing_radius_m": syn.RADIUS,
        }
    )
    return ds


def _expected_rel():
    """Relative u_num of any quantity proportional to the map (closed form of the factors)."""
    lv, gv = _factors()
    mean, sem, count = level_statistics(lv)
    fit = eca_hoekstra(H, mean, sem, formal_order=1.0, counts=count)
    gm, gs, _ = level_statistics(gv)
    u_grid = grid_term((mean[0], sem[0]), (float(gm), float(gs)), ratio=2.0, order=1.0)
    fit = fit.with_grid(u_grid)
    # the compared simulation is one run: u_num_run (sd of one run, not of the mean)
    assert fit.u_num_run > fit.u_num
    return fit.u_num_run / fit.value, float(mean[0])


def test_study_gives_u_num_of_each_band_quantity():
    sim = syn.sim_wear()
    meas = syn.meas_wear(u=0.2e-6)  # +-6 mm band of a 15 mm bearing
    c = compare(sim, meas, verification=study(), criteria=Criteria(wear_u_input_rel=0.05))
    rel, m0 = _expected_rel()
    assert np.isfinite(rel) and rel > 0
    for q in QUANTITIES:
        s = c.value(q, "value_sim")
        # every band quantity is proportional to the map: the study's u_num of it is the
        # factors' relative u_num times the band quantity of the finest level (m0 * S)
        assert c.value(q, "u_num") == pytest.approx(rel * m0 * s, rel=1e-6), q
        basis = c.metrics.set_index(["quantity", "metric"]).loc[(q, "u_num"), "basis"]
        assert "sim verify, on the measured band" in basis
    # the stored whole-map value gives the same relative u_num (the contract's fn=None path)
    whole = study_uncertainty(study(), "max_wear_depth")
    assert whole.u_num_run / whole.value == pytest.approx(rel, rel=1e-6)
    assert c.state("maximum wear depth") in ("pass", "fail")


def test_study_and_sim_u_count_the_update_interval_once():
    sim = syn.sim_wear()
    sim["wear_depth_u"] = (
        sim["wear_depth"].dims,
        np.full(sim["wear_depth"].shape, 3e-7),
        {"units": "m", "coverage_factor": 2.0},
    )
    meas = syn.meas_wear(u=0.2e-6)
    c = compare(sim, meas, verification=study(), criteria=Criteria(wear_u_input_rel=0.05))
    s = c.value("max_wear_depth", "value_sim")
    rel, m0 = _expected_rel()
    assert c.value("max_wear_depth", "u_num") == pytest.approx(rel * m0 * s, rel=1e-6)
    basis = c.metrics.set_index(["quantity", "metric"]).loc[("max_wear_depth", "u_num"), "basis"]
    assert "not added (cycle-to-cycle variability, wear-update interval already counted)" in basis


def test_study_of_other_cycles_contributes_its_relative_u_num():
    sim = syn.sim_wear()
    meas = syn.meas_wear(u=0.2e-6)
    c = compare(sim, meas, verification=study(cycles=5e4), criteria=Criteria(wear_u_input_rel=0.05))
    s = c.value("worn_volume", "value_sim")
    # another wear time: the relative u_num applied to the compared value
    assert c.value("worn_volume", "u_num") == pytest.approx(_expected_rel()[0] * s, rel=1e-6)
    basis = c.metrics.set_index(["quantity", "metric"]).loc[("worn_volume", "u_num"), "basis"]
    assert "run for 50000 cycles: relative u_num" in basis


def test_study_without_grid_runs_is_not_assessed():
    st = study().drop_vars(["wear_depth_grid_run", "grid_replicate_value"])
    c = compare(syn.sim_wear(), syn.meas_wear(u=0.2e-6), verification=st)
    assert np.isnan(c.value("max_wear_depth", "u_num"))
    reason = c.decisions[c.decisions.key == "max_wear_depth"].reason.iloc[0]
    assert "grid term is not assessed" in reason
