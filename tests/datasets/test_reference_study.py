"""The reference study's reported values against the default rig, end to end at reduced size.

The full size runs in ``benchmarks/bench_reported.py``; its verdicts are quoted in
docs/compare-report.md. Here: the documented command chain (CLI) and the library run with a
verification study and an ensemble, each printing the verdict per reported quantity.
"""

from __future__ import annotations

import numpy as np
import pytest

import jointwear.compare.verdicts as vd
from jointwear import io
from jointwear.cli import main
from jointwear.compare import load_comparison
from jointwear.compare.outcome import card_lines
from jointwear.datasets.reference_study import REDUCED, reference_file, run_reference_study

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
    out = tmp_path_factory.mktemp("reference")
    return out, run_reference_study(out, REDUCED)


@pytest.mark.slow
def test_reference_study_command(study, tmp_path, capsys):
    """``jointwear datasets reference-study --reduced`` gives the library's verdicts."""
    _, result = study
    code = main(["datasets", "reference-study", str(tmp_path / "r"), "--reduced"])
    printed = capsys.readouterr().out
    print(printed)
    assert code == (1 if result.any_failed else 0)
    back = load_comparison(io.load(tmp_path / "r" / "metrics.nc"))
    assert list(back.decisions.state) == list(result.decisions.state)  # deterministic
    assert result.summary() in printed


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
