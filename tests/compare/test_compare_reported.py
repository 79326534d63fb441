"""Reported measurements judged against simulated wear maps with closed-form truths.

The simulated map ``h = N / N_ref [c (z + W/2) + e/2 (1 + cos 2(theta - phi))]`` has a known
cylindricity on the measured layers (a taper plus an ovality: LSCY = MZCY = c L + e); the map
``N / N_ref [c (z + W/2) + A bump(theta - theta0(z))]`` a known angle of maximum wear per layer
(the bump's centre theta0(z)). Every criterion is shown to pass for the right model and to FAIL for a wrong
one (kw x 2, angles off by 180 degree).
"""

from __future__ import annotations

import copy

import _jw_synth as syn
import numpy as np
import pytest
import xarray as xr

import jointwear.compare.verdicts as vd
from jointwear.compare import Criteria, compare
from jointwear.compare._reported_quantities import mz_cylindricity
from jointwear.compare.metrics import lsq_cylindricity
from jointwear.reported import reported_dataset

WIDTH = 15e-3
N_REF = 4e5
C_TAPER = 5e-3  # 5 um of wear per mm along z
E_OVAL = 6e-6  # ovality peak-to-valley [m]
LAYERS = {"count": 5, "spacing": "1 mm", "z_centre": "0 mm", "first": "+z"}
CYL_TRUE = C_TAPER * 4e-3 + E_OVAL  # on the 5 measured layers (4 mm span): 26 um


def theta0(z):
    """Canonical angle of the bump's maximum at axial position z [m]: 90 + 20 degree/mm."""
    return 90.0 + 20.0 * np.asarray(z) * 1e3


def field(z, theta, *, bump=0.0, rotate=0.0, scale=1.0, twist=20.0):
    z = np.asarray(z)[:, None]
    th = np.asarray(theta)[None, :]
    oval = E_OVAL if bump == 0 else 0.0  # the angle maps: taper and bump only (no shift)
    h = C_TAPER * (z + WIDTH / 2) + 0.5 * oval * (1 + np.cos(np.deg2rad(2 * (th - 30.0))))
    d = (th - (90.0 + twist * z * 1e3) - rotate + 180.0) % 360.0 - 180.0
    return scale * (h + bump * np.exp(-0.5 * (d / 20.0) ** 2))


def sim_map(*, bump=0.0, rotate=0.0, scale=1.0, cycles=(1e5, 4e5, 1e6), n_layers=31, twist=20.0):
    z = np.linspace(-WIDTH / 2, WIDTH / 2, n_layers)
    theta = np.arange(360) * 1.0
    depth = np.stack(
        [
            field(z, theta, bump=bump, rotate=rotate, scale=scale, twist=twist) * c / N_REF
            for c in cycles
        ]
    )
    ds = syn.wear_history(depth, cycles, z, theta)
    ds.attrs.update({"title": "synthetic simulated wear", "data_origin": "simulated"})
    return ds


def cyl_file(reference="LS", *, new=True, value_um=5.0 + CYL_TRUE * 1e6, cycles=N_REF) -> dict:
    q = {
        "cyl": {
            "kind": "cylindricity",
            "value": value_um,
            "unit": "um",
            "cycles": cycles,
            "layers": "all",
            "reference": reference,
            "source": "sheet",
            "uncertainty": {"standard": 0.1},
        }
    }
    if new:
        q["cyl_new"] = {**q["cyl"], "value": 5.0, "cycles": 0}
    return {
        "schema": "jointwear.reported/1",
        "data_origin": "synthetic",
        "source": {"citation": "synthetic"},
        "layers": dict(LAYERS),
        "quantity": q,
    }


def angle_file(value, *, zero="-x", direction="clockwise", layer=1, figure="6 degree") -> dict:
    return {
        "schema": "jointwear.reported/1",
        "data_origin": "synthetic",
        "source": {"citation": "synthetic"},
        "layers": dict(LAYERS),
        "angle": {"zero": zero, "direction": direction},
        "quantity": {
            "ang": {
                "kind": "max_wear_angle",
                "value": value,
                "unit": "degree",
                "cycles": N_REF,
                "layer": layer,
                "source": "fig",
                "uncertainty": {"figure_reading": figure},
            }
        },
    }


STATED = Criteria(wear_u_num_rel=0.05, wear_u_input_rel=0.05)


def vv20(result, name):
    d = result.decisions[(result.decisions.key == name) & (result.decisions.basis == "V&V 20")]
    assert len(d) == 1, result.decisions
    return d.iloc[0]


def test_mz_and_ls_cylindricity_closed_form():
    z = np.linspace(-2e-3, 2e-3, 5)
    theta = np.arange(360) * 1.0
    f = field(z, theta)
    assert lsq_cylindricity(f, z, theta) == pytest.approx(CYL_TRUE, rel=1e-9)
    assert mz_cylindricity(f, z, theta) == pytest.approx(CYL_TRUE, rel=1e-6)
    # an eccentric, tilted cylinder is no form error for either reference
    ecc = 3e-6 * np.cos(np.deg2rad(theta - 40))[None, :] * (1 + 200 * z[:, None])
    assert mz_cylindricity(f + ecc, z, theta) == pytest.approx(CYL_TRUE, rel=1e-6)
    rng = np.random.default_rng(0)
    noisy = f + rng.normal(0, 1e-6, f.shape)
    assert mz_cylindricity(noisy, z, theta) < lsq_cylindricity(noisy, z, theta)


@pytest.mark.parametrize("reference", ["LS", "MZ", "unstated"])
def test_cylindricity_growth_right_model_passes_kw_x2_fails(reference):
    rep = reported_dataset(cyl_file(reference))
    right = compare(sim_map(), rep, criteria=STATED)
    row = vv20(right, "cyl")
    assert row.state == vd.PASS, row
    assert right.value("cyl", "value_sim") == pytest.approx(CYL_TRUE, rel=1e-5)
    assert right.value("cyl", "value_meas") == pytest.approx(CYL_TRUE, rel=1e-9)  # growth
    # u_D: both readings and the new bore's form as a rectangular +-C0 term
    u_d = np.sqrt(2 * 0.1e-6**2 + (5e-6 / np.sqrt(3)) ** 2)
    assert right.value("cyl", "u_D") == pytest.approx(u_d, rel=1e-6)
    wrong = compare(sim_map(scale=2.0), rep, criteria=STATED)  # the wear coefficient doubled
    assert vv20(wrong, "cyl").state == vd.FAIL
    assert wrong.any_failed


def test_cylindricity_new_bore_is_baseline_not_a_prediction():
    result = compare(sim_map(), reported_dataset(cyl_file()), criteria=STATED)
    row = vv20(result, "cyl_new")
    assert row.state == vd.NOT_COMPARABLE and "baseline" in row.reason
    assert result.value("cyl_new", "value_meas") == pytest.approx(5e-6)  # as reported


def test_cylindricity_without_new_bore_is_not_assessed():
    rep = reported_dataset(cyl_file(new=False))
    row = vv20(compare(sim_map(), rep, criteria=STATED), "cyl")
    assert row.state == vd.NOT_ASSESSED
    assert "new bore's cylindricity is not reported" in row.reason


def ensemble_of_rotations(shifts, cycles=(N_REF,), rotate=0.0):
    """Members of the bump map turned by ``rotate + shifts`` degree: u_input = std(shifts)."""
    base = sim_map(bump=20e-6, cycles=cycles)
    members = [sim_map(bump=20e-6, rotate=rotate + s, cycles=cycles)["wear_depth"] for s in shifts]
    ens = xr.Dataset({"wear_depth": xr.concat(members, dim="run")})
    ens = ens.assign_coords(run=np.arange(len(shifts)), shift=("run", np.asarray(shifts, float)))
    ens.attrs.update({"cycles": cycles[-1], "probabilistic_sample": "true"})
    ens["wear_depth"].attrs = base["wear_depth"].attrs
    return ens


def refinement_study(offsets, h=(1.0, 2.0, 4.0), rotate=0.0):
    """Maps per refinement level h, the bump turned by ``rotate + offsets`` (converging)."""
    maps = [sim_map(bump=20e-6, rotate=rotate + o, cycles=(N_REF,))["wear_depth"] for o in offsets]
    study = xr.Dataset({"wear_depth": xr.concat(maps, dim="dn")})
    return study.assign_coords(dn=("dn", np.asarray(h), {"units": "1", "long_name": "dN"}))


@pytest.mark.parametrize(
    ("zero", "direction", "value"),
    [("-x", "clockwise", 130.0), ("+y", "counterclockwise", 320.0), ("+x", "clockwise", 310.0)],
)
def test_angle_right_model_passes_180_off_fails(zero, direction, value):
    # layer 1 at +z: z = +2 mm, bump centre 130 degree (canonical); the same direction in the
    # other conventions: (+y, ccw) 320 degree, (+x, cw) 310 degree
    rep = reported_dataset(angle_file(value, zero=zero, direction=direction))
    ens = ensemble_of_rotations([-2.0, -1.0, 0.0, 1.0, 2.0])
    study = refinement_study([0.5, 1.0, 2.0])
    sim = sim_map(bump=20e-6)
    right = compare(sim, rep, ensemble=ens, verification=[study])
    row = vv20(right, "ang")
    assert row.state == vd.PASS, row
    assert right.value("ang", "value_meas") == pytest.approx(130.0)
    assert right.value("ang", "value_sim") == pytest.approx(130.0, abs=0.2)
    assert right.value("ang", "u_input") == pytest.approx(
        np.std([-2, -1, 0, 1, 2], ddof=1), rel=0.05
    )
    # GCI of 130.5, 131, 132 at h = 1, 2, 4: p = 1, GCI = 1.25 * 0.5 / 1 -> u_num = 0.625 / 2
    assert right.value("ang", "u_num") == pytest.approx(0.625 / 2, rel=0.05)
    # the wrong model through the whole chain: its ensemble and verification study too
    wrong = compare(
        sim_map(bump=20e-6, rotate=180.0),
        rep,
        ensemble=ensemble_of_rotations([-2.0, -1.0, 0.0, 1.0, 2.0], rotate=180.0),
        verification=[refinement_study([0.5, 1.0, 2.0], rotate=180.0)],
    )
    row = vv20(wrong, "ang")
    assert wrong.value("ang", "u_input") == pytest.approx(
        np.std([-2, -1, 0, 1, 2], ddof=1), rel=0.05
    )
    assert row.state == vd.FAIL
    assert abs(wrong.value("ang", "E")) == pytest.approx(180.0, abs=0.5)


def test_angle_error_is_circular_across_zero():
    # reported 355 degree, simulated 5 degree: E = +10, not -350
    sim = sim_map(bump=20e-6, rotate=5.0 - 130.0)  # bump at 5 degree on layer 1
    rep = reported_dataset(angle_file(355.0, figure="10 degree"))
    result = compare(
        sim,
        rep,
        ensemble=ensemble_of_rotations([-2.0, 0.0, 2.0]),
        verification=[refinement_study([0.5, 1.0, 2.0])],
    )
    assert result.value("ang", "E") == pytest.approx(10.0, abs=0.3)
    assert vv20(result, "ang").state == vd.PASS


def test_angle_without_uncertainties_is_not_assessed_screening_is_no_verdict():
    rep = reported_dataset(angle_file(130.0))
    result = compare(sim_map(bump=20e-6), rep)
    row = vv20(result, "ang")
    assert row.state == vd.NOT_ASSESSED
    assert "screening only" in row.value and "<= 30 degree" in row.value
    assert len(result.decisions) == 1  # the screening threshold is never a pass or a fail
    off = vv20(compare(sim_map(bump=20e-6, rotate=180.0), rep), "ang")
    assert off.state == vd.NOT_ASSESSED and "> 30 degree" in off.value


def test_unstated_direction_decides_only_where_readings_agree():
    ens = ensemble_of_rotations([-2.0, 0.0, 2.0])
    study = refinement_study([0.5, 1.0, 2.0])
    # 130 cw = 230 ccw: the readings disagree -> not comparable, naming the field
    rep = reported_dataset(angle_file(130.0, direction="unstated"))
    row = vv20(compare(sim_map(bump=20e-6), rep, ensemble=ens, verification=[study]), "ang")
    assert row.state == vd.NOT_COMPARABLE
    assert "angle.direction" in row.reason and "PASS" in row.reason and "FAIL" in row.reason
    # 0 degree reads the same in both directions: decided
    sim0 = sim_map(bump=20e-6, rotate=-130.0)
    rep0 = reported_dataset(angle_file(0.0, direction="unstated"))
    assert vv20(compare(sim0, rep0, ensemble=ens, verification=[study]), "ang").state == vd.PASS
    assert (
        vv20(compare(sim_map(bump=20e-6), rep0, ensemble=ens, verification=[study]), "ang").state
        == vd.FAIL
    )


def test_unstated_layer_order_enumerated():
    data = angle_file(130.0)
    data["layers"]["first"] = "unstated"  # layer 1 at +2 mm (130 degree) or -2 mm (50 degree)
    rep = reported_dataset(data)
    result = compare(
        sim_map(bump=20e-6),
        rep,
        ensemble=ensemble_of_rotations([-2.0, 0.0, 2.0]),
        verification=[refinement_study([0.5, 1.0, 2.0])],
    )
    row = vv20(result, "ang")
    assert row.state == vd.NOT_COMPARABLE and "layers.first" in row.reason


@pytest.mark.parametrize(
    ("change", "reason"),
    [
        ({"cycles": 3e6}, "cannot give it at 3e+06 cycles"),
        ({"z": "9 mm"}, "outside the simulated bore"),
        ({"kind": "other", "definition": "surface roughness Ra"}, "no quantity of this definition"),
    ],
)
def test_not_comparable_with_reason(change, reason):
    data = angle_file(130.0)
    q = data["quantity"]["ang"]
    q.update(change)
    if "z" in change:
        del q["layer"]
    rep = reported_dataset(data)
    row = vv20(compare(sim_map(bump=20e-6), rep, criteria=STATED), "ang")
    assert row.state == vd.NOT_COMPARABLE
    assert reason in row.reason


def test_reported_beside_a_wear_map_and_storage_round_trip(tmp_path):
    from jointwear.compare import load_comparison, save_comparison

    sim = sim_map()
    meas = sim.sel(cycles=N_REF).drop_vars("cycles")
    meas.attrs = {"title": "measured", "data_origin": "synthetic", "cycles": N_REF}
    rep = reported_dataset(copy.deepcopy(cyl_file()))
    result = compare(sim, [meas, rep], criteria=STATED)
    assert any(str(q).startswith("wear map shape") for q in result.decisions.quantity)
    assert vv20(result, "cyl").state == vd.PASS
    path = save_comparison(result, tmp_path / "metrics.nc")
    back = load_comparison(xr.open_dataset(path))
    assert list(back.decisions.state) == list(result.decisions.state)


def verify_study(cycles=N_REF, rng=None):
    """A study in the file format of ``jointwear sim verify``: the bump turned by 0.25 h degree."""
    rng = rng or np.random.default_rng(1)
    h = np.array([1.0, 2.0, 4.0, 8.0])
    maps = np.stack(
        [
            np.stack(
                [
                    sim_map(bump=20e-6, rotate=0.25 * hi + 0.05 * rng.normal(), cycles=(N_REF,))[
                        "wear_depth"
                    ].isel(cycles=0)
                    for _ in range(3)
                ]
            )
            for hi in h
        ]
    )
    grid = sim_map(bump=20e-6, rotate=0.2, cycles=(N_REF,), n_layers=61)["wear_depth"].isel(
        cycles=0
    )
    gmaps = np.stack([grid.values + 1e-9 * rng.normal(size=grid.shape) for _ in range(3)])
    base = sim_map(cycles=(N_REF,))
    return xr.Dataset(
        {
            "wear_depth_run": (("level", "replicate", "z", "theta"), maps),
            "wear_depth_grid_run": (("grid_replicate", "z_grid", "theta_grid"), gmaps),
        },
        coords={
            "level": np.arange(h.size),
            "h": ("level", h),
            "z": base["z"].values,
            "theta": base["theta"].values,
            "z_grid": grid["z"].values,
            "theta_grid": grid["theta"].values,
        },
        attrs={
            "jointwear_file": "verification_study",
            "grid_ratio": 2.0,
            "grid_level": 0,
            "cycles": cycles,
        },
    )


def test_u_num_from_a_sim_verify_study():
    pytest.importorskip("jointwear.refinement")
    rep = reported_dataset(angle_file(130.0))
    ens = ensemble_of_rotations([-2.0, 0.0, 2.0])
    result = compare(sim_map(bump=20e-6), rep, ensemble=ens, verification=[verify_study()])
    m = result.metrics.set_index(["quantity", "metric"])
    u = m.loc[("ang", "u_num"), "value"]
    assert "verification study" in m.loc[("ang", "u_num"), "basis"]
    # the finest level is 0.25 degree off the converged angle: u_num covers it, and is small
    assert 0.1 < u < 5.0
    assert vv20(result, "ang").state == vd.PASS
    other = compare(sim_map(bump=20e-6), rep, ensemble=ens, verification=[verify_study(cycles=1e6)])
    row = vv20(other, "ang")
    assert row.state == vd.NOT_ASSESSED and "run for 1e+06 cycles" in row.reason


def test_unstated_stack_position_tried_along_the_bore():
    # a taper plus ovality has the same cylindricity wherever the 4 mm stack lies: decided
    data = cyl_file()
    data["layers"]["z_centre"] = "unstated"
    rep = reported_dataset(data)
    assert np.isnan(rep.attrs["layers_z_centre_m"])
    row = vv20(compare(sim_map(), rep, criteria=STATED), "cyl")
    assert row.state == vd.PASS, row
    # a wear growing with z^2 has a cylindricity that depends on where the stack lies: the
    # centred truth is not enough to decide - not comparable, naming the field
    sim = sim_map()
    z = sim["z"].values
    bowl = 2.0 * (z * 1e3) ** 2 * 1e-6  # 2 um/mm^2
    sim["wear_depth"] = (
        sim["wear_depth"] + bowl[None, :, None] * sim["cycles"].values[:, None, None] / N_REF
    )
    centred = compare(sim, reported_dataset(cyl_file()), criteria=STATED)
    s_centre = centred.value("cyl", "value_sim")
    truth = reported_dataset(cyl_file(value_um=5.0 + s_centre * 1e6))
    assert vv20(compare(sim, truth, criteria=STATED), "cyl").state == vd.PASS
    data = cyl_file(value_um=5.0 + s_centre * 1e6)
    data["layers"]["z_centre"] = "unstated"
    row = vv20(compare(sim, reported_dataset(data), criteria=STATED), "cyl")
    assert row.state == vd.NOT_COMPARABLE
    assert "layers.z_centre" in row.reason and "centred at z = +5.50 mm" in row.reason


def twisted(twist, *, study=False):
    """Ensemble with twists twist + (-0.5, 0, 0.5) degree/mm (separation over 4 mm: sd 2 degree),
    or a study over h = 1, 2, 4 with twist + 0.125 h (separation converging like 0.5 h)."""
    if study:
        maps = [
            sim_map(bump=20e-6, twist=twist + 0.125 * h, cycles=(N_REF,))["wear_depth"]
            for h in (1, 2, 4)
        ]
        ds = xr.Dataset({"wear_depth": xr.concat(maps, dim="dn")})
        return ds.assign_coords(dn=("dn", [1.0, 2.0, 4.0], {"units": "1", "long_name": "dN"}))
    base = sim_map(bump=20e-6, cycles=(N_REF,))
    members = [
        sim_map(bump=20e-6, twist=twist + t, cycles=(N_REF,))["wear_depth"] for t in (-0.5, 0, 0.5)
    ]
    ens = xr.Dataset({"wear_depth": xr.concat(members, dim="run")})
    ens = ens.assign_coords(run=np.arange(3), twist=("run", [twist - 0.5, twist, twist + 0.5]))
    ens.attrs.update({"cycles": N_REF, "probabilistic_sample": "true"})
    ens["wear_depth"].attrs = base["wear_depth"].attrs
    return ens


def test_angle_between_two_layers_needs_no_convention():
    # layer 1 (z = +2 mm) at 130 degree, layer 5 (z = -2 mm) at 50 degree: 80 degree apart in
    # any convention; the file states neither the direction nor the layer order
    data = angle_file(130.0, direction="unstated")
    data["layers"]["first"] = "unstated"
    data["quantity"]["ang5"] = dict(data["quantity"]["ang"], value=50.0, layer=5)
    rep = reported_dataset(data)
    right = compare(
        sim_map(bump=20e-6), rep, ensemble=twisted(20.0), verification=[twisted(20.0, study=True)]
    )
    assert vv20(right, "ang").state == vd.NOT_COMPARABLE  # each angle alone: readings disagree
    sep = "angle_between_ang_and_ang5"
    assert right.value(sep, "value_meas") == pytest.approx(80.0)
    assert right.value(sep, "value_sim") == pytest.approx(80.0, abs=0.5)
    assert vv20(right, sep).state == vd.PASS
    # a model whose wear does not turn along the bore (10 degree/mm instead of 20): FAIL
    wrong = compare(
        sim_map(bump=20e-6, twist=10.0),
        rep,
        ensemble=twisted(10.0),
        verification=[twisted(10.0, study=True)],
    )
    assert wrong.value(sep, "u_input") == pytest.approx(2.0, rel=0.05)
    assert wrong.value(sep, "value_sim") == pytest.approx(40.0, abs=0.5)
    assert vv20(wrong, sep).state == vd.FAIL


def test_max_wear_depth_right_model_passes_kw_x2_fails():
    # the taper map at layer 1 (z = +2 mm): c (z + W/2) + e (the ovality's peak), at N_REF
    depth_um = (C_TAPER * (2e-3 + WIDTH / 2) + E_OVAL) * 1e6
    data = cyl_file()
    data["quantity"] = {
        "depth": {
            "kind": "max_wear_depth",
            "value": depth_um,
            "unit": "um",
            "cycles": N_REF,
            "layer": 1,
            "source": "sheet",
            "uncertainty": {"standard": 0.5},
        }
    }
    rep = reported_dataset(data)
    right = compare(sim_map(), rep, criteria=STATED)
    assert right.value("depth", "value_sim") == pytest.approx(depth_um * 1e-6, rel=1e-6)
    assert vv20(right, "depth").state == vd.PASS
    assert vv20(compare(sim_map(scale=2.0), rep, criteria=STATED), "depth").state == vd.FAIL
