"""The whole-band field criteria: Mahalanobis distance of the wear field and of its axial
distribution, against synthetic truth (a right model passes, a wrong model form fails)."""

from __future__ import annotations

import _jw_synth as syn
import numpy as np
import pytest
import xarray as xr

from jointwear import conventions
from jointwear.compare import Criteria, compare
from jointwear.compare._field import mahalanobis_test

Z = np.linspace(-6e-3, 6e-3, 13)  # the measured band: 13 layers, 5-degree grid
TH = np.arange(72) * 5.0


def field(a=30e-6, th0=120.0, w=35.0, slope=0.2, edge=0.0):
    """A worn patch at th0 whose axial distribution is a slope (edge = 0, spread along the band)
    or piled at both edges (edge > 0: the wrong form, its peak about as deep)."""
    d = (TH[None, :] - th0 + 180) % 360 - 180
    zz = Z[:, None] / Z[-1]
    axial = (1 + slope * zz) * (1 - edge) + edge * (0.25 + 0.75 * zz**4)
    return a * np.exp(-0.5 * (d / w) ** 2) * axial + 0.5e-6


def inputs(rng, n):
    """Uncertain inputs: depth scale 10 %, angle 4 degree, width 8 %, axial slope 0.1 (1 sd)."""
    return [
        {
            "a": 30e-6 * (1 + 0.10 * rng.standard_normal()),
            "th0": 120 + 4 * rng.standard_normal(),
            "w": 35 * (1 + 0.08 * rng.standard_normal()),
            "slope": 0.2 + 0.1 * rng.standard_normal(),
        }
        for _ in range(n)
    ]


def sim_map(f):
    ds = syn.wear_history(np.stack([0 * f, f]), [0.0, 4e5], Z, TH)
    ds.attrs.update(bearing_radius_m=8e-3, title="synthetic simulated wear")
    return ds


def meas_map(f, u):
    coords = {"z": conventions.z_coord(Z), "theta": conventions.theta_coord(TH)}
    ds = xr.Dataset(coords=coords, attrs={"cycles": 4e5, "data_origin": "synthetic"})
    ds["wear_depth"] = (("z", "theta"), f, conventions.variable_attrs("wear_depth"))
    ds["wear_depth_u"] = (("z", "theta"), np.full_like(f, u), {"units": "m"})
    return ds


def ensemble(rng, n, **form):
    """n members of the model over its uncertain inputs, keeping their maps."""
    maps = np.array([field(**p, **form) for p in inputs(rng, n)])
    coords = {
        "run": np.arange(n),
        "z": conventions.z_coord(Z),
        "theta": conventions.theta_coord(TH),
    }
    ens = xr.Dataset({"wear_depth": (("run", "z", "theta"), maps, {"units": "m"})}, coords=coords)
    ens = ens.assign_coords(kw=("run", rng.uniform(size=n)))
    ens.attrs.update(cycles=4e5, probabilistic_sample="true")
    return ens


def test_mahalanobis_test_fails_a_right_model_at_the_stated_rate():
    rng = np.random.default_rng(0)
    a = rng.standard_normal((5, 5))
    cov = a @ a.T + 0.1 * np.eye(5)
    draws = rng.multivariate_normal(np.zeros(5), cov, size=4000)
    fails = np.mean([not mahalanobis_test(e, cov, 0.05).passed for e in draws])
    assert 0.04 < fails < 0.06
    # shares sum to 1: a singular covariance, one fewer degree of freedom
    j = np.eye(4) - 0.25
    t = mahalanobis_test(np.array([0.1, -0.1, 0.0, 0.0]), j @ j.T, 0.05)
    assert t.dof == 3 and t.d2 == pytest.approx(0.02)
    # a common scale error along s is detected beyond the stated resolution, not below
    s = np.array([1.0, 2.0, 3.0, 4.0, 5.0])
    res = mahalanobis_test(0 * s, cov, 0.05, s).scale_resolution
    assert mahalanobis_test(0.99 * res * s, cov, 0.05).passed
    assert not mahalanobis_test(1.01 * res * s, cov, 0.05).passed


def test_right_model_passes_and_a_wrong_axial_form_fails_on_synthetic_truth():
    """8 truths drawn from the inputs, measured with noise; the right model (nominal inputs, its
    own 16-member ensemble) against the wrong form (wear piled at the band's edges, peak about as
    deep: the maximum depth and the shape still pass it)."""
    rng = np.random.default_rng(1)
    crit = Criteria(wear_u_num_rel=0.02)
    right, wrong, depth_wrong = [], [], []
    for _ in range(8):
        truth = field(**inputs(rng, 1)[0])
        meas = meas_map(truth + 0.6e-6 * rng.standard_normal(truth.shape), 0.6e-6)
        c = compare(sim_map(field()), meas, ensemble=ensemble(rng, 16), criteria=crit)
        right.append([c.state(q) for q in ("wear field", "axial distribution of the wear")])
        w = compare(sim_map(field(edge=0.6)), meas, ensemble=ensemble(rng, 16, edge=0.6),
                    criteria=crit)  # fmt: skip
        wrong.append([w.state(q) for q in ("wear field", "axial distribution of the wear")])
        depth_wrong.append(w.state("maximum wear depth"))
    assert all(s == ["pass", "pass"] for s in right), right
    assert all(s == ["fail", "fail"] for s in wrong), wrong
    assert depth_wrong.count("pass") >= 6  # the scalar criterion does not see the form
    # the card states the false-fail rate, the metrics the distance, the resolution the scale
    row = w.decisions[w.decisions.key == "wear_field"].iloc[0]
    assert "false-fail rate 5%" in row.criterion and row.basis == "field"
    assert w.value("wear_field", "mahalanobis_d2") > w.value("wear_field", "mahalanobis_threshold")
    assert 0 < c.value("wear_field", "detectable_scale_error") < 1


def test_field_criteria_not_assessed_without_their_uncertainties():
    meas = meas_map(field(), 0.6e-6)
    c = compare(sim_map(field()), meas, criteria=Criteria(wear_u_num_rel=0.02))
    assert c.state("wear field") == "not_assessed"
    # a stated relative u_input is a common scale: enough for the field, not for the form
    c = compare(
        sim_map(field()), meas, criteria=Criteria(wear_u_num_rel=0.02, wear_u_input_rel=0.1)
    )
    assert c.state("wear field") == "pass"
    assert c.state("axial distribution of the wear") == "not_assessed"
    why = c.decisions.set_index("key").loc["axial_distribution", "reason"]
    assert "ensemble" in why
    no_u = meas.drop_vars("wear_depth_u")
    c = compare(sim_map(field()), no_u, ensemble=ensemble(np.random.default_rng(2), 8),
                criteria=Criteria(wear_u_num_rel=0.02))  # fmt: skip
    assert c.state("wear field") == "not_assessed"


def test_an_estimated_covariance_gives_hotellings_limit():
    """With the whole covariance a sample covariance of n members (nothing else known), the
    bootstrap limit is Hotelling's T²: K nu / (nu - K + 1) F(K, nu - K + 1), nu = n - 1."""
    from scipy import stats

    rng = np.random.default_rng(7)
    k, n = 3, 10
    x = rng.standard_normal((n, k)) @ np.diag([3.0, 1.0, 0.3])
    dev = (x - x.mean(axis=0)) / np.sqrt(n - 1)
    test = mahalanobis_test(np.zeros(k), dev.T @ dev, 0.05, estimated=(dev, n - 1))
    nu = n - 1
    hotelling = k * nu / (nu - k + 1) * stats.f.ppf(0.95, k, nu - k + 1)
    assert test.threshold == pytest.approx(hotelling, rel=0.1)
    assert test.threshold > 1.5 * stats.chi2.ppf(0.95, k)  # what chi² alone would have used


def test_an_ensemble_with_no_more_members_than_inputs_is_not_enough():
    """n members span n - 1 directions: over 4 varied inputs, 4 members leave the field criteria
    not assessed (naming the fix), 5 decide them."""
    rng = np.random.default_rng(8)
    meas = meas_map(
        field() + 0.6e-6 * rng.standard_normal(Z.size * TH.size).reshape(13, 72), 0.6e-6
    )
    for n, state in ((4, "not_assessed"), (5, "pass")):
        ens = ensemble(rng, n)
        ens.attrs["sweep_parameters"] = ["a", "th0", "w", "slope"]
        c = compare(sim_map(field()), meas, ensemble=ens, criteria=Criteria(wear_u_num_rel=0.02))
        assert c.state("wear field") == state, n
        if state == "not_assessed":
            why = c.decisions.set_index("key").loc["wear_field", "reason"]
            assert "at least 5 members" in why and "4 inputs" in why
