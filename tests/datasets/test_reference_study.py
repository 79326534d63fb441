"""The reference study's reported values against the default rig, end to end at reduced size.

The full size runs in ``benchmarks/bench_reported.py``; its verdicts are quoted in
docs/compare-report.md. Here: ``jointwear datasets reference-study --reduced`` (verification
study and ensemble), the documented command chain, and the library call without an ensemble,
each printing the verdict per reported quantity (``pytest -s``).
"""

from __future__ import annotations

import numpy as np
import pytest

import jointwear.compare.verdicts as vd
from jointwear import io
from jointwear.cli import main
from jointwear.compare import load_comparison
from jointwear.compare.outcome import card_lines
from jointwear.datasets.reference_study import reference_file

QUANTITIES = (
    "cylindricity_new",
    "cylindricity_4e5",
    "cylindricity_1_2e6",
    "max_wear_angle_first_4e5",
    "max_wear_angle_first_1_2e6",
    "max_wear_angle_last_1_2e6",
    # derived: the angle between the two layers' maxima, free of the unstated conventions
    "angle_between_max_wear_angle_first_1_2e6_and_max_wear_angle_last_1_2e6",
)


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    """``jointwear datasets reference-study --reduced``, run once; its saved comparison."""
    import contextlib
    import io as _io

    out = tmp_path_factory.mktemp("reference") / "study"
    printed = _io.StringIO()
    with contextlib.redirect_stdout(printed):
        code = main(["datasets", "reference-study", str(out), "--reduced"])
    result = load_comparison(io.load(out / "metrics.nc"))
    calibrated = load_comparison(io.load(out / "metrics_calibrated.nc"))
    assert code == (1 if result.any_failed or calibrated.any_failed else 0)
    _PRINTED.append(printed.getvalue())
    return out, result


_PRINTED: list[str] = []  # what the command printed (its default output)


@pytest.mark.slow
def test_the_default_output_has_at_most_three_lines_per_criterion(study):
    _, result = study
    lines = _PRINTED[0].splitlines()
    head = next(i for i, ln in enumerate(lines) if ln.startswith("calibrated on the 4e5"))
    lines, calibration = lines[:head], lines[head + 1 :]
    card = [ln for ln in lines if not ln.startswith(("unstated:", "to decide them", "note:"))][:-1]
    blocks: list[list[str]] = []
    for line in card:
        (blocks[-1].append(line) if line.startswith(" ") else blocks.append([line]))
    assert len(blocks) == len(result.decisions) and all(len(b) <= 3 for b in blocks)
    assert not any("layers centred at z" in ln for ln in lines)  # the readings: --verbose
    n = len(result.decisions) - 1  # the new bore is the baseline, not a criterion
    assert lines[-1 - sum(ln.startswith("note:") for ln in lines)].startswith(f"{n} criteria: ")
    # then the calibrate -> validate block: one line per input, the 1.2e6 verdict in <= 3 lines
    assert calibration[0].startswith("CALIBRATED") and "wear.kw" in calibration[0]
    assert calibration[1].startswith("NOT INFORMED") and "joint.tilt_stiffness" in calibration[1]
    verdict = calibration[2:]
    assert "cylindricity_1_2e6" in verdict[0] and len(verdict) <= 3
    assert "growth ratio 4e5/1.2e6: measured 0.68" in verdict[1]


@pytest.mark.slow
def test_without_the_ensemble_no_criterion_passes_or_fails(study):
    """The library's comparison of the command's own files (its simulation, verification study
    and the reported values; deterministic) without the ensemble: u_input is then not assessed,
    so no criterion can pass or fail by V&V 20, and the same quantities are decided."""
    from jointwear.compare import compare

    out, saved = study
    again = compare(
        io.load(out / "sim_wear.nc"),
        io.load(out / "reported.nc"),
        verification=[io.load(out / "verification.nc", validate=False)],
    )
    assert not (again.states == vd.PASS).any() and not again.any_failed
    assert set(again.decisions.key) == set(saved.decisions.key)
    # the difference is the ensemble's: u_input assessed by the command, not here
    for result, finite in ((saved, True), (again, False)):
        m = result.metrics
        u_input = m[(m.quantity == "cylindricity_1_2e6") & (m.metric == "u_input")]
        assert bool(np.isfinite(u_input.value).all()) is finite and len(u_input) == 1


@pytest.mark.slow
def test_library_run_decides_every_reported_quantity(study):
    out, result = study
    print("\n".join(card_lines(result)))  # the verdict per quantity (pytest -s)
    assert set(result.decisions.key) == set(QUANTITIES)
    assert set(result.decisions.state) <= set(vd.STATES)
    new = result.decisions[result.decisions.key == "cylindricity_new"].iloc[0]
    assert new.state == vd.NOT_COMPARABLE and "baseline" in new.reason
    # the measured side is the paper's growth, 33.34 - 5.02 and 46.57 - 5.02 um
    assert result.value("cylindricity_4e5", "value_meas") == pytest.approx(28.32e-6)
    assert result.value("cylindricity_1_2e6", "value_meas") == pytest.approx(41.55e-6)
    # u_input from the ensemble's maps, u_D from the paper's figures and the new bore's form
    m = result.metrics.set_index(["quantity", "metric"])
    assert "ensemble" in m.loc[("cylindricity_1_2e6", "u_input"), "basis"]
    assert np.isfinite(m.loc[("cylindricity_1_2e6", "u_input"), "value"])
    floor = np.sqrt(2 * ((0.03 / np.sqrt(3)) ** 2 + (0.01 / np.sqrt(12)) ** 2) + 5.02**2 / 3)
    u_d = m.loc[("cylindricity_1_2e6", "u_D"), "value"] * 1e6
    assert floor <= u_d <= floor + 2.0  # plus the LS/MZ half-difference of the simulated bore
    # the angles: the paper leaves their direction and the layer order unstated
    assert any("angle.direction, layers.first, layers.z_centre" in n for n in result.notes)
    back = load_comparison(io.load(out / "metrics.nc"))
    assert list(back.decisions.state) == list(result.decisions.state)
    assert io.load(out / "reported.nc").attrs["data_origin"] == "measured"


@pytest.mark.slow
def test_documented_command_chain(study, tmp_path, capsys):
    folder, _ = study
    toml, rep, sim = tmp_path / "zhang2023.toml", tmp_path / "reported.nc", tmp_path / "sim.nc"
    assert main(["datasets", "reported", str(toml)]) == 0
    assert toml.read_text() == reference_file().read_text()
    assert main(["import", "reported", str(toml), "--out", str(rep)]) == 0
    args = ["sim", "wear", "--cycles", "1.2e6", "--snapshots", "4e5,1.2e6", "--scheme", "fixed"]
    args += [
        "--dn",
        "400000",
        "--layers",
        "8",
        "--points",
        "72",
        "--out",
        str(sim),
        "--no-progress",
    ]
    assert main(args) == 0
    capsys.readouterr()
    code = main(
        ["compare", str(sim), str(rep), "--out", str(tmp_path / "metrics.nc")]
        + [
            "--ensemble",
            str(folder / "ensemble.nc"),
            "--verification",
            str(folder / "verification.nc"),
        ]
    )
    printed = capsys.readouterr().out
    print(printed)
    for name in QUANTITIES:
        assert name in printed
    assert code == (1 if "FAIL  " in printed else 0)
    assert "data origin: simulation simulated, measurement measured" in printed
