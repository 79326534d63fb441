"""Edge contact and wear work that do not depend on the bearing grid (issue 16, items 2-3).

A tilted journal pressed against one edge of the bore, shorter contact than any layer spacing
tested: its penetration along the bore is linear in z, so the contact force and the line load
at the edge have closed forms. The full grid study (4e5 cycles, 20x200 to 80x800) is
``benchmarks/bench_sim_grid.py``; here one contact evaluation and a few cycles.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from jointwear.params import replace_nested
from jointwear.sim import PARAMETER_SETS, run_cycles
from jointwear.sim.dynamics import _layers, _pack, point_area
from jointwear.sim.kernels._contact import _contact, _latch_impacts, _stiffness
from jointwear.sim.kernels._context import make_context

BASE = PARAMETER_SETS["zhang2023"]
EDGE_PEN = 1.0e-6  # penetration at the bearing edge z = +wb/2 [m]
CONTACT_LENGTH = 0.25e-3  # axial length of the contact [m], < wb / (Nl - 1) for Nl <= 40
SLIDE = 0.05  # tangential sliding speed [m/s]


def _press(params, length=CONTACT_LENGTH):
    """One contact evaluation of the tilted journal.

    Returns (wear work [Pa m], point areas, normal force [N], J0, u, normal work F |v_t| dt).
    """
    j = params.joint
    nl, nd = j.n_layers, j.n_points
    P, IP = _pack(params)
    zl, wl = _layers(params)
    h = np.zeros((nl, nd))
    tilt = EDGE_PEN / length  # d(penetration)/dz [rad]
    # journal axis in the x-z plane, offset towards theta = 0 (-x), deepest at z = +wb/2
    u = np.array([-math.sin(tilt), 0.0, math.cos(tilt)])
    e_edge = j.radial_clearance + EDGE_PEN  # axis offset in the edge plane (to first order)
    # journal centre at mid-width (no end-face contact), axis through (-e_edge, 0, wb/2)
    J0 = np.array([-e_edge, 0.0, 0.5 * j.bearing_width]) - 0.5 * j.bearing_width / u[2] * u
    V0 = np.array([0.0, SLIDE, 0.0])  # sliding along theta, no approach: L-N factor 1
    W = np.zeros(3)
    area = point_area(params)
    ww = np.zeros((2, nl, nd))
    acc = np.zeros(3)
    ctx = make_context(P, IP, h, h.min(axis=1).copy(), zl, wl, area, np.zeros(nl + 2), ww, acc)
    wrench = np.zeros(12)
    _contact(J0, u, V0, W, ctx, wrench, True, 1.0)
    return ww[0], area, float(np.linalg.norm(wrench[6:9])), J0, u, float(acc[0])


def _exact_penetration(params, J0, u, z):
    """Penetration of the bore point (theta = 0, z) by the journal (closed-form geometry)."""
    j = params.joint
    d = np.stack([np.full_like(z, -j.bearing_radius), np.zeros_like(z), z], axis=-1) - J0
    s = d @ u
    dist = np.linalg.norm(d - s[:, None] * u, axis=-1)
    return j.journal_radius - dist


def _grid(nl, nd, proj="local", **kw):
    return replace_nested(
        BASE,
        **{"joint.n_layers": nl, "joint.n_points": nd, "contact.wear_projection": proj, **kw},
    )


@pytest.mark.parametrize("grading", [0.0, 0.75])
@pytest.mark.parametrize("grid", [(10, 100), (20, 200), (40, 400)])
def test_edge_contact_force_and_line_load_match_the_closed_form(grid, grading):
    p = _grid(*grid, **{"joint.axial_grading": grading})
    j = p.joint
    work, area, fn, J0, u, _ = _press(p)
    K = _stiffness(*_pack(p), 0.0)  # eq. 9 on the new bore
    n = BASE.contact.exponent
    # penetration along the bore from the exact geometry: linear in z to 1e-4 relative
    z = np.linspace(0.5 * j.bearing_width - 2 * CONTACT_LENGTH, 0.5 * j.bearing_width, 201)
    pen = _exact_penetration(p, J0, u, z)
    slope = (pen[-1] - pen[0]) / (z[-1] - z[0])
    np.testing.assert_allclose(pen, pen[-1] + slope * (z - z[-1]), atol=1e-4 * EDGE_PEN)
    d0 = float(pen[-1])
    length = d0 / slope
    # the joint-level law spread over the width: q(z) = K delta(z)^n / wb [N/m]
    force = K * d0 ** (n + 1) / ((n + 1) * slope) / j.bearing_width
    assert fn == pytest.approx(force, rel=1e-3)
    zl, share = _layers(p)
    # wear work of the edge layer (z = +wb/2): its line load is the law at the edge, K d0^n / wb
    slice_width = share[0] * j.bearing_width
    line_load = float(np.sum(work[0] * area[0])) / SLIDE / slice_width
    assert line_load == pytest.approx(K * d0**n / j.bearing_width, rel=1e-3)
    # and nothing beyond the contact (on the equally spaced grids the next layer lies outside)
    outside = zl < 0.5 * j.bearing_width - length
    if grading == 0.0:
        assert outside[1]
    assert not np.any(work[outside])
    assert np.all(work[~outside].max(axis=1) > 0)


def test_lumped_projection_dilutes_the_edge_with_the_grid():
    """The projection before issue 16 spreads the edge force over the whole edge slice."""
    loads = []
    for nl, nd in ((10, 100), (40, 400)):
        work, area, *_ = _press(_grid(nl, nd, "lumped", **{"joint.axial_grading": 0.0}))
        loads.append(float(np.sum(work[0] * area[0])) / (0.5 / (nl - 1)))
    # the edge layer's line load scales with 1 / slice width: x4.3 from 10 to 40 layers
    assert loads[1] / loads[0] > 3.5


@pytest.mark.parametrize("proj", ["local_conserving", "lumped", "local"])
def test_worn_volume_is_kw_times_normal_work_unless_local(proj):
    # sum(wear work x area) = integral F |v_t| dt: exact for the conserving projections; the
    # unscaled local law overestimates it where the contact is shorter than a layer spacing
    # (equal spacing: the 0.25 mm contact lies in a 0.39 mm half-slice)
    work, area, _, _, _, normal = _press(_grid(20, 200, proj, **{"joint.axial_grading": 0.0}))
    ratio = float(np.sum(work * area)) / normal
    if proj == "local":
        assert ratio > 1.5
    else:
        assert ratio == pytest.approx(1.0, rel=1e-12)


def test_conserving_projection_keeps_the_local_shape_of_a_resolved_contact():
    # a long edge contact (8 layer spacings): local and conserving differ by one factor
    # close to 1, the lumped edge value lies below both (one-sided slice average)
    length = 8 * BASE.joint.bearing_width / 19
    eq = {"joint.axial_grading": 0.0}
    rows = {
        p: _press(_grid(20, 200, p, **eq), length) for p in ("local", "local_conserving", "lumped")
    }
    load = {k: np.sum(v[0] * v[1], axis=1) for k, v in rows.items()}  # per layer
    ratio = load["local_conserving"][:8] / load["local"][:8]
    np.testing.assert_allclose(ratio, ratio[0], rtol=1e-12)
    assert abs(ratio[0] - 1) < 0.05
    assert load["lumped"][0] / load["local"][0] < 0.96  # 0.94 for this contact


def test_one_cycle_edge_wear_work_converges_with_the_grid():
    """Dynamics on the new bore: edge-layer wear work of two cycles, two grids."""
    edge = {}
    for proj in ("local", "lumped"):
        vals = []
        for nl, nd in ((20, 200), (40, 400)):
            p = _grid(nl, nd, proj)
            st = run_cycles(p, cycles=1.0, record=False).state
            r = run_cycles(p, cycles=2.0, state=st, record=False)
            vals.append(float(r.wear_work[-1].max()))
        edge[proj] = vals
    assert edge["local"][1] / edge["local"][0] == pytest.approx(1.0, abs=0.08), edge
    assert edge["lumped"][1] / edge["lumped"][0] > 1.15, edge


def _latch(son, srate, vimp, floor=0.01, per_layer=0):
    son = np.asarray(son, dtype=np.int64)
    vimp = np.asarray(vimp, dtype=float).copy()
    _latch_impacts(vimp, np.asarray(srate, dtype=float), son, son.size - 2, floor, per_layer)
    return vimp


def test_impact_velocity_is_latched_once_per_impact_and_region():
    # layers 0-5 then the two end faces; new impact on layers 1-2: the region's fastest rate
    v = _latch([0, 1, 1, 0, 0, 0, 0, 1], [0, 0.3, 0.5, 0, 0, 0, 0, 0.002], np.zeros(8))
    np.testing.assert_array_equal(v, [0, 0.5, 0.5, 0, 0, 0, 0, 0.01])  # face: the floor
    # the contact spreads to layer 3 (approaching slowly): the impact keeps its velocity
    v2 = _latch([0, 1, 1, 1, 0, 0, 0, 0], [0, -0.1, 0.0, 0.001, 0, 0, 0, 0], v)
    np.testing.assert_array_equal(v2, [0, 0.5, 0.5, 0.5, 0, 0, 0, 0])
    # the per-layer form (before issue 16) latches the newcomer's own rate, at the floor
    v3 = _latch([0, 1, 1, 1, 0, 0, 0, 0], [0, -0.1, 0.0, 0.001, 0, 0, 0, 0], v, per_layer=1)
    np.testing.assert_array_equal(v3, [0, 0.5, 0.5, 0.01, 0, 0, 0, 0])
    # two regions: a second impact at layer 5 gets its own velocity; contact lost forgets
    v4 = _latch([0, 0, 1, 1, 0, 1, 0, 0], [0, 0, 0, 0, 0, 0.2, 0, 0], v2)
    np.testing.assert_array_equal(v4, [0, 0, 0.5, 0.5, 0, 0.2, 0, 0])
