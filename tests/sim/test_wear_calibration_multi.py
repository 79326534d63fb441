"""kw against several snapshots at once, leave-one-out, and kw plus one geometry parameter.

Truth: synthetic snapshots generated with the simulator (a Winkler lining: the wear feeds back
on the pressure, so wear is not linear in kw) at a known kw and tilt.
"""

from __future__ import annotations

import numpy as np
import pytest

from jointwear.errors import BadInputError
from jointwear.sim import (
    BearingGrid,
    Measurement,
    WearSettings,
    WinklerContact,
    calibrate_kw_and_parameter,
    calibrate_kw_multi,
    simulate_wear,
)

GRID = BearingGrid(6, 72)
SNAPS = [10_000, 40_000]
KW_TRUE, TILT_TRUE = 2.0e-13, 3.0e-3


def model(tilt=TILT_TRUE):
    return WinklerContact(GRID, load=20.0, load_angle_deg=90.0, foundation_modulus=1e11, tilt=tilt)


def run(kw, tilt=TILT_TRUE):
    return simulate_wear(
        contact=model(tilt), cycles=SNAPS[-1], snapshots=SNAPS, settings=WearSettings(kw=kw)
    )


@pytest.fixture(scope="module")
def truth():
    return run(KW_TRUE)


def measured(truth, quantity="max_depth", scale=(1.0, 1.0)):
    var = {"max_depth": "max_wear_depth", "volume": "worn_volume"}[quantity]
    return [
        Measurement(quantity, c, float(truth[var].sel(cycles=c)) * f)
        for c, f in zip(SNAPS, scale, strict=True)
    ]


def test_recovers_a_known_kw_from_several_snapshots(truth):
    cal = calibrate_kw_multi(run(0.8e-13), measured(truth), resimulate=run)
    assert cal.kw == pytest.approx(KW_TRUE, rel=0.02)
    assert np.all(np.abs(cal.residuals) < 0.02)
    assert np.all(np.abs(cal.loo_errors) < 0.03)  # consistent data: each snapshot predicted
    assert cal.simulations >= 1
    assert np.all(np.array(cal.exponents) < 0.95)  # feedback: depth grows less than kw
    text = "\n".join(cal.report())
    assert "max_depth" in text and "at 10000 cycles" in text and "residual" in text


def test_inconsistent_snapshots_show_in_residuals_and_leave_one_out(truth):
    # the early snapshot 30 % deeper than the simulator can produce with the same kw
    cal = calibrate_kw_multi(run(KW_TRUE), measured(truth, scale=(1.3, 1.0)), resimulate=run)
    r = np.array(cal.residuals)
    assert r[0] < -0.05 and r[1] > 0.05  # no single kw fits both: residuals of opposite sign
    assert abs(cal.loo_errors[0]) > 0.2 and abs(cal.loo_errors[1]) > 0.2


def test_linear_estimate_without_resimulation(truth):
    cal = calibrate_kw_multi(run(KW_TRUE), measured(truth))
    assert cal.simulations == 0
    assert cal.kw == pytest.approx(KW_TRUE, rel=1e-6)
    one = calibrate_kw_multi(run(KW_TRUE), measured(truth)[:1])
    assert np.isnan(one.loo_errors[0])  # nothing left to fit: not assessed


def test_kw_and_tilt_together(truth):
    # the volume fixes kw (Winkler carries the load: volume = kw F s N), the depth the tilt
    data = [*measured(truth, "volume")[1:], *measured(truth, "max_depth")[1:]]
    only_kw = calibrate_kw_multi(run(KW_TRUE, tilt=0.0), data, resimulate=lambda k: run(k, 0.0))
    assert only_kw.rms_log_misfit > 0.03  # the wrong tilt: one parameter cannot fit both
    cal = calibrate_kw_and_parameter(
        run, data, parameter="tilt", bounds=(0.0, 6e-3), kw0=1e-13, xatol=5e-5
    )
    assert cal.parameter == "tilt"
    assert cal.parameter_value == pytest.approx(TILT_TRUE, abs=3e-4)
    assert cal.kw == pytest.approx(KW_TRUE, rel=0.03)
    assert cal.rms_log_misfit < 0.01 < only_kw.rms_log_misfit
    assert all(np.isnan(cal.loo_errors))  # as many parameters as data: not assessed


def test_bad_measurements_are_refused():
    with pytest.raises(BadInputError, match="must be positive"):
        Measurement("cylindricity", 4e5, -1e-6)
    with pytest.raises(BadInputError, match="quantity must be one of"):
        Measurement("roundness", 4e5, 1e-6)
    with pytest.raises(BadInputError, match="covers 0 .. 40000 cycles"):
        calibrate_kw_multi(run(KW_TRUE), [Measurement("max_depth", 1e6, 1e-5)])
