"""Dynamics of the four-bar with joint C: ideal limit, energy, convergence, records, errors."""

from __future__ import annotations

import math
import pickle

import numpy as np
import pytest
import xarray as xr

from jointwear import conventions
from jointwear.errors import BadInputError, SimulationError
from jointwear.params import replace_nested
from jointwear.sim import PARAMETER_SETS, CycleResult, run_cycles

BASE = PARAMETER_SETS["zhang2023"]


def freudenstein(theta_crank, a=0.10, b=0.40, c=0.30, d=0.30, omega=4 * math.pi):
    """Follower angle and rate of a planar four-bar (Norton's form of Freudenstein's equation).

    Crank a pivoted at the origin, follower c pivoted at (d, 0); the branch with the follower
    pointing up (joint C above the ground line).
    """
    t2 = np.asarray(theta_crank, dtype=float)
    k1, k2, k3 = d / a, d / c, (a * a - b * b + c * c + d * d) / (2 * a * c)
    A = np.cos(t2) - k1 - k2 * np.cos(t2) + k3
    B = -2 * np.sin(t2)
    C = k1 - (k2 + 1) * np.cos(t2) + k3
    root = np.sqrt(B * B - 4 * A * C)
    cands = [2 * np.arctan2(-B + sgn * root, 2 * A) for sgn in (1.0, -1.0)]
    t4 = np.where(np.sin(cands[0]) > 0, cands[0], cands[1])
    # coupler angle from the two ends, then Norton's velocity relation
    bx, by = a * np.cos(t2), a * np.sin(t2)
    cx, cy = d + c * np.cos(t4), c * np.sin(t4)
    assert np.allclose(np.hypot(cx - bx, cy - by), b, atol=1e-12)  # the loop closes
    t3 = np.arctan2(cy - by, cx - bx)
    w4 = a * omega * np.sin(t2 - t3) / (c * np.sin(t4 - t3))
    return t4, w4


@pytest.mark.parametrize("theta10", [0.0, 137.0])
def test_ideal_joint_matches_loop_closure(theta10):
    p = replace_nested(
        BASE, **{"joint.model": "ideal", "mechanism.initial_crank_angle_deg": theta10}
    )
    ds = run_cycles(p, cycles=1.0).dataset
    theta = ds.crank_angle.values
    assert theta[0] == pytest.approx(math.radians(theta10), abs=1e-12)
    assert ds.time.values[-1] == pytest.approx(0.5)
    assert np.ptp(np.unwrap(theta)) == pytest.approx(2 * math.pi, rel=1e-6)
    t4, w4 = freudenstein(theta)
    err = np.angle(np.exp(1j * (ds.follower_angle.values - t4)))
    assert np.abs(err).max() < 1e-6
    assert np.abs(ds.follower_angular_velocity.sel(axis="z").values - w4).max() < 1e-4
    # follower centre of mass moves on its circle around D with the right speed
    speed = np.linalg.norm(ds.follower_velocity.values, axis=1)
    assert np.allclose(speed, np.abs(w4) * 0.15, atol=1e-4)
    assert set(np.unique(ds.contact_mode.values)) == {6}


def test_small_clearance_tends_to_ideal():
    errs = []
    for rb in (7.52e-3, 7.505e-3):  # clearance 20 um, 5 um
        p = replace_nested(BASE, **{"joint.bearing_radius": rb, "mechanism.joint_offset": 0.0})
        ds = run_cycles(p, cycles=0.5).dataset
        t4, _ = freudenstein(ds.crank_angle.values)
        errs.append(np.abs(np.angle(np.exp(1j * (ds.follower_angle.values - t4)))).max())
    assert errs[0] < 3e-4
    assert errs[1] < 0.5 * errs[0]


@pytest.mark.parametrize("bearing_on", ["follower", "coupler"])
def test_energy_conserved_without_driver_friction_damping(bearing_on):
    p = replace_nested(
        BASE,
        **{
            "mechanism.driver": False,
            "mechanism.bearing_on": bearing_on,
            "friction.enabled": False,
            "contact.restitution": 1.0,
        },
    )
    ds = run_cycles(p, cycles=1.0).dataset
    e = ds.mechanical_energy.values
    assert np.abs(e - e[0]).max() / abs(e[0]) < 1e-4
    # the journal really hit the bearing (bore and end faces): the test is not vacuous
    assert (ds.contact_mode.values > 0).mean() > 0.1
    assert ds.contact_force.max() > 100.0
    assert ds.journal_tilt.max() > 1e-3


def _summary(params):
    r = run_cycles(params, cycles=1.0)
    fv = r.dataset.follower_velocity.values
    touching = r.dataset.contact_mode.values > 0
    return {
        "median_penetration": float(np.median(r.dataset.penetration.values[touching])),
        "impulse": r.normal_impulse,
        "mean_force": float(r.dataset.contact_force.mean()),
        "velocity_rms": float(np.sqrt((fv**2).sum(axis=1).mean())),
    }


@pytest.fixture(scope="module")
def reference_cycle():
    return _summary(BASE)


def test_grid_independence(reference_cycle):
    fine = _summary(replace_nested(BASE, **{"joint.n_layers": 40, "joint.n_points": 400}))
    for key in ("impulse", "mean_force"):
        assert fine[key] == pytest.approx(reference_cycle[key], rel=0.02), key
    assert reference_cycle["mean_force"] > 10.0
    # most contacts are edge contacts of the tilted journal, shorter than a layer spacing: the
    # penetration (hence pressure and stiffness) must not depend on the layer spacing either
    assert fine["median_penetration"] == pytest.approx(
        reference_cycle["median_penetration"], rel=0.1
    )


def test_tolerance_convergence(reference_cycle):
    s = BASE.solver
    tight = _summary(
        replace_nested(BASE, **{"solver.rtol": s.rtol / 10, "solver.atol": s.atol / 10})
    )
    for key in ("mean_force", "velocity_rms"):
        assert tight[key] == pytest.approx(reference_cycle[key], rel=0.01), key


def test_record_follows_contract_and_wear_work_balances():
    r = run_cycles(BASE, cycles=0.2)
    assert isinstance(r, CycleResult)
    ds = r.dataset
    conventions.validate(ds)
    assert ds.sizes["time"] == 1001
    assert ds.follower_velocity.dims == ("time", "axis")
    assert list(ds.axis.values) == ["x", "y", "z"]
    meanings = ds.contact_mode.attrs["flag_meanings"].split()
    assert meanings[:5] == ["free_flight", "single_point", "line", "two_point", "axial"]
    assert len(ds.contact_mode.attrs["flag_values"]) == len(meanings)
    for name, var in ds.variables.items():
        if name != "axis":
            assert "units" in var.attrs and "long_name" in var.attrs, name
    # joint C in the global frame: the bearing turns about D at fixed distance, the journal
    # sits on the coupler L2 from B, and their distance is the journal offset's length
    bc, jc = ds.bearing_centre_position.values, ds.journal_centre_position.values
    np.testing.assert_allclose(np.linalg.norm(bc - [0.3, 0, 0], axis=1), math.hypot(0.3, 0.01))
    b = 2 * ds.crank_position.values
    np.testing.assert_allclose(np.linalg.norm((jc - b)[:, :2], axis=1), 0.4)
    np.testing.assert_allclose(jc[:, 2], 0.01)
    np.testing.assert_allclose(
        np.linalg.norm(jc - bc, axis=1), np.linalg.norm(ds.journal_offset.values, axis=1)
    )
    # wear work: non-negative, balances the normal work, and sits where the journal pressed
    assert r.wear_work.shape == r.point_area.shape == (20, 200)
    assert (r.wear_work >= 0).all()
    assert r.normal_work > 0
    assert (r.wear_work * r.point_area).sum() == pytest.approx(r.normal_work, rel=1e-10)
    # the maps are in the record too, on (z, theta) in the canonical convention
    np.testing.assert_array_equal(ds.wear_work.values, r.wear_work)
    assert ds.theta.attrs["angle_zero"] == "-x" and ds.z.values[0] == pytest.approx(7.5e-3)
    # sliding distance: only where there is wear work, bounded by the relative rotation
    slid = r.sliding_distance
    assert ((slid > 0) == (r.wear_work > 0)).all()
    dt = float(ds.time[1] - ds.time[0])
    w_rel = np.gradient(np.unwrap(ds.coupler_angle.values), dt) - (
        ds.follower_angular_velocity.sel(axis="z").values
    )
    assert 0.3 * np.abs(w_rel).sum() * dt * 8e-3 < slid.max()
    assert slid.max() < 1.2 * np.abs(w_rel).sum() * dt * 8e-3
    # total area of the bore
    assert r.point_area.sum() == pytest.approx(2 * math.pi * 8e-3 * 15e-3, rel=1e-12)
    touching = ds.contact_mode.values > 0
    off = ds.journal_offset.values[touching]
    u = ds.journal_axis.values[touching]
    for layer, z in ((0, 7.5e-3), (19, -7.5e-3)):
        axis_at_z = off + ((z - off[:, 2]) / u[:, 2])[:, None] * u  # journal axis in that slice
        phi = np.degrees(np.arctan2(axis_at_z[:, 1], -axis_at_z[:, 0])) % 360  # canonical
        worn = np.nonzero(r.wear_work[layer] > 0)[0] * 360 / 200
        assert worn.size > 0
        gap = np.abs((worn[:, None] - phi[None, :] + 180) % 360 - 180).min(axis=1)
        assert gap.max() < 30.0  # contact arcs reach +-25 deg at the deepest edge loads


def test_state_continues_and_pickles():
    first = run_cycles(BASE, cycles=0.1)
    state = pickle.loads(pickle.dumps(first.state))
    assert state.time == pytest.approx(0.05)
    second = run_cycles(BASE, cycles=0.1, state=state)
    a, b = first.dataset, second.dataset
    assert b.time.attrs["simulation_time_at_start"] == pytest.approx(0.05)
    # the second record starts where the first ended
    for name in ("crank_angle", "follower_angle", "journal_offset", "follower_velocity"):
        np.testing.assert_allclose(b[name].isel(time=0), a[name].isel(time=-1), atol=1e-9)
    with pytest.raises(BadInputError, match="state comes from a 'clearance' run"):
        run_cycles(replace_nested(BASE, **{"joint.model": "ideal"}), cycles=0.1, state=state)


def test_uniform_wear_moves_the_contact_outwards():
    h = np.full((20, 200), 20e-6)
    worn = run_cycles(BASE, cycles=0.2, wear_depth=h).dataset
    new = run_cycles(BASE, cycles=0.2).dataset
    # the journal sits deeper in a worn bore: eccentricity in contact grows by about h
    e_w = np.hypot(*worn.journal_offset.values[:, :2].T)[worn.contact_mode.values == 2]
    e_n = np.hypot(*new.journal_offset.values[:, :2].T)[new.contact_mode.values == 2]
    assert np.median(e_w) - np.median(e_n) == pytest.approx(20e-6, rel=0.1)


def test_bad_wear_input():
    with pytest.raises(BadInputError, match=r"wear_depth has shape \(20, 10\), expected"):
        run_cycles(BASE, cycles=0.1, wear_depth=np.zeros((20, 10)))
    bad = np.zeros((20, 200))
    bad[3, 4] = np.nan
    with pytest.raises(BadInputError, match="NaN"):
        run_cycles(BASE, cycles=0.1, wear_depth=bad)


def test_failure_names_time_and_keeps_partial_record():
    p = replace_nested(BASE, **{"contact.max_penetration_fraction": 0.01})
    with pytest.raises(SimulationError, match=r"t = .* s \(crank angle .* deg\).*penetration") as e:
        run_cycles(p, cycles=0.5)
    partial = e.value.partial
    assert isinstance(partial, xr.Dataset)
    assert 0 < partial.sizes["time"] < 2500
    assert np.isfinite(partial.contact_force.values).all()


def test_friction_force_bounded_by_coulomb():
    ds = run_cycles(BASE, cycles=0.2).dataset
    fn, ft = ds.contact_force_normal.values, ds.contact_force_tangential.values
    touching = fn > 1.0
    assert touching.sum() > 100
    assert (ft[touching] <= 0.2 * fn[touching] * (1 + 1e-9)).all()  # mu <= mu_s
    assert np.median(ft[touching] / fn[touching]) > 0.05  # the journal slides: mu ~ mu_d
    np.testing.assert_allclose(
        np.hypot(fn, ft)[touching], ds.contact_force.values[touching], rtol=0.05
    )
    nofric = run_cycles(replace_nested(BASE, **{"friction.enabled": False}), cycles=0.1).dataset
    assert (nofric.contact_force_tangential.values == 0).all()


def test_step_collapse_is_reported():
    p = replace_nested(BASE, **{"solver.min_step": 5e-4})
    with pytest.raises(SimulationError, match="step size collapsed below solver.min_step"):
        run_cycles(p, cycles=0.2)


def test_recording_does_not_change_the_solution_and_reports_progress():
    seen = []
    a = run_cycles(BASE, cycles=0.1, progress=seen.append)
    b = run_cycles(BASE, cycles=0.1, record=False)
    assert b.dataset is None
    np.testing.assert_array_equal(a.wear_work, b.wear_work)
    np.testing.assert_array_equal(a.state.y, b.state.y)
    assert seen == sorted(seen) and seen[-1] == 1.0 and len(seen) == 5


def test_wear_map_resampled_onto_the_grid_in_the_canonical_convention():
    from jointwear.conventions import AngleConvention, theta_coord, z_coord
    from jointwear.errors import ConventionError
    from jointwear.sim import wear_depth_on_grid
    from jointwear.sim.dynamics import _layers

    # a measured-style map: 13 layers 1 mm apart, 1 degree steps, 0 deg along +x, ccw
    psi = np.arange(360.0)  # physical angle, ccw from +x
    z = np.linspace(-6e-3, 6e-3, 13)

    def truth(psi_deg, z_m):
        return 10e-6 + 20e-6 * np.cos(np.radians(psi_deg - 30.0)) * (1 + z_m / 0.01)

    da = xr.DataArray(
        truth(psi[None, :], z[:, None]),
        coords={"z": z_coord(z), "theta": theta_coord(psi, AngleConvention("+x", "ccw"))},
        dims=("z", "theta"),
        attrs={"units": "m"},
    )
    h = wear_depth_on_grid(da, BASE)
    assert h.shape == (20, 200)
    phi = np.arange(200) * 1.8  # canonical: from -x, clockwise
    zn = np.clip(_layers(BASE)[0], -6e-3, 6e-3)  # the simulator's (graded) layers
    expected = truth(180.0 - phi[None, :], zn[:, None])
    np.testing.assert_allclose(h, expected, atol=2e-9)
    stacked = xr.concat([da * 0, da], dim="cycles").assign_coords(cycles=[0.0, 1e5])
    np.testing.assert_allclose(wear_depth_on_grid(stacked, BASE), h)
    np.testing.assert_allclose(wear_depth_on_grid(stacked, BASE, cycles=0.0), 0.0)
    da.theta.attrs.pop("angle_zero")
    with pytest.raises(ConventionError, match="does not state its angle convention"):
        wear_depth_on_grid(da, BASE)


def test_bearing_carrier_does_not_change_planar_motion():
    # with joint C in the links' plane the motion is planar and only the relative motion of
    # journal and bearing matters: the carrier (follower or coupler) must not change it
    out = []
    for carrier in ("follower", "coupler"):
        p = replace_nested(BASE, **{"mechanism.bearing_on": carrier, "mechanism.joint_offset": 0.0})
        r = run_cycles(p, cycles=1.0)
        ecc = np.linalg.norm(r.dataset.journal_offset.values, axis=1)
        out.append((r.normal_impulse, float(r.dataset.contact_force.mean()), ecc.mean()))
        assert np.abs(r.dataset.follower_position.sel(axis="z")).max() < 1e-9
    np.testing.assert_allclose(out[0], out[1], rtol=0.02)


def test_ideal_four_bar_without_driver_is_refused():
    # the ideal four-bar is kinematically driven: a free crank is not modelled, so it is refused
    from jointwear.errors import ParameterError

    p = replace_nested(BASE, **{"joint.model": "ideal", "mechanism.driver": False})
    with pytest.raises(ParameterError, match=r"needs mechanism\.driver = true"):
        run_cycles(p, cycles=0.01)


@pytest.mark.parametrize(
    ("base", "model", "step", "length"),
    [
        ("zhang2023", "clearance", 1e-5, 11),
        ("zhang2023", "ideal", 1e-4, 6),
        ("slider_crank", "clearance", 1e-6, 11),
        ("slider_crank", "ideal", 1e-6, 2),
    ],
)
def test_initial_state_of_each_mechanism_and_model(base, model, step, length):
    from jointwear.sim import initial_state

    p = replace_nested(PARAMETER_SETS[base], **{"joint.model": model})
    st = initial_state(p)
    assert (st.model, st.mechanism, st.step, st.y.shape) == (
        model,
        base.replace("zhang2023", "four_bar"),
        step,
        (length,),
    )
    assert st.y[0] == pytest.approx(math.radians(p.mechanism.initial_crank_angle_deg))
