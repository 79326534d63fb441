"""The resolution of a V&V 20 criterion: the smallest relative error it detects, both ways."""

from __future__ import annotations

import math

import _jw_synth as syn
import numpy as np
import pytest

from jointwear.compare import Criteria, compare
from jointwear.compare._decide import resolution_text
from jointwear.compare.metrics import detectable_error, vv20


def test_detectable_error_of_a_hand_computed_budget():
    """D = 10, S = 11, u_num 0.5 and u_D 0.3 fixed, u_input 10 % of S, k = 2.

    By hand: alpha = 2 sqrt(0.34) / 10, beta = 0.2; (1 - beta^2) e^2 - 2 beta^2 e -
    (alpha^2 + beta^2) = 0 -> 0.96 e^2 - 0.08 e - 0.0536 = 0 -> e = (0.08 ± 0.46068) / 1.92.
    """
    low, high = detectable_error(10.0, 11.0, u_fixed=math.sqrt(0.34), u_relative=1.1, k=2.0)
    assert low == pytest.approx((0.08 - math.sqrt(0.0064 + 4 * 0.96 * 0.0536)) / 1.92)
    assert high == pytest.approx((0.08 + math.sqrt(0.0064 + 4 * 0.96 * 0.0536)) / 1.92)
    assert (low, high) == pytest.approx((-0.19827, 0.28160), abs=1e-5)
    # at S' = D (1 + e), with u_input rescaled to 10 % of S', |E| is U_val exactly
    for e in (low, high):
        s = 10.0 * (1 + e)
        res = vv20(s, 10.0, u_num=0.5, u_input=0.1 * abs(s), u_d=0.3, k=2.0)
        assert abs(res.E) == pytest.approx(res.U_val)
    # a fixed budget is symmetric; a relative part makes it asymmetric (over-predictions carry
    # more uncertainty): the band the wrong "only errors above about 45 % fail" sentence missed
    assert detectable_error(10.0, 10.0, u_fixed=1.0, u_relative=0.0, k=2.0) == pytest.approx(
        (-0.2, 0.2)
    )


def test_undetectable_directions():
    # u_D alone larger than |D| / k: no under-prediction down to S = 0 fails
    low, high = detectable_error(10.0, 10.0, u_fixed=6.0, u_relative=0.0, k=2.0)
    assert low == -math.inf and high == pytest.approx(1.2)
    # u_input 60 % of S with k = 2: U_val grows faster than |E|, no over-prediction fails
    low, high = detectable_error(10.0, 10.0, u_fixed=1.0, u_relative=6.0, k=2.0)
    assert high == math.inf and -1 < low < 0
    res = vv20(10 * (1 + low), 10.0, u_input=0.6 * 10 * (1 + low), u_d=1.0, k=2.0)
    assert abs(res.E) == pytest.approx(res.U_val)
    assert "no over-prediction" in resolution_text(low, high)
    assert math.isnan(detectable_error(0.0, 1.0, u_fixed=1.0, u_relative=0.0, k=2.0)[0])


def _decided(scale: float):
    """A map compared with a measurement of the same field and a stated u_D; the simulated
    maximum ``scale`` times the measured one. u_num 5 % and u_input 10 % of S (relative)."""
    sim = syn.sim_wear()
    sim["wear_depth"] = sim["wear_depth"] * scale
    meas = syn.meas_wear(n_layers=16, u=0.6e-6)
    crit = Criteria(wear_u_num_rel=0.05, wear_u_input_rel=0.10)
    return compare(sim, meas, criteria=crit)


def test_resolution_in_metrics_card_and_summary_predicts_the_verdict(tmp_path):
    c = _decided(1.0)
    low = c.value("max_wear_depth", "detectable_error_low")
    high = c.value("max_wear_depth", "detectable_error_high")
    d, s = c.value("max_wear_depth", "value_meas"), c.value("max_wear_depth", "value_sim")
    u_d = c.value("max_wear_depth", "u_D")
    # the hand formula with the budget's fixed part (u_D) and relative part (u_num, u_input)
    rel = math.hypot(0.05, 0.10) * abs(s)
    assert (low, high) == pytest.approx(detectable_error(d, s, u_fixed=u_d, u_relative=rel, k=2))
    assert low < 0 < high and high > -low  # asymmetric: u_input is applied relative to S
    # the resolution predicts the verdict of a model that errs by just less / more
    ratio = s / d
    for e, state in ((high * 0.97, "pass"), (high * 1.03, "fail"), (low * 0.97, "pass")):
        assert _decided((1 + e) / ratio).state("maximum wear depth") == state
    assert _decided((1 + low * 1.03) / ratio).state("maximum wear depth") == "fail"
    # the card and the summary say it; metrics.nc stores it
    row = c.decisions[c.decisions.key == "max_wear_depth"].iloc[0]
    pct = f"{low * 100:+.0f} %".replace("-", "−")
    assert row.resolution.startswith("detects errors outside " + pct)
    assert "maximum wear depth" in c.resolution() and pct in c.resolution()
    ds = c.to_dataset()
    assert float(ds["max_wear_depth__detectable_error_high"]) == pytest.approx(high)
    assert ds["max_wear_depth__detectable_error_high"].attrs["units"] == "1"
    assert ds.attrs["resolution_summary"] == c.resolution()
    from jointwear.compare.storage import load_comparison

    again = load_comparison(ds)
    assert again.decisions.set_index("key").loc["max_wear_depth", "resolution"] == row.resolution


def test_not_assessed_criteria_state_no_resolution():
    c = compare(syn.sim_wear(), syn.meas_wear(n_layers=16))
    assert not np.any(c.metrics.metric == "detectable_error_low")
    assert "maximum wear depth" not in c.resolution()  # only the decided shape states one


def test_the_criteria_table_decides_the_wear_card_in_its_order():
    """compare.registry.CRITERIA is what decides: its wear rows, in order, are the card's."""
    from jointwear.compare.registry import CRITERIA, criteria_of

    c = _decided(1.0)
    wear = criteria_of("wear")
    assert [e.basis for e in wear] == list(c.decisions.basis)
    assert [e.name for e in wear if e.basis == "V&V 20"] == [
        k for k, b in zip(c.decisions.key, c.decisions.basis, strict=True) if b == "V&V 20"
    ]
    assert all(callable(e.decide) for e in CRITERIA)
