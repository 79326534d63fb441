"""Archard wear with cycle updates on prescribed (non-dynamic) contact models.

Truths: closed forms (constant contact: h = N kw p s; Winkler: worn volume = kw F s N because the
foundation carries the load F at every instant), refinement of the update interval, the linear
stability limit dN = 2 / (kw s kf) of explicit updates on a Winkler foundation, and round trips.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from jointwear import conventions
from jointwear.errors import BadInputError, ParameterError
from jointwear.sim import (
    BearingGrid,
    ConstantContact,
    CycleWear,
    WearRun,
    WearSettings,
    WinklerContact,
    simulate_wear,
    worn_volume,
)
from jointwear.sim.wear._files import demo_winkler_contact

GRID = BearingGrid(10, 72)


def swept_winkler(grid=GRID, **changes):
    """Load swinging between 45 and 135 degrees over the cycle (12 steps), tilted journal;
    ``changes``: other WinklerContact fields."""
    return dataclasses.replace(demo_winkler_contact(grid, n_steps=12), **changes)


def roughness(h):
    """Largest second difference around the circumference [m] (grid-scale zig-zag)."""
    return float(np.max(np.abs(np.diff(np.concatenate([h, h[:, :2]], axis=1), 2, axis=1))))


@pytest.mark.parametrize(
    "settings",
    [
        WearSettings(kw=3e-14, scheme="fixed", dn=1),
        WearSettings(kw=3e-14, scheme="fixed", dn=7),
        WearSettings(kw=3e-14, scheme="fixed", dn=333),
        WearSettings(kw=3e-14, scheme="fixed", dn=5000),
        WearSettings(kw=3e-14, scheme="adaptive", dn=3),
    ],
    ids=lambda s: f"{s.scheme}-{s.dn}",
)
def test_constant_contact_depth_is_n_kw_p_s_for_any_dn(settings):
    rng = np.random.default_rng(1)
    p = rng.uniform(0, 2e6, GRID.shape) * (rng.uniform(size=GRID.shape) > 0.3)
    model = ConstantContact(GRID, pressure=p, sliding=0.013)
    n = 2000 if settings.dn == 1 else 12345
    ds = simulate_wear(contact=model, cycles=n, settings=settings, snapshots=[1000, 1500])
    np.testing.assert_array_equal(ds["cycles"].values, [1000, 1500, n])
    for c in ds["cycles"].values:
        expected = c * settings.kw * p * 0.013  # layer order; map has z ascending
        got = ds["wear_depth"].sel(cycles=c).values[::-1, :]
        np.testing.assert_allclose(got, expected, rtol=1e-12, atol=0)
    assert int(ds["update_dn"].sum()) == n


def test_wear_map_layout_follows_the_contract():
    p = np.zeros(GRID.shape)
    p[0, 5] = 1e6  # layer 1 (z = +wb/2), point 5 (theta = 25 degree)
    ds = simulate_wear(
        contact=ConstantContact(GRID, pressure=p), cycles=10, settings=WearSettings(kw=1e-14)
    )
    conventions.validate(ds)
    assert np.all(np.diff(ds["z"].values) > 0)
    assert ds["z"].attrs["z_zero"] == "bearing mid-width"
    assert conventions.angle_convention_of(ds) == conventions.CANONICAL
    last = ds["wear_depth"].isel(cycles=-1)
    iz, it = np.unravel_index(np.argmax(last.values), last.shape)
    assert last.dims == ("z", "theta")
    assert float(last["z"][iz]) == pytest.approx(GRID.width / 2)
    assert float(last["theta"][it]) == pytest.approx(25.0)
    assert np.count_nonzero(last.values) == 1


def test_worn_volume_equals_kw_times_load_times_sliding():
    model = swept_winkler()
    kw, n = 1e-13, 50_000
    ds = simulate_wear(contact=model, cycles=n, settings=WearSettings(kw=kw))
    archard = kw * 20.0 * 0.02 * ds["cycles"].values  # kw * integral F_n ds, closed form
    np.testing.assert_allclose(ds["worn_volume"].values, archard, rtol=0.01)
    np.testing.assert_allclose(ds["archard_volume"].values, archard, rtol=1e-6)
    assert worn_volume(ds["wear_depth"].isel(cycles=-1).values[::-1], GRID) == pytest.approx(
        archard[-1], rel=0.01
    )


def _final(ds):
    return float(ds["max_wear_depth"][-1]), float(ds["worn_volume"][-1])


def test_halving_the_update_interval_changes_depth_and_volume_below_3_percent():
    model = swept_winkler(grid=BearingGrid(10, 90))
    kw, n = 1e-13, 100_000
    fixed = [
        _final(
            simulate_wear(
                contact=model,
                cycles=n,
                snapshots=[],
                settings=WearSettings(kw=kw, scheme="fixed", dn=dn),
            )
        )
        for dn in (2000, 1000)
    ]
    adaptive = [
        _final(
            simulate_wear(
                contact=model, cycles=n, snapshots=[], settings=WearSettings(kw=kw, tol=tol)
            )
        )
        for tol in (0.1, 0.05)
    ]
    for (d1, v1), (d2, v2) in (fixed, adaptive):
        assert abs(d1 / d2 - 1) < 0.03
        assert abs(v1 / v2 - 1) < 0.03
    # and the adaptive result agrees with the fixed one
    assert abs(adaptive[0][0] / fixed[1][0] - 1) < 0.03


def test_too_large_fixed_interval_is_unstable_and_the_adaptive_scheme_avoids_it():
    grid = BearingGrid(4, 200)
    model = WinklerContact(grid, load=20.0, load_angle_deg=90.0, foundation_modulus=1e11)
    kw, n = 1e-13, 100_000
    n_crit = model.critical_cycles(kw)  # 5000 cycles: explicit updates diverge above 2 n_crit
    assert n_crit == pytest.approx(5000)
    ref = simulate_wear(
        contact=model, cycles=n, snapshots=[], settings=WearSettings(kw=kw, scheme="fixed", dn=250)
    )
    big = simulate_wear(
        contact=model,
        cycles=n,
        snapshots=[],
        settings=WearSettings(kw=kw, scheme="fixed", dn=int(4 * n_crit)),
    )
    ada = simulate_wear(
        contact=model,
        cycles=n,
        snapshots=[],
        settings=WearSettings(kw=kw, dn=int(4 * n_crit), tol=0.1),
    )
    h_ref = ref["wear_depth"].values[-1]
    h_big = big["wear_depth"].values[-1]
    h_ada = ada["wear_depth"].values[-1]
    # fixed 4 n_crit: the rate field flips at every update and the profile zig-zags
    assert np.all(big["update_rate_change"].values > 1.0)
    assert roughness(h_big) > 4 * roughness(h_ref)
    assert "too large to resolve the profile feedback" in big.attrs["convergence_warning"]
    assert "convergence_warning" not in ada.attrs and "convergence_warning" not in ref.attrs
    # adaptive: rejects the oversize interval, stays smooth and converged
    assert int((ada["update_accepted"] == 0).sum()) >= 1
    acc = ada["update_accepted"].values == 1
    assert np.all(ada["update_rate_change"].values[acc] <= 0.3)
    assert roughness(h_ada) < 1.5 * roughness(h_ref)
    assert abs(float(ada["max_wear_depth"][-1]) / float(ref["max_wear_depth"][-1]) - 1) < 0.03
    assert np.max(np.abs(h_ada - h_ref)) < 0.05 * np.max(h_ref)


def test_wear_map_is_invariant_to_the_grid():
    kw, n = 1e-13, 50_000
    out = []
    for grid in (BearingGrid(20, 200), BearingGrid(40, 400)):
        ds = simulate_wear(
            contact=swept_winkler(grid=grid), cycles=n, snapshots=[], settings=WearSettings(kw=kw)
        )
        out.append(_final(ds))
    (d1, v1), (d2, v2) = out
    assert abs(d1 / d2 - 1) < 0.05
    assert abs(v1 / v2 - 1) < 0.05


class NoisyContact:
    """Constant contact times a random factor per cycle from a generator carried in ``state``."""

    def __init__(self, grid):
        self.grid = grid
        self.calls = 0

    def describe(self):
        return {"model": "noisy"}

    def run(self, wear_depth, *, cycles, state, progress=None):
        self.calls += 1
        rng = np.random.default_rng(7)
        if state is not None:
            rng.bit_generator.state = state
        p = 1e6 * (1 + 0.02 * rng.standard_normal(self.grid.shape)) * np.exp(-wear_depth / 1e-6)
        w = p * 0.02 * cycles
        area = self.grid.point_area
        return CycleWear(w, area, float(np.sum(w * area)), rng.bit_generator.state, cycles)


def test_resume_after_interrupt_gives_identical_arrays(tmp_path, interrupt_after):
    settings = WearSettings(kw=1e-14, tol=0.1)
    full = WearRun(NoisyContact(GRID), settings, cycles=30_000).run()

    ckpt = tmp_path / "run.ckpt"
    stop = interrupt_after(5)
    run = WearRun(NoisyContact(GRID), settings, cycles=30_000, checkpoint=ckpt, on_update=stop)
    with pytest.raises(KeyboardInterrupt):
        run.run()
    partial = run.to_dataset()
    conventions.validate(partial)
    assert partial.attrs["status"] == "partial"
    assert 0 < run.cycles_done < 30_000
    assert float(partial["cycles"][-1]) == run.cycles_done

    resumed = WearRun.resume(ckpt, NoisyContact(GRID), settings, cycles=30_000).run()
    assert resumed.attrs["status"] == "complete"
    for name in ("wear_depth", "worn_volume", "normal_work", "update_dn", "update_rate_change"):
        np.testing.assert_array_equal(resumed[name].values, full[name].values)
    np.testing.assert_array_equal(resumed["cycles"].values, full["cycles"].values)
    assert resumed.attrs["cycles_simulated"] == full.attrs["cycles_simulated"]


def test_resume_refuses_other_parameters_and_lower_targets(tmp_path):
    ckpt = tmp_path / "w.ckpt"
    model = swept_winkler()
    WearRun(model, WearSettings(kw=1e-13), cycles=5000, checkpoint=ckpt).run()
    with pytest.raises(BadInputError, match=r"wear\.kw: 1e-13 in the checkpoint, 2e-13 now"):
        WearRun.resume(ckpt, model, WearSettings(kw=2e-13), cycles=5000)
    with pytest.raises(BadInputError, match=r"contact\.clearance"):
        WearRun.resume(ckpt, swept_winkler(clearance=0.4e-3), WearSettings(kw=1e-13), cycles=5000)
    with pytest.raises(BadInputError, match="below the 5000 cycles already done"):
        WearRun.resume(ckpt, model, WearSettings(kw=1e-13), cycles=1000)
    with pytest.raises(BadInputError, match="does not exist"):
        WearRun.resume(tmp_path / "nope.ckpt", model, WearSettings(kw=1e-13), cycles=5000)
    (tmp_path / "junk.ckpt").write_bytes(b"not a pickle")
    with pytest.raises(BadInputError, match="could not be read"):
        WearRun.resume(tmp_path / "junk.ckpt", model, WearSettings(kw=1e-13), cycles=5000)
    # extending a finished run continues from where it stopped
    more = WearRun.resume(ckpt, model, WearSettings(kw=1e-13), cycles=8000).run()
    assert more.attrs["cycles_done"] == 8000
    assert 5000 in more["cycles"].values


@pytest.mark.parametrize(
    ("kw", "match"),
    [
        (-1e-14, "must be a positive number"),
        (0.0, "must be a positive number"),
        (float("nan"), "must be a positive number"),
        (5.05e-10, "absurd.*cannot be SI"),
        (1e-25, "absurdly small"),
    ],
)
def test_bad_kw_is_refused(kw, match):
    with pytest.raises(ParameterError, match=match):
        WearSettings(kw=kw)


@pytest.mark.parametrize(
    ("model", "name", "value"),
    [
        ("ConstantContact", "sliding", 0.0),
        ("WinklerContact", "sliding", float("inf")),
        ("WinklerContact", "clearance", -1e-4),
        ("WinklerContact", "foundation_modulus", float("nan")),
    ],
)
def test_contact_models_refuse_a_non_positive_length_or_modulus(model, name, value):
    cls = {"ConstantContact": ConstantContact, "WinklerContact": WinklerContact}[model]
    with pytest.raises(ParameterError, match=rf"{model}\.{name} must be a positive finite number"):
        cls(GRID, **{name: value})


def test_bad_settings_and_targets():
    # the Literal field's check (params.check_fields), as for every parameter dataclass
    with pytest.raises(
        ParameterError,
        match=r"^wear\.scheme: expected one of \['adaptive', 'fixed', 'schedule'\], got 'implicit'$",
    ):
        WearSettings(scheme="implicit")
    with pytest.raises(ParameterError, match="needs a non-empty wear.schedule"):
        WearSettings(scheme="schedule")
    with pytest.raises(ParameterError, match="whole numbers of cycles >= 1"):
        WearSettings(scheme="schedule", schedule=(10, 0))
    with pytest.raises(ParameterError, match="dn_min = 10 exceeds"):
        WearSettings(dn_min=10, dn_max=5)
    with pytest.raises(ParameterError, match=r"wear\.tol must be in \(0, 1\)"):
        WearSettings(tol=2.0)
    model = ConstantContact(GRID)
    with pytest.raises(BadInputError, match="whole number >= 1"):
        WearRun(model, cycles=-5)
    with pytest.raises(BadInputError, match="snapshot 2000.0 must be"):
        WearRun(model, cycles=1000, snapshots=[2000])
    with pytest.raises(BadInputError, match=r"initial_wear has shape \(3, 3\)"):
        WearRun(model, cycles=10, initial_wear=np.zeros((3, 3)))
    with pytest.raises(BadInputError, match="not writable"):
        WearRun(model, cycles=10, checkpoint="/proc/no/such/dir/x.ckpt")


def test_max_increment_caps_the_depth_step():
    model = ConstantContact(GRID, pressure=1e6, sliding=0.02)
    st = WearSettings(kw=1e-14, scheme="fixed", dn=10_000, max_increment=1e-7)
    ds = simulate_wear(contact=model, cycles=20_000, snapshots=[], settings=st)
    rate = 1e-14 * 1e6 * 0.02
    assert np.all(ds["update_dn"].values * rate <= 1e-7 * (1 + 1e-12))
    assert float(ds["max_wear_depth"][-1]) == pytest.approx(20_000 * rate, rel=1e-12)


@settings(max_examples=25, deadline=None)
@given(
    dn=st.integers(1, 5000),
    target=st.integers(1, 20_000),
    snaps=st.lists(st.integers(1, 20_000), max_size=4),
)
def test_closed_form_holds_for_any_interval_and_snapshots(dn, target, snaps):
    model = ConstantContact(BearingGrid(3, 8), pressure=2e6, sliding=0.01)
    snaps = [s for s in snaps if s <= target]
    ds = simulate_wear(
        contact=model,
        cycles=target,
        snapshots=snaps,
        settings=WearSettings(kw=1e-14, scheme="fixed", dn=dn),
    )
    expected_cycles = sorted(set(snaps) | {target})
    np.testing.assert_array_equal(ds["cycles"].values, expected_cycles)
    np.testing.assert_allclose(
        ds["max_wear_depth"].values, np.array(expected_cycles) * 1e-14 * 2e6 * 0.01, rtol=1e-12
    )
