"""Uncertainty arithmetic: coverage factors, combination of components, the GCI's capped order."""

from __future__ import annotations

import _jw_synth as syn
import numpy as np
import pytest
import xarray as xr

from jointwear.compare import Criteria, compare, gci
from jointwear.compare.budget import Component, combine, coverage_factor
from jointwear.errors import BadInputError, ParameterError

SIM_U_NOTE = (  # what jointwear sim wear writes (sim/_wear_output.py), without coverage_factor
    "expanded uncertainty (coverage factor k = 2) from the update control: explicit-Euler "
    "truncation dN (r_new - r_old) / 2 summed over the updates"
)


def _with_u(ds: xr.Dataset, u: float, attrs: dict) -> xr.Dataset:
    ds = ds.copy()
    ds["wear_depth_u"] = (ds["wear_depth"].dims, np.full(ds["wear_depth"].shape, u), attrs)
    return ds


def test_coverage_factor_declared_legacy_and_undeclared():
    assert coverage_factor({"coverage_factor": 2.0}, "x")[0] == 2.0
    k, note = coverage_factor({"long_name": "expanded uncertainty", "comment": SIM_U_NOTE}, "x")
    assert k == 2.0 and "declared in its long_name/comment" in note
    k, note = coverage_factor({"long_name": "standard uncertainty"}, "x")
    assert k == 1.0 and "read as standard" in note
    with pytest.raises(BadInputError, match="without its coverage factor"):
        coverage_factor({"long_name": "expanded uncertainty of the wear depth"}, "x")
    with pytest.raises(BadInputError, match="coverage_factor"):
        coverage_factor({"coverage_factor": 0.0}, "x")


@pytest.mark.parametrize(
    "attrs",
    [
        {"units": "m", "coverage_factor": 2.0},
        {
            "units": "m",
            "long_name": "expanded uncertainty of the wear depth",
            "comment": SIM_U_NOTE,
        },
    ],
)
def test_a_k2_simulation_u_enters_as_half(attrs):
    """sim wear's _u is expanded (k = 2): u_num must be U / 2, not U (a k = 2 read as k = 1)."""
    big_u = 2e-6
    sim = _with_u(syn.sim_wear(), big_u, attrs)
    meas = syn.meas_wear(u=1e-6, n_layers=16)
    c = compare(sim, meas, criteria=Criteria(wear_u_input_rel=0.1))
    assert c.value("max_wear_depth", "u_num") == pytest.approx(big_u / 2)
    basis = c.metrics.set_index(["quantity", "metric"]).loc[("max_wear_depth", "u_num"), "basis"]
    assert "divided by 2" in basis
    # the measurement side too: a k = 2 map gives u_D = U / 2
    meas_k2 = meas.copy()
    meas_k2["wear_depth_u"] = meas_k2["wear_depth_u"].assign_attrs(coverage_factor=2.0)
    c2 = compare(sim, meas_k2, criteria=Criteria(wear_u_input_rel=0.1))
    assert c2.value("max_wear_depth", "u_D") == pytest.approx(0.5e-6, rel=1e-6)


def test_combine_adds_in_quadrature_and_counts_a_source_once():
    a = Component(3.0, "study", frozenset({"update", "stat", "grid"}))
    b = Component(4.0, "sim _u", frozenset({"update", "stat"}))
    c = Component(4.0, "other", frozenset({"model form"}))
    u = combine("u_num", [a, b])
    assert u.value == 3.0 and "not added (stat, update already counted): sim _u" in u.basis
    assert combine("u_num", [a, c]).value == pytest.approx(5.0)
    assert "study = 3; other = 4" in combine("u_num", [a, c]).basis
    none = combine("u_num", [Component(None, "study: oscillates", frozenset({"x"}))])
    assert not none.known and "oscillates" in none.basis


def test_verification_and_partial_sim_u_both_listed_nothing_twice():
    sim = _with_u(syn.sim_wear(), 1e-6, {"units": "m", "coverage_factor": 2.0})
    meas = syn.meas_wear(u=1e-6, n_layers=16)
    s = compare(sim, meas, criteria=Criteria(wear_u_input_rel=0.1)).value(
        "max_wear_depth", "value_sim"
    )
    h = np.array([4.0, 2.0, 1.0])
    # refines the update interval, which the sim's _u also covers: counted once (the study)
    upd = xr.Dataset(
        {"max_wear_depth": ("update_dn", s * (1 + 0.01 * h), {"units": "m"})},
        coords={"update_dn": ("update_dn", h * 1000)},
    )
    c = compare(sim, meas, verification=upd, criteria=Criteria(wear_u_input_rel=0.1))
    g = gci(h * 1000, s * (1 + 0.01 * h), refined="update_dn")
    assert c.value("max_wear_depth", "u_num") == pytest.approx(g.u_num_rel * s)
    basis = c.metrics.set_index(["quantity", "metric"]).loc[("max_wear_depth", "u_num"), "basis"]
    assert "not added (wear-update interval already counted)" in basis
    # a study of another parameter (the grid): both added in quadrature
    grid = upd.rename(update_dn="n_points")
    c2 = compare(sim, meas, verification=grid, criteria=Criteria(wear_u_input_rel=0.1))
    assert c2.value("max_wear_depth", "u_num") == pytest.approx(np.hypot(g.u_num_rel * s, 0.5e-6))


def test_gci_order_capped_at_formal_order_and_safety_factor():
    h = np.array([4.0, 2.0, 1.0])
    # observed p = 2 on a first-order scheme: p capped at 1 and not credible -> Fs = 3
    g = gci(h, 10 + 0.3 * h**2, formal_order=1.0)
    e_a = 0.9 / 10.3
    assert g.order == pytest.approx(2.0) and g.order_used == 1.0 and g.safety_factor == 3.0
    assert g.gci_fine == pytest.approx(3.0 * e_a / (2.0 - 1.0))
    # p = 2 on a second-order scheme: credible -> Fs = 1.25, uncapped
    g2 = gci(h, 10 + 0.3 * h**2, formal_order=2.0)
    assert g2.safety_factor == 1.25 and g2.gci_fine == pytest.approx(1.25 * e_a / 3.0)
    # the case: changes of 1 % and 0.01 % (p ~ 6.6) no longer give u_num ~ 1e-6
    steep = gci(h, [1.01, 1.0001, 1.0])
    assert steep.order > 6 and steep.safety_factor == 3.0
    assert steep.u_num_rel == pytest.approx(3.0 * 1e-4 / 1.0 / 2.0, rel=1e-6)
    # p = 0.3 < 0.5: not credible -> Fs = 3 with the observed (lower) order
    f = 1 + 0.1 * h**0.3
    low = gci(h, f)
    assert low.safety_factor == 3.0 and low.order_used == pytest.approx(0.3, rel=1e-6)
    with pytest.raises(BadInputError, match="formal_order"):
        gci(h, f, formal_order=0.0)


def test_a_stated_zero_uncertainty_is_refused():
    for name in ("wear_u_num_rel", "wear_u_input_rel", "motion_u_num_rel", "motion_u_input_rel"):
        with pytest.raises(ParameterError, match="exactly zero"):
            Criteria(**{name: 0.0})


def test_no_threshold_pass_without_uncertainties():
    """A value within the screening threshold is not a pass when V&V 20 cannot be assessed."""
    sim = syn.sim_wear()
    c = compare(sim, syn.meas_wear(scale=1.05, n_layers=16))  # 5 % off: inside 0.30
    vv = c.decisions[c.decisions.basis == "V&V 20"]
    assert len(vv) == 3 and (vv.state == "not_assessed").all()
    assert vv.value.str.contains("screening only").all()
    assert not c.any_failed and c.summary().count("pass") == 1  # the shape/location ones only
    assert "5 not assessed" in c.summary()  # and the two field criteria (no u at all)


def test_u_d_from_the_maps_per_point_and_derived_u_with_k():
    sim = syn.sim_wear()
    meas = syn.meas_wear(n_layers=16, u=0.4e-6)  # covers the simulated width
    meas["worn_volume_u"] = ((), 2e-12, {"units": "m3", "coverage_factor": 2.0})
    crit = Criteria(wear_u_num_rel=0.01, wear_u_input_rel=0.05)
    meas["worn_volume"] = (
        (),
        compare(sim, meas).value("worn_volume", "value_meas"),
        {"units": "m3"},
    )
    c = compare(sim, meas, criteria=crit)
    # max depth: the per-point u at the maximum; volume: the map's own derived worn_volume_u / k
    assert c.value("max_wear_depth", "u_D") == pytest.approx(0.4e-6, rel=1e-9)
    assert c.value("worn_volume", "u_D") == pytest.approx(1e-12)
    basis = c.metrics.set_index(["quantity", "metric"]).loc[("worn_volume", "u_D"), "basis"]
    assert "worn_volume_u" in basis and "divided by 2" in basis
    # combined with u_num and u_input in quadrature
    s = c.value("worn_volume", "value_sim")
    expected = np.sqrt((0.01 * s) ** 2 + (0.05 * s) ** 2 + 1e-24)
    assert c.value("worn_volume", "u_val") == pytest.approx(expected)
    # a map cut after its volume was computed: its worn_volume_u is of another width, so the
    # per-point u is integrated instead (fully correlated: an upper bound), and the basis says so
    narrow = compare(sim, meas.isel(z=slice(2, 14)), criteria=crit)
    basis = narrow.metrics.set_index(["quantity", "metric"]).loc[("worn_volume", "u_D"), "basis"]
    assert "fully correlated" in basis


def test_instrument_calibration_terms_raise_u_d(tmp_path):
    """[measurement] gain_u_rel and probe_u_m enter u_D in quadrature with the map's own u."""
    from jointwear.compare import load_criteria

    sim, meas = syn.sim_wear(), syn.meas_wear(n_layers=16, u=0.4e-6)
    base = Criteria(wear_u_num_rel=0.01, wear_u_input_rel=0.05)
    plain = compare(sim, meas, criteria=base)
    toml = tmp_path / "criteria.toml"
    toml.write_text(
        "[criteria]\nwear_u_num_rel = 0.01\nwear_u_input_rel = 0.05\n"
        "[measurement]\ngain_u_rel = 0.02\nprobe_u_m = 0.5e-6\n"
    )
    crit = load_criteria(toml)
    assert (crit.gain_u_rel, crit.probe_u_m) == (0.02, 0.5e-6)
    cal = compare(sim, meas, criteria=crit)
    d = cal.value("max_wear_depth", "value_meas")
    own = plain.value("max_wear_depth", "u_D")
    assert cal.value("max_wear_depth", "u_D") == pytest.approx(
        np.sqrt(own**2 + (0.02 * d) ** 2 + 0.5e-6**2)
    )
    # the volume: the offset over the band's area, R 2 pi (z_max - z_min) for a full band
    lo, hi = (float(v) for v in np.ravel(cal.wear.attrs["z_overlap_m"]))
    area = syn.RADIUS * 2 * np.pi * (hi - lo)
    v, own_v = cal.value("worn_volume", "value_meas"), plain.value("worn_volume", "u_D")
    assert cal.value("worn_volume", "u_D") == pytest.approx(
        np.sqrt(own_v**2 + (0.02 * v) ** 2 + (0.5e-6 * area) ** 2)
    )
    # the cylindricity removes a uniform offset: the gain only
    c, own_c = cal.value("cylindricity", "value_meas"), plain.value("cylindricity", "u_D")
    assert cal.value("cylindricity", "u_D") == pytest.approx(np.hypot(own_c, 0.02 * c))
    basis = cal.metrics.set_index(["quantity", "metric"]).loc[("max_wear_depth", "u_D"), "basis"]
    assert "gain_u_rel" in basis and "probe_u_m" in basis
    # a calibration term alone does not make an unstated u_D known
    bare = compare(sim, syn.meas_wear(n_layers=16), criteria=crit)
    assert bare.state("maximum wear depth") == "not_assessed"
    # a misspelt key and a key stated twice are refused, naming it
    toml.write_text("[measurement]\ngain_u = 0.02\n")
    with pytest.raises(ParameterError, match=r"measurement\.gain_u"):
        load_criteria(toml)
    toml.write_text("[criteria]\ngain_u_rel = 0.01\n[measurement]\ngain_u_rel = 0.02\n")
    with pytest.raises(ParameterError, match="both"):
        load_criteria(toml)
