"""Validity of the contact model: a soft polymer bearing warns and records, a metal rig does not.

Truths: the ratios of :data:`jointwear.sim.CONTACT_LIMITS` in closed form for a given
penetration; the PTFE rig of issue 25 (bearing modulus 0.5 GPa: peak penetration ~218 um, 87 %
of the stop) against the study's steel/brass rig and a steel/steel rig.
"""

from __future__ import annotations

import json
import logging
import math

import pytest

from jointwear.params import replace_nested
from jointwear.sim import (
    CONTACT_LIMITS,
    DEFAULT_KW,
    PARAMETER_SETS,
    WearSettings,
    contact_validity,
    run_cycles,
    simulate_wear,
)

BASE = PARAMETER_SETS["zhang2023"]
PTFE = {"contact.bearing_modulus": 0.5e9, "contact.bearing_poisson": 0.46}
STEEL = {"contact.bearing_modulus": 207e9, "contact.bearing_poisson": 0.29}


def test_ratios_match_their_closed_forms():
    c = BASE.joint.radial_clearance
    rj, rb = BASE.joint.journal_radius, BASE.joint.bearing_radius
    delta = 0.3 * c
    res = contact_validity(BASE, delta, kw=DEFAULT_KW)
    ch = res["checks"]
    assert ch["penetration_clearance"]["value"] == pytest.approx(0.3, rel=1e-12)
    assert ch["penetration_stop"]["value"] == pytest.approx(0.3 / 0.5, rel=1e-12)
    assert ch["hertz_contact_angle"]["value"] == pytest.approx(
        math.sqrt(rj * rb / c * delta) / rj, rel=1e-12
    )
    assert ch["polymer_with_metal_kw"]["value"] == 0.0  # brass is not a polymer
    assert res["status"] == "exceeded" and ch["penetration_clearance"]["status"] == "exceeded"
    assert ch["penetration_stop"]["status"] == "within limits"
    # every limit is documented with its quantity
    assert set(ch) == set(CONTACT_LIMITS)
    small = contact_validity(BASE, 0.05 * c)
    assert small["status"] == "within limits" and small["warning"] is None
    assert small["checks"]["polymer_with_metal_kw"]["status"] == "not assessed"  # no kw given


def test_unknown_penetration_is_not_assessed_not_within_limits():
    res = contact_validity(BASE, math.nan, kw=DEFAULT_KW)
    assert res["status"] == "not assessed"
    assert res["checks"]["penetration_clearance"]["value"] is None


def test_ptfe_bearing_run_records_the_breach():
    p = replace_nested(BASE, **PTFE)
    r = run_cycles(p, cycles=1.0)
    attrs = r.dataset.attrs
    assert r.max_penetration == pytest.approx(float(r.dataset["penetration"].max()), rel=0.05)
    assert r.max_penetration > 0.2 * p.joint.radial_clearance
    assert attrs["contact_validity_status"] == "exceeded"
    checks = json.loads(attrs["contact_validity"])
    assert checks["penetration_clearance"]["status"] == "exceeded"
    assert checks["hertz_contact_angle"]["status"] == "exceeded"
    assert "penetration_clearance" in attrs["contact_validity_warning"]


@pytest.mark.parametrize("pair", ["steel_brass", "steel_steel"])
def test_metal_rigs_stay_within_the_limits(pair):
    p = replace_nested(BASE, **({} if pair == "steel_brass" else STEEL))
    r = run_cycles(p, cycles=1.0)
    assert r.dataset.attrs["contact_validity_status"] == "within limits"
    assert "contact_validity_warning" not in r.dataset.attrs
    assert 1e-6 < r.max_penetration < 0.2 * p.joint.radial_clearance  # contact happened


def test_wear_run_of_a_polymer_with_the_metal_kw_warns(caplog):
    p = replace_nested(BASE, **{**PTFE, "joint.n_layers": 6, "joint.n_points": 60})
    settings = WearSettings(kw=DEFAULT_KW, scheme="fixed", dn=50, settle_cycles=0)
    with caplog.at_level(logging.WARNING, logger="jointwear.sim.wear"):
        ds = simulate_wear(p, cycles=100, snapshots=[], settings=settings)
    checks = json.loads(ds.attrs["contact_validity"])
    assert checks["polymer_with_metal_kw"]["status"] == "exceeded"
    assert checks["penetration_stop"]["status"] == "exceeded"  # 87 % of the stop
    assert ds.attrs["contact_validity_max_penetration_m"] > 0.4 * p.joint.radial_clearance
    assert any("validity range" in r.getMessage() for r in caplog.records)
    # a kw calibrated for the pair removes that breach (the penetration ones remain)
    ds2 = simulate_wear(p, cycles=100, snapshots=[], settings=settings, kw=2 * DEFAULT_KW)
    assert json.loads(ds2.attrs["contact_validity"])["polymer_with_metal_kw"]["status"] == (
        "within limits"
    )


def test_metal_wear_run_records_no_breach():
    p = replace_nested(BASE, **{"joint.n_layers": 6, "joint.n_points": 60})
    settings = WearSettings(kw=DEFAULT_KW, scheme="fixed", dn=50, settle_cycles=0)
    ds = simulate_wear(p, cycles=100, snapshots=[], settings=settings)
    assert ds.attrs["contact_validity_status"] == "within limits"
    assert "contact_validity_warning" not in ds.attrs


def test_cycle_command_prints_and_records_the_breach(tmp_path, capsys):
    from jointwear import io
    from jointwear.cli import main

    params = tmp_path / "ptfe.toml"
    params.write_text("[contact]\nbearing_modulus = 0.5e9\nbearing_poisson = 0.46\n")
    out = tmp_path / "c.nc"
    assert main(["sim", "cycle", "--cycles", "1", "--out", str(out), "--params", str(params)]) == 0
    assert "left its validity range" in capsys.readouterr().err
    assert io.load(out).attrs["contact_validity_status"] == "exceeded"


SC = PARAMETER_SETS["slider_crank"]


@pytest.mark.parametrize(
    ("changes", "cause"),
    [
        # 10-um clearance at 5000 rpm: stops within about 40 us
        (
            {"joint.bearing_radius": SC.joint.journal_radius + 10e-6},
            "the clearance is too small for this load",
        ),
        # a PTFE bearing: stops at about 0.3 ms
        (PTFE, "the soft pair (0.5 GPa)"),
    ],
)
def test_a_physical_penetration_stop_names_its_cause_and_levers(changes, cause):
    """The stop compares the Hertz deflection under the ideal joint's load (2.72 kN, closed
    forms below) with the clearance and names the physical parameters, not the solver's."""
    from jointwear.errors import SimulationError
    from jointwear.sim.contact import contact_constant

    p = replace_nested(SC, **changes)
    with pytest.raises(SimulationError) as exc:
        run_cycles(p, cycles=1.0, record=False)
    msg = str(exc.value)
    assert "physical cause: " + cause in msg
    for lever in ("joint.bearing_radius", "contact.bearing_modulus", "crank_speed_rpm"):
        assert lever in msg
    assert "tightening the solver does not help" in msg
    assert "tighten solver tolerances" not in msg
    # the numbers quoted are the closed forms: d = (F/K)^(2/3), sudden ((n+1) F/K)^(2/3)
    ideal = run_cycles(replace_nested(p, **{"joint.model": "ideal"}), cycles=1.0).dataset
    f = float(ideal["contact_force"].max())
    k = contact_constant(p)[1]
    assert f"{f:.4g} N" in msg
    assert f"by {1e6 * (f / k) ** (2 / 3):.3g} um statically" in msg
    assert f"{1e6 * (2.5 * f / k) ** (2 / 3):.3g} um when applied at once" in msg


def test_the_printed_levers_run():
    """A lever the 10-um message names, applied: a tenth of the speed runs the cycle."""
    p = replace_nested(
        SC,
        **{
            "joint.bearing_radius": SC.joint.journal_radius + 10e-6,
            "mechanism.crank_speed_rpm": 500.0,
        },
    )
    assert run_cycles(p, cycles=1.0, record=False).max_penetration < 5e-6


def test_an_unexplained_stop_keeps_the_numerical_advice():
    """On the default four-bar the ideal joint's load deflects the contact by a few um against a
    250-um stop: a stop there would not be explained by the load, and the advice says so."""
    from jointwear.sim.validity import penetration_stop_advice

    text = penetration_stop_advice(BASE)  # the default four-bar: 63 um peaks of 500 um
    assert "physical cause" not in text and "solver.rtol" in text


def test_a_stop_set_below_the_loads_deflection_names_the_setting():
    from jointwear.sim.validity import penetration_stop_advice

    low = replace_nested(BASE, **{"contact.max_penetration_fraction": 0.01})
    text = penetration_stop_advice(low)
    assert (
        "the stop itself is set below" in text and "raise contact.max_penetration_fraction" in text
    )
