"""``jointwear report --reported``: reported measurements alone make a report."""

from __future__ import annotations

import sys
from pathlib import Path

from jointwear import io
from jointwear.cli import main
from jointwear.reported import reported_dataset

sys.path.insert(0, str(Path(__file__).parents[1] / "compare"))

from test_compare_reported import cyl_file, sim_map  # noqa: E402


def test_report_with_reported_measurements_only(tmp_path, capsys):
    sim = io.save(sim_map(), tmp_path / "sim.nc")
    rep = io.save(reported_dataset(cyl_file()), tmp_path / "reported.nc")
    crit = tmp_path / "criteria.toml"
    crit.write_text("wear_u_num_rel = 0.05\nwear_u_input_rel = 0.05\n")
    out = tmp_path / "report.html"
    code = main(
        ["report", "--sim", str(sim), "--reported", str(rep), "--criteria", str(crit)]
        + ["--out", str(out)]
    )
    printed = capsys.readouterr().out
    assert code == 0, printed
    html = out.read_text()
    assert "cylindricity growth since new" in html and "cyl_new" in html
    assert "PASS" in printed and "NOT COMPARABLE" in printed  # the growth; the new bore
    # the measured side is the reported file, data origin stated by it
    assert "measurement synthetic" in printed


def test_report_refuses_without_any_measurement(tmp_path, capsys):
    sim = io.save(sim_map(), tmp_path / "sim.nc")
    assert main(["report", "--sim", str(sim), "--out", str(tmp_path / "r.html")]) == 3
    assert "--reported FILE.nc" in capsys.readouterr().err
