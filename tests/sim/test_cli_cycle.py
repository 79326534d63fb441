"""``jointwear sim cycle`` end to end."""

from __future__ import annotations

import numpy as np

from jointwear import io
from jointwear.cli import main


def test_cycle_writes_record_with_parameters(tmp_path, capsys):
    params = tmp_path / "p.toml"
    params.write_text("[solver]\noutput_interval = 1e-3\n[joint]\nn_layers = 10\n")
    out = tmp_path / "cycle.nc"
    code = main(["sim", "cycle", "--cycles", "0.1", "--out", str(out), "--params", str(params)])
    assert code == 0, capsys.readouterr().err
    assert "cycle.nc" in capsys.readouterr().out
    ds = io.load(out)
    assert ds.sizes["time"] == 51
    assert np.isfinite(ds.contact_force.values).all()
    prov = io.parse_provenance(ds)
    assert prov["parameters"]["joint"]["n_layers"] == 10
    assert prov["parameters"]["solver"]["output_interval"] == 1e-3
    assert any(str(params) in str(i) for i in prov["inputs"])
    assert ds.attrs["source"].endswith("(sim.dynamics)")


def test_cycle_bad_parameter_exit_code(tmp_path, capsys):
    params = tmp_path / "p.toml"
    params.write_text("[joint]\njournal_radius = 9e-3\n")
    code = main(["sim", "cycle", "--out", str(tmp_path / "x.nc"), "--params", str(params)])
    assert code == 3
    err = capsys.readouterr().err
    assert "joint.journal_radius" in err and "smaller than" in err
    assert not (tmp_path / "x.nc").exists()


def test_cycle_failure_keeps_partial(tmp_path, capsys):
    params = tmp_path / "p.toml"
    params.write_text("[contact]\nmax_penetration_fraction = 0.01\n")
    out = tmp_path / "x.nc"
    code = main(["sim", "cycle", "--out", str(out), "--params", str(params)])
    assert code == 3
    err = capsys.readouterr().err
    assert "crank angle" in err and "x.partial.nc" in err
    assert not out.exists()
    assert io.load(tmp_path / "x.partial.nc").sizes["time"] > 0
