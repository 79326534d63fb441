"""Conformal-contact wear pressure (elastic foundation over the worn bore) against closed forms.

Truths: a rigid cylinder in a conforming bore on a Winkler foundation carries a line load F' with
``p = p0 cos(phi)`` over the half circle, ``F' = p0 R pi / 2``; in a bore of clearance c the
contact half-angle a has ``cos a = c / (d0 + c)`` and ``F' = kf R ((d0 + c)(a + sin a cos a) -
2 c sin a)``; the foundation modulus of an elastic layer is ``(1 - nu) E / ((1 + nu)(1 - 2 nu)
t)``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from jointwear.errors import ParameterError
from jointwear.params import replace_nested
from jointwear.sim import PARAMETER_SETS
from jointwear.sim.wear import conformal_wear_work
from jointwear.sim.wear._conformal import (
    _advance,
    _seated_gaps,
    foundation_modulus,
    hertz_matched_modulus,
    seated_gap,
    winkler_line_pressure,
)

RJ, C = 7.5e-3, 0.5e-3
KF = 1e14
N = 1440
PHI = np.arange(N) * 2 * math.pi / N
LOAD = 5000.0  # N/m


def test_cylinder_in_a_conforming_bore_closed_form():
    gap = seated_gap(np.full(N, RJ), RJ, PHI, 0.3)
    assert np.nanmax(gap) < 1e-15
    p, d0 = winkler_line_pressure(gap, PHI, 0.3, RJ, LOAD, KF)
    p0 = 2 * LOAD / (math.pi * RJ)
    c = np.cos(PHI - 0.3)
    np.testing.assert_allclose(p, p0 * np.maximum(c, 0), rtol=1e-6, atol=1e-9 * p0)
    assert d0 == pytest.approx(p0 / KF, rel=1e-6)


def test_bore_with_clearance_closed_form():
    """A softer foundation and a larger load so that the arc spans many points; the exact gap
    of a journal seated in a bore of radius R = Rj + c is (R c / Rj)(1 - cos phi) to second
    order, the clearance of the closed form."""
    kf, load, r = 1e12, 2e4, RJ + C
    gap = seated_gap(np.full(N, r), RJ, PHI, 1.0)
    p, d0 = winkler_line_pressure(gap, PHI, 1.0, r, load, kf)
    c = r * C / RJ
    a = math.acos(c / (d0 + c))
    exact = kf * r * ((d0 + c) * (a + math.sin(a) * math.cos(a)) - 2 * c * math.sin(a))
    assert exact == pytest.approx(load, rel=5e-3)
    half = np.abs((PHI[p > 0] - 1.0 + math.pi) % (2 * math.pi) - math.pi).max()
    assert half == pytest.approx(a, abs=2 * math.pi / N)
    assert math.degrees(a) > 5


def test_a_worn_groove_of_the_journals_radius_carries_the_load_over_a_wider_arc():
    """A groove worn 20 um deep to a circle of the journal's radius (plus 1 um) spans about
    +-16 deg; the same load on the new bore touches a narrower arc at a higher peak."""
    depth = 20e-6
    new = seated_gap(np.full(N, RJ + C), RJ, PHI, 0.0)
    circle = (C + depth) * np.cos(PHI) + np.sqrt(
        np.maximum((RJ + 1e-6) ** 2 - ((C + depth) * np.sin(PHI)) ** 2, 0.0)
    )
    groove = np.where(np.cos(PHI) > 0, np.maximum(circle, RJ + C), RJ + C)
    assert groove.max() - (RJ + C) == pytest.approx(depth + 1e-6, rel=1e-6)
    worn = seated_gap(groove, RJ, PHI, 0.0)
    kf, load = 1e12, 2e3
    p_new, _ = winkler_line_pressure(new, PHI, 0.0, RJ + C, load, kf)
    p_worn, _ = winkler_line_pressure(worn, PHI, 0.0, RJ + C, load, kf)
    arc_new = np.count_nonzero(p_new) * 360 / N
    arc_worn = np.count_nonzero(p_worn) * 360 / N
    assert arc_worn > 2 * arc_new
    assert p_worn.max() < 0.6 * p_new.max()


def test_matched_modulus_gives_hertz_width_on_the_unworn_bore():
    estar, load = 70e9, 2e4
    kf = hertz_matched_modulus(load, RJ, RJ + C, estar)
    b = math.sqrt(4 * load * (RJ * (RJ + C) / C) / (math.pi * estar))
    gap = seated_gap(np.full(N, RJ + C), RJ, PHI, 0.0)
    p, _ = winkler_line_pressure(gap, PHI, 0.0, RJ + C, load, kf)
    half = np.abs((PHI[p > 0] + math.pi) % (2 * math.pi) - math.pi).max() * (RJ + C)
    assert half == pytest.approx(b, abs=2 * math.pi / N * (RJ + C))


def test_foundation_modulus_and_refusals():
    assert foundation_modulus(100e9, 0.39, 2e-3) == pytest.approx(
        0.61 * 100e9 / (1.39 * 0.22 * 2e-3), rel=1e-12
    )
    with pytest.raises(Exception, match="thickness"):
        foundation_modulus(100e9, 0.39, 0.0)


ESTAR = 7.75e10  # the reference rig's steel journal on a bronze bush [Pa]
RB = RJ + C


def _groove(depth: float, centre: float, nd: int, extra: float = 1e-6) -> np.ndarray:
    """Worn depth of a groove to a circle of radius Rj + extra, ``depth`` deep at ``centre``."""
    phi = np.arange(nd) * 2 * math.pi / nd
    d = phi - centre
    ecc = C + depth - extra
    circle = ecc * np.cos(d) + np.sqrt(np.maximum((RJ + extra) ** 2 - (ecc * np.sin(d)) ** 2, 0))
    return np.where(np.cos(d) > 0, np.maximum(circle - RB, 0.0), 0.0)


def _area(nd: int, h: np.ndarray, width: float = 1e-3) -> np.ndarray:
    return width * (RB + h) * 2 * math.pi / nd


def test_exact_advance_is_the_root_of_the_balance():
    """The piecewise-linear solve equals the root the scalar reference finds by bisection."""
    groove = RB + _groove(15e-6, 0.5, N)
    kf, load = 1e12, 3e3
    for k in (100, 120, 200):
        ref_gap = seated_gap(groove, RJ, PHI, PHI[k])
        _, d_ref = winkler_line_pressure(ref_gap, PHI, PHI[k], float(np.mean(groove)), load, kf)
        gap, cos = _seated_gaps(groove, RJ, PHI, np.array([k]))
        dphi = 2 * math.pi / N
        rho = np.full(N, float(np.mean(groove)))
        d0 = _advance(gap, cos, rho, np.array([load / (kf * dphi)]))[0]
        assert d0 == pytest.approx(d_ref, rel=1e-9)


def test_one_contact_on_the_unworn_bore_stays_where_it_pressed():
    """Hertz's width on the reference rig (line load 1.3 kN/m: b = 51 um, 0.37 deg) is below
    a grid step: the work stays on the two nodes the contact's direction lies between, and the
    pressure's resultant is the force (unworn: the work is the centres' work)."""
    nd, nl = 200, 2
    h = np.zeros((nl, nd))
    area = np.broadcast_to(_area(nd, h[0]), (nl, nd)).copy()
    work = np.zeros((nl, nd))
    work[0, 50], work[1, 70], work[1, 71] = 2.0, 1.5, 0.5
    force = 1.3e3 * 1e-3  # N on a 1 mm slice
    out = conformal_wear_work(
        work, force * work, h, area, journal_radius=RJ, bearing_radius=RB, reduced_modulus=ESTAR
    )
    np.testing.assert_allclose(out * area, work, rtol=1e-9, atol=1e-15)


def test_total_force_is_the_applied_load_and_the_groove_spreads_it():
    """A groove worn 20 um to the journal's radius (plus 1 um): one contact at its centre.
    The Winkler pressure's resultant equals the force; the groove carries it over a wider arc
    than the unworn bore, at a lower peak, and centred on the contact's direction."""
    nd = 720
    phi = np.arange(nd) * 2 * math.pi / nd
    force, width = 30.0, 1e-3  # N, m: 30 kN/m
    peaks, arcs = {}, {}
    for name, depth in (("new", 0.0), ("groove", 20e-6)):
        h = _groove(depth, phi[300], nd)[None, :]
        area = _area(nd, h[0], width)[None, :]
        work = np.zeros((1, nd))
        work[0, 300] = 1.0  # N m
        out = conformal_wear_work(
            work, force * work, h, area, journal_radius=RJ, bearing_radius=RB, reduced_modulus=ESTAR
        )[0]
        pressure = out / 1.0 * force  # p = work x F / (F |ds|), per unit sliding
        cos = np.cos(phi - phi[300])
        resultant = np.sum(pressure * np.maximum(cos, 0) * area[0])
        assert resultant == pytest.approx(force, rel=1e-9)
        peaks[name] = pressure.max()
        arcs[name] = np.count_nonzero(out) * 360 / nd
        centroid = np.angle(np.sum(out * np.exp(1j * (phi - phi[300]))))
        assert abs(centroid) < 1e-9
    assert arcs["groove"] > 5 * arcs["new"]
    assert peaks["groove"] < 0.3 * peaks["new"]


def test_a_contact_on_a_grooves_flank_stays_where_the_journal_touches():
    """The error of the first attempt was to re-seat the journal along each worn point's own
    direction, which moved work from a groove's flank onto its rim. A contact is now seated
    along the journal's direction, as in the dynamics: its work lies, within a grid step, on
    the bore point a journal moved that way touches first (the dynamics' deepest point), here
    the groove's edge 6 deg further out, and nowhere else."""
    nd = 360
    phi = np.arange(nd) * 2 * math.pi / nd
    h = _groove(20e-6, phi[180], nd)[None, :]
    area = _area(nd, h[0])[None, :]
    work = np.zeros((1, nd))
    work[0, 190] = 1.0  # the journal points 10 deg off the groove's centre, inside its +-16 deg
    out = conformal_wear_work(
        work, 1.0 * work, h, area, journal_radius=RJ, bearing_radius=RB, reduced_modulus=ESTAR
    )[0]
    gap, _ = _seated_gaps(RB + h[0], RJ, phi, np.array([190]))
    touch = int(np.argmin(gap[0]))
    assert touch == 196
    centroid = math.degrees(np.angle(np.sum(out * area[0] * np.exp(1j * (phi - phi[touch])))))
    assert abs(centroid) < 1.0
    assert np.flatnonzero(out).min() >= touch - 1 and np.flatnonzero(out).max() <= touch + 1


def test_conformal_needs_the_slice_formulation():
    base = PARAMETER_SETS["zhang2023"]
    with pytest.raises(ParameterError, match="contact.formulation = 'slice'"):
        replace_nested(
            base, **{"contact.wear_pressure": "conformal", "contact.formulation": "per_point"}
        )
    fixed = replace_nested(base, **{"contact.wear_pressure": "conformal"})
    assert fixed.contact.formulation == "slice"


def test_the_dynamics_record_the_contacts_and_spread_them_conformally():
    """A quarter cycle of the reference rig on a coarse grid: the kernel's contact centres
    carry the same work as its Hertz spread (the normal work), and on the unworn bore the
    conformal pressure keeps that work (its arc being narrower than a grid step)."""
    from jointwear.sim import run_cycles

    base = replace_nested(
        PARAMETER_SETS["zhang2023"], **{"joint.n_layers": 4, "joint.n_points": 60}
    )
    conf = replace_nested(base, **{"contact.wear_pressure": "conformal"})
    hertz = run_cycles(base, cycles=0.25, record=False)
    res = run_cycles(conf, cycles=0.25, record=False)
    assert hertz.normal_work > 0
    assert res.normal_work == hertz.normal_work  # the option changes the wear, not the dynamics
    np.testing.assert_array_equal(res.sliding_distance, hertz.sliding_distance)
    total = float(np.sum(res.wear_work * res.point_area))
    assert total == pytest.approx(res.normal_work, rel=2e-3)
    assert total >= res.normal_work * (1 - 1e-12)
    assert res.wear_work.max() > hertz.wear_work.max()  # Hertz's width: narrower than the overlap
    lined = replace_nested(conf, **{"contact.foundation_thickness": 0.5})  # a very soft lining
    soft = run_cycles(lined, cycles=0.25, record=False)
    assert np.sum(soft.wear_work * soft.point_area) >= res.normal_work * (1 - 1e-12)
    assert soft.wear_work.max() < res.wear_work.max()  # softer: wider, lower peak


def test_a_stale_kernel_is_refused_not_read_as_no_wear():
    from jointwear.errors import SimulationError
    from jointwear.sim.dynamics import _conformal_maps

    conf = replace_nested(PARAMETER_SETS["zhang2023"], **{"contact.wear_pressure": "conformal"})
    shape = (conf.joint.n_layers, conf.joint.n_points)
    ww = np.zeros((4, *shape))
    ww[0, 0, 0] = 1.0
    with pytest.raises(SimulationError, match="NUMBA_CACHE_DIR"):
        _conformal_maps(conf, ww, np.zeros(shape), np.ones(shape))


def test_wear_command_refuses_conformal_on_per_point_and_its_fix_runs(tmp_path, capsys):
    from jointwear import io
    from jointwear.cli import main

    toml = tmp_path / "rig.toml"
    toml.write_text('[contact]\nwear_pressure = "conformal"\nformulation = "per_point"\n')
    out = tmp_path / "w.nc"
    args = ["sim", "wear", "--layers", "4", "--points", "48", "--out", str(out)]
    args += ["--cycles", "4", "--scheme", "fixed", "--dn", "2", "--snapshots", "4"]
    assert main([*args, "--params", str(toml)]) == 3
    err = capsys.readouterr().err
    assert "contact.wear_pressure = 'conformal'" in err and "contact.formulation = 'slice'" in err
    toml.write_text('[contact]\nwear_pressure = "conformal"\nformulation = "slice"\n')
    assert main([*args, "--params", str(toml)]) == 0
    ds = io.load(out)
    assert float(ds["worn_volume"][-1]) > 0
    assert ds.attrs["wear_pressure"] == "conformal"


def test_a_lining_foundation_gives_the_closed_form_contact_angle():
    """A fixed foundation (a 2 mm bronze lining) on the unworn bore: the contact half-angle a
    of ``F' = kf Rb c' ((a + sin a cos a) / cos a - 2 sin a)``, c' = Rb c / Rj."""
    from scipy.optimize import brentq

    nd = 7200
    kf = foundation_modulus(100e9, 0.39, 2e-3)
    force, width = 50.0, 1e-3  # 50 kN/m
    h = np.zeros((1, nd))
    area = _area(nd, h[0], width)[None, :]
    work = np.zeros((1, nd))
    work[0, 0] = 1.0
    out = conformal_wear_work(
        work,
        force * work,
        h,
        area,
        journal_radius=RJ,
        bearing_radius=RB,
        reduced_modulus=ESTAR,
        foundation=kf,
    )[0]
    cp = RB * C / RJ
    a = brentq(
        lambda a: (
            kf * RB * cp * ((a + math.sin(a) * math.cos(a)) / math.cos(a) - 2 * math.sin(a))
            - force / width
        ),
        1e-6,
        1.0,
    )
    half = (np.count_nonzero(out) - 1) / 2 * 360 / nd
    assert half == pytest.approx(math.degrees(a), abs=360 / nd)
    assert math.degrees(a) > 10 * 360 / nd  # resolved by the grid


def test_foundation_thickness_needs_the_conformal_pressure():
    base = PARAMETER_SETS["zhang2023"]
    with pytest.raises(ParameterError, match="set contact.wear_pressure = 'conformal'"):
        replace_nested(base, **{"contact.foundation_thickness": 2e-3})
    fixed = replace_nested(
        base, **{"contact.foundation_thickness": 2e-3, "contact.wear_pressure": "conformal"}
    )
    assert fixed.contact.foundation_thickness == 2e-3
