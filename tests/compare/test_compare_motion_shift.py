"""The motion alignment's shift is a reported quantity with its u; the history criterion states
what it can detect."""

from __future__ import annotations

import _jw_synth as syn
import numpy as np
import pytest

from jointwear.compare import compare

TRUE_SHIFT = ((0.3 - 1.7) / syn.OMEGA + syn.PERIOD / 2) % syn.PERIOD - syn.PERIOD / 2


@pytest.mark.parametrize("with_crank", [True, False])
def test_shift_reported_with_its_u_and_covers_the_truth(with_crank):
    c = compare(syn.sim_motion(), syn.meas_motion(with_crank=with_crank))
    shift = c.value("motion_alignment", "time_shift")
    u = c.value("motion_alignment", "time_shift_u")
    assert 0 < u < 0.02 * syn.PERIOD
    assert abs(shift - TRUE_SHIFT) <= 2 * u
    assert c.value("motion_alignment", "phase_shift") == pytest.approx(shift / syn.PERIOD * 360.0)
    basis = c.metrics.set_index(["quantity", "metric"]).loc[
        ("motion_alignment", "time_shift"), "basis"
    ]
    assert ("clock offset" in basis) if with_crank else ("not judged" in basis)


def test_history_criterion_states_its_closed_form_resolution():
    """C <= 0.3: a pure amplitude error of 29 % passes, 31 % fails - as the card says."""
    sim = syn.sim_motion()
    rows = {}
    for a in (1.29, 1.31):
        c = compare(sim, syn.meas_motion(scale=1 / a))
        d = c.decisions[c.decisions.quantity == "follower velocity x history"].iloc[0]
        rows[a] = d
    assert rows[1.29].state == "pass" and rows[1.31].state == "fail"
    assert "amplitude error beyond ±30%" in rows[1.29].resolution
    assert np.isfinite(c.value("motion_alignment", "time_shift_u"))
