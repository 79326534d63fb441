"""Verdict states, GCI (verification), ensemble u_input and data origin against constructed truths."""

from __future__ import annotations

import _jw_synth as syn
import numpy as np
import pytest
import xarray as xr

from jointwear.compare import (
    Criteria,
    compare,
    gci,
    load_comparison,
    numerical_uncertainty,
    save_comparison,
)
from jointwear.errors import BadInputError

# ----------------------------------------------------------------------------- GCI


def test_gci_recovers_order_and_extrapolated_value():
    # f(h) = 10 + 0.3 h^2 on h = 1, 2, 4: p = 2, f_ext = 10, e_a = 0.9/10.3
    h = np.array([4.0, 2.0, 1.0])
    g = gci(h, 10 + 0.3 * h**2, quantity="f", formal_order=2.0)
    assert g.assessed and g.order == pytest.approx(2.0, rel=1e-9)
    assert g.extrapolated == pytest.approx(10.0, rel=1e-12)
    e_a = 0.9 / 10.3
    assert g.gci_fine == pytest.approx(1.25 * e_a / 3.0, rel=1e-12)
    assert g.u_num_rel == pytest.approx(g.gci_fine / 2)


def test_one_rule_for_a_numerical_uncertainty_bound():
    """GCI and Eça & Hoekstra's U_phi are both ~95 % bounds: one k (= 2) converts both, so three
    and four levels of the same exactly first-order data give the same u_num (they differed by
    2 / 1.15 = 1.74x when the GCI was divided by 1.15 and U_phi by 2)."""
    from jointwear.compare.verification import GCI_TO_STANDARD, refinement_study
    from jointwear.refinement import COVERAGE_K

    assert GCI_TO_STANDARD == COVERAGE_K == 2.0
    h = np.array([1.0, 2.0, 4.0, 8.0])
    f = 1.0 + 0.1 * h
    three = refinement_study(h[:3], f[:3], quantity="q")
    four = refinement_study(h, f, quantity="q")
    assert type(three).__name__ == "GCI" and type(four).__name__ == "LeastSquaresStudy"
    # by hand: e_a = 0.1 / 1.1, p = 1, Fs = 1.25: GCI = 1.25 e_a, u_num = GCI / 2
    assert three.u_num_rel == pytest.approx(1.25 * 0.1 / 1.1 / 2, rel=1e-9)
    assert four.u_num_rel == pytest.approx(three.u_num_rel, rel=1e-6)
    assert "GCI/2" in three.describe()


def test_gci_non_constant_ratio():
    # unequal refinement ratios (Celik's iteration): f = 2 - 0.5 h^1.5, h = 0.1, 0.25, 0.4
    h = np.array([0.1, 0.25, 0.4])
    g = gci(h, 2 - 0.5 * h**1.5, formal_order=2.0)
    assert g.assessed and g.order == pytest.approx(1.5, rel=1e-6)
    assert g.extrapolated == pytest.approx(2.0, rel=1e-9)


def test_gci_refuses_oscillating_and_diverging_sequences():
    # the demo's earlier study: 10.65 -> 10.46 -> 11.15 um as tol is refined (oscillating)
    osc = gci([0.4, 0.2, 0.1], [10.65, 10.46, 11.15], quantity="max_wear_depth")
    assert not osc.assessed and "oscillate" in osc.reason and np.isnan(osc.u_num_rel)
    div = gci([0.4, 0.2, 0.1], [1.0, 1.1, 1.3])  # changes grow with refinement
    assert not div.assessed and "do not converge" in div.reason
    two = gci([0.2, 0.1], [1.0, 1.01])
    assert not two.assessed and "three are needed" in two.reason
    with pytest.raises(BadInputError, match="share the refinement value"):
        gci([0.1, 0.1, 0.2], [1, 2, 3])


def test_verification_study_sets_u_num_only_when_monotone():
    sim = syn.sim_wear()
    meas = syn.meas_wear(u=1e-6, n_layers=16)
    tol = np.array([0.4, 0.2, 0.1])
    s = compare(sim, meas).value("max_wear_depth", "value_sim")

    def study(values):
        return xr.Dataset(
            {"max_wear_depth": ("tol", values, {"units": "m"})},
            coords={"tol": ("tol", tol, {"units": "1"})},
        )

    conv = study(s * (1 + 0.08 * tol))  # first order, converging to S
    c = compare(sim, meas, verification=study(s * (1 + 0.08 * tol)))
    g = numerical_uncertainty(conv)["max_wear_depth"]
    assert c.value("max_wear_depth", "u_num") == pytest.approx(g.u_num_rel * s)
    basis = c.metrics.set_index(["quantity", "metric"]).loc[("max_wear_depth", "u_num"), "basis"]
    assert "GCI" in basis
    osc = compare(sim, meas, verification=study(s * np.array([1.02, 0.99, 1.05])))
    assert np.isnan(osc.value("max_wear_depth", "u_num"))
    row = osc.decisions[(osc.decisions.key == "max_wear_depth")]
    assert row.state.iloc[0] == "not_assessed" and "oscillate" in row.reason.iloc[0]


# ----------------------------------------------------------------------------- ensemble


def _ensemble(values: dict[str, np.ndarray], **coords) -> xr.Dataset:
    n = len(next(iter(values.values())))
    ds = xr.Dataset(coords={"run": np.arange(n), **{k: ("run", v) for k, v in coords.items()}})
    ds.attrs["cycles"] = 4e5  # the synthetic maps' cycles (syn.meas_wear)
    for k, v in values.items():
        ds[k] = ("run", np.asarray(v, dtype=float), {"units": "m"})
    return ds


def test_ensemble_spread_is_u_input():
    sim = syn.sim_wear()
    meas = syn.meas_wear(u=1e-6, n_layers=16)
    rng = np.random.default_rng(3)
    depth = 32e-6 + 2e-6 * rng.standard_normal(12)
    ens = _ensemble({"max_wear_depth": depth}, kw=rng.uniform(1, 2, 12))
    c = compare(sim, meas, ensemble=ens, criteria=Criteria(wear_u_num_rel=1e-9))
    assert c.value("max_wear_depth", "u_input") == pytest.approx(np.std(depth, ddof=1))
    basis = c.metrics.set_index(["quantity", "metric"]).loc[("max_wear_depth", "u_input"), "basis"]
    assert "standard deviation over 12 runs" in basis
    # an ensemble that does not say after how many cycles: its spread could be of any wear time
    undated = ens.copy()
    del undated.attrs["cycles"]
    c_undated = compare(sim, meas, ensemble=undated, criteria=Criteria(wear_u_num_rel=1e-9))
    assert np.isnan(c_undated.value("max_wear_depth", "u_input"))
    # a failed run (NaN) biases the spread of the others: not assessed, never left out silently
    broken = ens.copy(deep=True)
    broken["max_wear_depth"][4] = np.nan
    c_broken = compare(sim, meas, ensemble=broken, criteria=Criteria(wear_u_num_rel=1e-9))
    assert np.isnan(c_broken.value("max_wear_depth", "u_input"))
    assert c_broken.state("maximum wear depth", "V&V 20") == "not_assessed"
    # a grid sweep's spread is not an input distribution
    grid = ens.assign_attrs(probabilistic_sample="false", sweep_method="grid")
    c_grid = compare(sim, meas, ensemble=grid, criteria=Criteria(wear_u_num_rel=1e-9))
    assert np.isnan(c_grid.value("max_wear_depth", "u_input"))
    reason = c_grid.decisions[c_grid.decisions.key == "max_wear_depth"].reason.iloc[0]
    assert "not a sample of the input distribution" in reason
    assert c.state("maximum wear depth", "V&V 20") in ("pass", "fail")
    # a quantity the ensemble does not have stays not assessed
    assert np.isnan(c.value("worn_volume", "u_input"))
    # two ensembles over independent inputs: variances add; over the same input: refused
    other = _ensemble({"max_wear_depth": 32e-6 + np.array([-1e-6, 1e-6])}, mu=[0.1, 0.2])
    both = compare(sim, meas, ensemble=[ens, other], criteria=Criteria(wear_u_num_rel=1e-9))
    expected = np.hypot(np.std(depth, ddof=1), np.std([-1e-6, 1e-6], ddof=1))
    assert both.value("max_wear_depth", "u_input") == pytest.approx(expected)
    with pytest.raises(BadInputError, match="both vary 'kw'"):
        compare(sim, meas, ensemble=[ens, ens])
    with pytest.raises(BadInputError, match="'run' dimension"):
        compare(sim, meas, ensemble=xr.Dataset({"max_wear_depth": 1.0}))


def test_ensemble_of_maps_gives_the_compared_quantity_per_run():
    """With maps, u_input is the spread of the quantity on the compared window itself."""
    meas = syn.meas_wear(u=1e-6, n_layers=16)
    sim = syn.sim_wear()
    scales = np.array([0.8, 0.9, 1.0, 1.1, 1.25])
    base = sim["wear_depth"].isel(cycles=-1)
    ens = xr.Dataset(
        {"wear_depth": (("run", "z", "theta"), np.stack([f * base.values for f in scales]))},
        coords={"run": np.arange(5), "kw": ("run", scales), "z": sim["z"], "theta": sim["theta"]},
        attrs={"cycles": 4e5},
    )
    ens["wear_depth"].attrs.update(sim["wear_depth"].attrs)
    c = compare(sim, meas, ensemble=ens)
    s = c.value("max_wear_depth", "value_sim")
    assert c.value("max_wear_depth", "u_input") == pytest.approx(
        s * np.std(scales, ddof=1), rel=1e-6
    )
    v = c.value("worn_volume", "value_sim")
    assert c.value("worn_volume", "u_input") == pytest.approx(v * np.std(scales, ddof=1), rel=1e-6)
    assert c.wear["wear_depth_sim_ensemble"].sizes["run"] == 5
    # run for fewer cycles: the relative spread is applied to the compared value
    short = ens.assign_attrs(cycles=1e5)
    short["wear_depth"] = short["wear_depth"] * 0.25
    c2 = compare(sim, meas, ensemble=short)
    assert c2.value("max_wear_depth", "u_input") == pytest.approx(
        s * np.std(scales, ddof=1) / np.mean(scales), rel=1e-6
    )


# ----------------------------------------------------------------------------- states, origin


def test_states_are_cf_flags_in_the_file(tmp_path):
    sim = syn.sim_wear()
    sim.attrs["data_origin"] = "simulated"
    meas = syn.meas_wear(u=1e-6)  # +-6 mm: narrower than the simulated worn zone
    meas.attrs["data_origin"] = "synthetic"
    c = compare(sim, meas, criteria=Criteria(strict_coverage=True))
    assert c.data_origin == {"simulation": "simulated", "measurement": "synthetic"}
    path = save_comparison(c, tmp_path / "m.nc")
    ds = xr.open_dataset(path)
    flags = [ds[v] for v in ds.data_vars if str(v).startswith("decision_")]
    assert all(f.attrs["flag_meanings"] == "fail pass not_assessed not_comparable" for f in flags)
    assert list(flags[0].attrs["flag_values"]) == [0, 1, 2, 3]
    assert (
        ds.attrs["data_origin_measurement"] == "synthetic"
        and ds.attrs["data_origin"] == "synthetic"
    )
    assert ds.attrs["n_not_comparable"] >= 1 and ds.attrs["n_not_assessed"] >= 1
    ds.close()
    back = load_comparison(path)
    assert list(back.decisions.state) == list(c.decisions.state)
    assert back.data_origin == c.data_origin
    # the validation-domain statement (extrapolation) is in the metrics file
    assert any(n.startswith("validation domain") for n in back.notes)
    assert back.value("validation_domain", "volume_fraction_outside") > 0.1
    # a measurement without data_origin is "not stated", never assumed measured
    assert compare(sim, syn.meas_wear()).data_origin["measurement"] == "not stated"


def _edge_case():
    sim = syn.sim_wear(width=15e-3)
    # move the simulated wear to the bearing edge: its maximum lies at z = -7.5 mm
    z = sim["z"].values
    edge = np.exp(-0.5 * ((z + 7.5e-3) / 2e-3) ** 2)[None, :, None]
    ring = 1 + 0.3 * np.cos(np.radians(sim["theta"].values))[None, None, :]
    sim["wear_depth"] = sim["wear_depth"] * 0 + edge * 20e-6 * ring
    meas = syn.meas_wear(n_layers=13, u=0.2e-6)  # +-6 mm
    zm = meas["z"].values
    # the measured bearing wears the same way: scanned on +-6 mm only
    th = np.radians(meas["theta"].values)
    from jointwear.conventions import CANONICAL, AngleConvention

    canon = CANONICAL.from_physical(
        AngleConvention("+y", "counterclockwise").to_physical(np.degrees(th))
    )
    meas["wear_depth"] = (
        ("z", "theta"),
        np.exp(-0.5 * ((zm + 7.5e-3) / 2e-3) ** 2)[:, None]
        * 20e-6
        * (1 + 0.3 * np.cos(np.radians(canon)))[None, :],
        meas["wear_depth"].attrs,
    )
    return sim, meas


def test_uncovered_maximum_strict_is_not_comparable_not_pass():
    """strict_coverage (the old rule): both maxima clipped to the scan edge are not comparable."""
    sim, meas = _edge_case()
    c = compare(sim, meas, criteria=Criteria(max_z_error_m=10.0, strict_coverage=True))
    assert c.wear.attrs["sim_max_inside"] == 0
    assert c.state("axial position of maximum wear") == "not_comparable"
    assert c.state("maximum wear depth") == "not_comparable"
    assert "lies outside the compared range" in c.decisions.reason.iloc[2]
    frac = c.value("wear_depth", "volume_fraction_compared")
    # analytic share of a Gaussian (sigma 2 mm, centre -7.5 mm) inside [-6, 6] of [-7.5, 7.5]
    from scipy.stats import norm

    inside = norm.cdf(13.5 / 2) - norm.cdf(1.5 / 2)
    total = norm.cdf(15 / 2) - norm.cdf(0)
    assert frac == pytest.approx(inside / total, abs=0.02)


def test_edge_maximum_is_decided_within_the_band_and_stated_as_extrapolation():
    sim, meas = _edge_case()
    crit = Criteria(wear_u_num_rel=0.02, wear_u_input_rel=0.05)
    c = compare(sim, meas, criteria=crit)
    # decided on the band, named so
    label = c.decisions.quantity[c.decisions.key == "max_wear_depth"].iloc[0]
    assert label == "maximum wear depth within z = −6…+6 mm"
    assert c.state("maximum wear depth") == "pass"
    assert c.state("worn volume") == "pass" and c.state("wear map shape") == "pass"
    assert c.state("angle of maximum wear") == "pass"
    # only the axial position cannot be answered: both maxima sit on the band's edge
    assert c.state("axial position of maximum wear") == "not_comparable"
    reason = c.decisions.reason[c.decisions.quantity.str.startswith("axial")].iloc[0]
    assert "lie on its edge layer z = -5.92 mm" in reason  # the first common layer
    # the validation domain: the global maximum outside, stated as extrapolation
    dom = [n for n in c.notes if n.startswith("validation domain")]
    assert dom and "extrapolation" in dom[0] and "z = -7.50 mm" in dom[0]
    assert c.value("validation_domain", "sim_global_max_z") == pytest.approx(-7.5e-3)
    outside = c.value("validation_domain", "volume_fraction_outside")
    assert outside == pytest.approx(1 - c.value("wear_depth", "volume_fraction_compared"))
    # a wrong model on the same band fails: 1.5x deeper
    deep = sim.assign(wear_depth=sim["wear_depth"] * 1.5)
    bad = compare(deep, meas, criteria=crit)
    assert bad.state("maximum wear depth") == "fail" and bad.state("worn volume") == "fail"
    # ... and so does the map turned by 180 degree (angle and shape)
    turned = sim.assign_coords(theta=(sim["theta"] + 180.0) % 360.0).sortby("theta")
    turned["theta"].attrs = sim["theta"].attrs
    t = compare(turned, meas, criteria=crit)
    assert t.state("angle of maximum wear") == "fail" and t.any_failed


def test_sweep_style_ensemble_sobol_indices_reach_the_comparison():
    """The layout of ``jointwear sim sweep``: run_seed coordinate, sobol_S1/ST(output, parameter)."""
    from jointwear.reports import render_html

    sim = syn.sim_wear()
    meas = syn.meas_wear(u=1e-6, n_layers=16)
    ens = _ensemble({"max_wear_depth": [30e-6, 33e-6, 31e-6, 34e-6]}, run_seed=np.arange(4))
    ens = ens.assign_coords(**{"wear.kw": ("run", [1.0, 1.1, 0.9, 1.2])})
    ens.attrs["sweep_parameters"] = ["wear.kw", "friction.dynamic_coefficient"]
    ens["sobol_S1"] = (("output", "parameter"), [[0.8, 0.1]])
    ens["sobol_ST"] = (("output", "parameter"), [[0.85, 0.12]])
    ens = ens.assign_coords(
        output=["max_wear_depth"], parameter=["wear.kw", "friction.dynamic_coefficient"]
    )
    c = compare(sim, meas, ensemble=ens)
    rows = c.sensitivity.set_index("parameter")
    assert rows.loc["wear.kw", "S1"] == pytest.approx(0.8)
    assert rows.loc["friction.dynamic_coefficient", "ST"] == pytest.approx(0.12)
    html = render_html(c, command="t")
    assert "first-order Sobol index S1" in html and "friction.dynamic_coefficient" in html
    # run_seed is not a varied input: a second ensemble with its own seeds is not refused
    other = _ensemble({"worn_volume": [1e-9, 1.1e-9]}, run_seed=np.arange(2), mu=[0.1, 0.2])
    compare(sim, meas, ensemble=[ens, other])


def test_regression_importance_without_sobol_finds_the_dominant_input():
    """An LHS-style ensemble: y = 3 a + 0.3 b -> SRC² of a near 0.99, of b near 0.01."""
    rng = np.random.default_rng(7)
    a, b = rng.standard_normal(40), rng.standard_normal(40)
    y = 32e-6 * (1 + 0.05 * (3 * a + 0.3 * b) / 3)
    ens = _ensemble({"max_wear_depth": y}, a=a, b=b)
    c = compare(syn.sim_wear(), syn.meas_wear(u=1e-6, n_layers=16), ensemble=ens)
    rows = c.sensitivity.set_index("parameter")
    # exact for a linear model: SRC_a = 3 sd(a) / sd(y) (the sample's own correlations included)
    lin = 3 * a + 0.3 * b
    assert rows.loc["a", "S1"] == pytest.approx((3 * np.std(a) / np.std(lin)) ** 2, rel=1e-9)
    assert rows.loc["b", "S1"] == pytest.approx((0.3 * np.std(b) / np.std(lin)) ** 2, rel=1e-6)
    assert rows.loc["b", "S1"] < 0.03
    assert rows.loc["a", "method"].startswith("SRC²") and "R² = 1.00" in rows.loc["a", "method"]


def test_real_sweep_output_as_ensemble(tmp_path):
    """jointwear.sim.run_sweep's own file: u_input = spread of the quantity each member gives
    when compared on its own (computed here through the public API, member by member)."""
    from jointwear import io
    from jointwear.params import replace_nested
    from jointwear.sim import DEFAULT_KW, PARAMETER_SETS, WearSettings, run_sweep, simulate_wear

    p = replace_nested(PARAMETER_SETS["zhang2023"], **{"joint.n_layers": 6, "joint.n_points": 36})
    wear = WearSettings(scheme="fixed", dn=2000)
    spec = {
        "sweep": {
            "run": "wear",
            "cycles": 4000.0,
            "method": "lhs",
            "samples": 4,
            "seed": 2,
            "outputs": ["max_wear_depth", "worn_volume"],
            "keep": ["wear_depth"],
        },
        "parameters": {
            "wear.kw": {"distribution": "uniform", "bounds": [0.8 * DEFAULT_KW, 1.2 * DEFAULT_KW]}
        },
    }
    io.save(run_sweep(spec, params=p, wear=wear, workers=0), tmp_path / "sweep.nc")
    ens = io.load(tmp_path / "sweep.nc")
    sim = simulate_wear(p, cycles=4000.0, snapshots=[4000.0], settings=wear)
    meas = syn.meas_wear(cycles=4000.0, u=1e-9)
    c = compare(sim, meas, ensemble=ens)
    per_member = []
    for r in range(ens.sizes["run"]):
        member = ens[["wear_depth"]].isel(run=r, drop=True)
        member.attrs["bearing_radius_m"] = sim.attrs.get("bearing_radius_m", 8e-3)
        member_c = compare(member, meas)
        per_member.append(
            [member_c.value(q, "value_sim") for q in ("max_wear_depth", "worn_volume")]
        )
    sd = np.std(np.asarray(per_member), axis=0, ddof=1)
    assert c.value("max_wear_depth", "u_input") == pytest.approx(sd[0], rel=1e-9)
    assert c.value("worn_volume", "u_input") == pytest.approx(sd[1], rel=1e-9)
    assert c.value("max_wear_depth", "u_input") > 0


def test_partial_arc_is_not_interpolated_across_its_gap():
    """A scan of half the circumference: the missing half is not compared (no interpolation
    across the gap), and a simulated maximum inside the gap makes the maximum not comparable."""
    from jointwear.conventions import CANONICAL, AngleConvention

    own = AngleConvention("+y", "counterclockwise")
    full = syn.meas_wear(n_layers=16, u=1e-6)
    peak_own = float(own.from_physical(CANONICAL.to_physical(90.0)))  # the largest wear bump
    d = (full["theta"].values - (peak_own + 180.0) + 180.0) % 360.0 - 180.0
    arc = full.isel(theta=np.flatnonzero(np.abs(d) < 90.0))  # the half opposite the bump
    c = compare(syn.sim_wear(), arc)
    assert c.wear.attrs["theta_fraction_measured"] == pytest.approx(0.5, abs=0.02)
    meas = c.wear["wear_depth_meas"].values
    assert np.isnan(meas).any() and np.isfinite(meas).any()
    # the simulated map is blanked where the measurement is missing: nothing is compared there
    np.testing.assert_array_equal(np.isnan(c.wear["wear_depth_sim"].values), np.isnan(meas))
    # decided on the measured arc only, and named so; the rest is extrapolation
    label = c.decisions.quantity[c.decisions.key == "max_wear_depth"].iloc[0]
    assert label.endswith("of the circumference") and "within z" in label
    assert any("global maximum" in n and "outside the band" in n for n in c.notes)
    assert c.value("wear_depth", "volume_fraction_compared") < 0.5
    strict = compare(syn.sim_wear(), arc, criteria=Criteria(strict_coverage=True))
    assert strict.state("maximum wear depth") == "not_comparable"
    reason = strict.decisions[strict.decisions.key == "max_wear_depth"].reason.iloc[0]
    assert "of the circumference" in reason
    assert strict.state("wear map shape") == "not_comparable"


def test_an_interrupted_simulation_is_flagged_partial_and_never_complete(tmp_path):
    sim = syn.sim_wear()
    meas = syn.meas_wear(u=1e-6, n_layers=16)
    assert not compare(sim, meas).partial
    sim.attrs.update(status="partial", cycles_done=3e4, cycles_target=4e5)
    c = compare(sim, meas)
    assert any("stopped after 30000 of 400000 cycles" in p for p in c.partial)
    assert not c.complete  # --strict exits 1
    save_comparison(c, tmp_path / "m.nc")
    assert any("stopped after 30000" in p for p in load_comparison(tmp_path / "m.nc").partial)


def test_each_wear_criterion_fails_on_a_wrong_model():
    """Within the band, every wear criterion can fail: a model wrong in what it judges."""
    meas = syn.meas_wear(u=0.2e-6)  # +-6 mm
    crit = Criteria(wear_u_num_rel=0.02, wear_u_input_rel=0.05)
    right = compare(syn.sim_wear(), meas, criteria=crit)
    assert not right.any_failed
    # mirrored axially: the maximum at the other end of the band (axial position), wrong shape
    sim = syn.sim_wear()
    mirrored = sim.assign_coords(z=-sim["z"]).sortby("z")
    mirrored["z"].attrs = sim["z"].attrs
    c = compare(mirrored, meas, criteria=crit)
    assert c.state("axial position of maximum wear") == "fail"
    assert c.state("wear map shape") == "fail"
    # twice as deep: maximum depth, volume and cylindricity of the wear
    deep = sim.assign(wear_depth=sim["wear_depth"] * 2.0)
    c = compare(deep, meas, criteria=crit)
    for name in ("maximum wear depth", "worn volume", "cylindricity of the wear (LSCY)"):
        assert c.state(name) == "fail", name
    # turned: the angle of the maximum
    c = compare(syn.sim_wear(rotate_deg=90.0), meas, criteria=crit)
    assert c.state("angle of maximum wear") == "fail"
