"""Power with the calibrate-then-validate path (issue 36 item 5), at reduced size.

The reference truth is scanned at 2e5 and 4e5 cycles; each candidate's kw is calibrated on the
2e5 map with ``jointwear.sim.calibrate`` (kw uniform ±50 % around the candidate's own), the
posterior prediction at 4e5 is compared with the 4e5 map. Asserted: the right model passes and
its posterior holds the true kw; kw × 1.5 is absorbed (its posterior returns to the truth's
kw); joint offset 0 is still detected (refused at calibration by the predictive check, or a
failed criterion); a refused calibration is never counted as a pass or a criterion fail. The
figures on the tilt truth with every graded error come from
``benchmarks/bench_validation_power.py --with-calibration``.
"""

from __future__ import annotations

import logging
from types import SimpleNamespace

import pandas as pd
import pytest

from jointwear.compare.calibration_use import posterior_note
from jointwear.reports import power_calibrated as pc
from jointwear.reports.power import CALIBRATED_POWER, power_paragraph


def _rep(calibration: str, states: dict[str, str] | None = None) -> dict:
    if states is None:
        return {"calibration": calibration, "outcome": None}
    n_fail = sum(s == "fail" for s in states.values())
    return {"calibration": calibration, "outcome": {"states": states, "n_fail": n_fail}}


def test_refused_calibration_is_its_own_outcome_never_a_pass_or_a_criterion_fail():
    reps = [
        _rep("refused_ppc"),
        _rep("refused_other"),
        _rep("ok", {"wear field": "fail", "maximum wear depth": "pass"}),
        _rep("ok", {"wear field": "pass", "maximum wear depth": "pass"}),
    ]
    r = pc.calibrated_rates(reps)
    assert r["replicates"] == 4 and r["validated"] == 2
    assert r["refused_at_calibration"] == 0.25  # the predictive check: the model cannot fit
    assert r["not_decided"] == 0.25  # emulator or chain: neither detection nor pass
    assert r["any_fail"] == 0.25 and r["detected"] == 0.5
    assert r["fail_rate"] == {"maximum wear depth": 0.0, "wear field": 0.25}


def test_refusal_kind_from_the_calibration_message():
    from jointwear.sim.calibrate import CalibrationRefused

    ppc = CalibrationRefused("posterior predictive check failed for worn_volume of a.nc: ...")
    emu = CalibrationRefused("the emulator's cross-validated error of worn_volume is 2e-12 ...")
    assert pc._refusal(ppc) == "refused_ppc"
    assert pc._refusal(emu) == "refused_other"


def test_spec_and_rig_files_read_back_as_the_command_reads_them(tmp_path):
    from jointwear.sim import WearSettings, load_parameters
    from jointwear.sim.calibrate import read_calibration_spec

    data = tmp_path / "early.nc"
    data.write_bytes(b"")  # the spec reader checks that the file exists
    path = tmp_path / "calibrate.toml"
    path.write_text(pc._spec_toml(data, pc.CAL_BENCH_SIZE, 2e-15, 0.04))
    spec = read_calibration_spec(path)
    (kw,) = spec.parameters
    assert kw.name == "wear.kw" and kw.bounds == pytest.approx((1e-15, 3e-15))
    assert spec.samples == pc.CAL_BENCH_SIZE.training_runs and spec.u_num_rel == 0.04
    assert spec.cycles == (2e5,) and spec.seed == 0  # the command's default seed
    over = {"joint.tilt_stiffness": 1000.0, "mechanism.initial_crank_angle_deg": 37.0}
    text = pc._rig_toml(over, pc.CAL_BENCH_SIZE.base, 4, WearSettings(scheme="fixed", dn=25000))
    rig = tmp_path / "rig.toml"
    rig.write_text(text)
    p = load_parameters(rig)
    assert p.joint.tilt_stiffness == 1000.0 and p.mechanism.initial_crank_angle_deg == 37.0
    assert (p.joint.n_layers, p.joint.n_points) == (10, 40)
    assert 'scheme = "fixed"' in text and "dn = 25000" in text


def test_power_paragraph_names_the_calibrated_figure_only_for_a_posterior():
    decisions = pd.DataFrame(
        {"quantity": ["maximum wear depth"], "state": ["pass"], "resolution": ["detects ±6 %"]}
    )
    plain = SimpleNamespace(decisions=decisions, notes=())
    assert CALIBRATED_POWER not in power_paragraph(plain)
    posterior = SimpleNamespace(decisions=decisions, notes=(posterior_note(["prediction.nc"]),))
    assert power_paragraph(posterior).endswith(CALIBRATED_POWER)
    # the demo states it in the report's notes ("The simulation compared is the posterior ...")
    demo = "The simulation compared is the posterior prediction (prediction.nc: 4 simulations)"
    assert power_paragraph(plain, [demo]).endswith(CALIBRATED_POWER)


@pytest.fixture(scope="module")
def calibrated(tmp_path_factory):
    logging.disable(logging.WARNING)
    folder = tmp_path_factory.mktemp("power_calibrated")
    try:
        result = pc.run_power_calibrated(pc.CAL_CI_SIZE, folder=folder)
    finally:
        logging.disable(logging.NOTSET)
    return result, folder


@pytest.mark.slow
def test_calibration_absorbs_kw_and_keeps_a_wrong_offset_detected(calibrated):
    result, _ = calibrated
    cands = result["truths"]["default"]["candidates"]
    right = cands["right"]["with_calibration"]
    assert right["validated"] == right["replicates"] == 2, right["replicates_detail"]
    assert right["any_fail"] == 0.0, right["replicates_detail"]
    for rep in right["replicates_detail"]:
        kw = rep["kw_over_truth"]
        assert kw["q025"] <= 1.0 <= kw["q975"], kw
    # kw x 1.5 is absorbed by design: the posterior returns to the truth's kw, and it passes
    kw15 = cands["kw x 1.5"]["with_calibration"]
    (rep,) = kw15["replicates_detail"]
    assert rep["calibration"] == "ok", rep
    assert rep["kw_over_truth"]["q025"] <= 1.0 <= rep["kw_over_truth"]["q975"]
    assert kw15["any_fail"] == 0.0
    # a non-kw error is still seen: refused by the predictive check, or a failed criterion
    offset = cands["joint offset 0"]
    assert offset["with_calibration"]["detected"] == 1.0, offset["with_calibration"]


@pytest.mark.slow
def test_the_calibrated_comparison_says_it_used_a_posterior(calibrated):
    from jointwear.compare import load_comparison

    _, folder = calibrated
    (metrics,) = folder.glob("default_*/calibrated_*/right/metrics_0.nc")
    c = load_comparison(metrics)
    assert any("posterior prediction prediction_0.nc" in n for n in c.notes), c.notes
    assert power_paragraph(c).endswith(CALIBRATED_POWER)
