"""``jointwear demo --quick`` end to end: simulate, generate and import the measurement, report."""

from __future__ import annotations

import pytest
from test_report_html import EXPECTED_SECTIONS, parse  # noqa: I001

from jointwear import io
from jointwear.cli import main
from jointwear.compare import load_comparison
from jointwear.reports.demo import MEASURED_ROTATION_DEG, MEASURED_SCALE


@pytest.fixture(scope="module")
def demo_run(tmp_path_factory):
    import contextlib
    import io as _io

    out = tmp_path_factory.mktemp("demo")
    err = _io.StringIO()
    with contextlib.redirect_stderr(err):
        code = main(["demo", "--out", str(out), "--quick"])
    return out, code, err.getvalue()


def test_demo_quick_runs_end_to_end(demo_run):
    out, code, err = demo_run
    assert code == 0  # nothing failed; what could not be decided is said, not passed
    for k in range(1, 3):
        assert f"[{k}/2]" in err
    assert "in this process" in err  # --quick: no worker processes
    assert "ensemble skipped (--quick): u_input not assessed" in err
    # the wear run's accuracy is stated once, in its line; no noise-floor warning to act on
    assert "not held in" not in err and "max depth" in err and " µm (k = 2" in err
    report = out / "report.html"
    page = parse(report)
    assert page.h2 == EXPECTED_SECTIONS
    html = report.read_text(encoding="utf-8")
    assert "INCOMPLETE: no criterion failed" in html and "VALIDATED:" not in html
    # the generated scans stay synthetic through the importer into the decision card
    assert 'measurement: <strong class="origin-synthetic">synthetic</strong>' in html
    # the virtual scans cover +-6 mm, the simulated bearing wears most at its edge (-7.5 mm):
    # the wear criteria are decided within the band (u_input is not assessed with --quick) and
    # what lies outside is stated as extrapolation
    c = load_comparison(out / "metrics.nc")
    label = c.decisions.quantity[c.decisions.key == "max_wear_depth"].iloc[0]
    assert label == "maximum wear depth within z = −6…+6 mm"
    assert c.state("maximum wear depth") == "not_assessed"
    assert c.state("angle of maximum wear") in ("pass", "fail")
    assert c.value("wear_depth", "volume_fraction_compared") < 0.9
    assert c.value("validation_domain", "sim_global_max_z") < -6e-3
    assert any(n.startswith("validation domain") and "extrapolation" in n for n in c.notes)
    # every stage wrote a contract file with provenance
    for name in ("sim_wear.nc", "sim_motion.nc", "metrology_wear.nc", "metrics.nc"):
        ds = io.load(out / name)
        assert io.parse_provenance(ds)["software"]["jointwear"]
    # the instrument files were really written and imported
    for scan in ("talyrond_worn", "talyrond_before"):
        assert len(list((out / scan).glob("*.txt"))) == 13
    # the motion part is skipped in --quick and the report says so plainly
    assert "skipped with --quick" in html


def test_demo_recovers_the_imposed_difference(demo_run):
    out, _, _ = demo_run
    c = load_comparison(out / "metrics.nc")
    # the "measured" bearing is the simulated wear turned by +6 degree and 10 % deeper: the
    # location of the maximum moves by about -6 degree (72-point simulation grid: 5 degree
    # steps; the metrology reference fit and the extra lobe add a little)
    assert c.value("wear_depth", "max_angle_error") == pytest.approx(-MEASURED_ROTATION_DEG, abs=5)
    assert c.value("wear_depth", "pearson_r") > 0.6
    ratio = c.value("worn_volume", "value_meas") / c.value("worn_volume", "value_sim")
    assert 0.9 < ratio < 1.4 and MEASURED_SCALE == 1.10
