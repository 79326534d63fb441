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


def test_cycle_with_a_wear_map(tmp_path, capsys):
    import xarray as xr

    from jointwear.conventions import theta_coord, z_coord

    depth = xr.DataArray(
        np.full((5, 36), 20e-6),
        coords={
            "z": z_coord(np.linspace(-7.5e-3, 7.5e-3, 5)),
            "theta": theta_coord(np.arange(0, 360, 10.0)),
        },
        dims=("z", "theta"),
        attrs={"units": "m", "long_name": "wear depth"},
    )
    wear = tmp_path / "wear.nc"
    io.save(xr.Dataset({"wear_depth": depth}), wear)
    out = tmp_path / "worn.nc"
    code = main(["sim", "cycle", "--cycles", "0.1", "--out", str(out), "--wear", str(wear)])
    assert code == 0, capsys.readouterr().err
    ds = io.load(out)
    k = ds.contact_stiffness.values
    k0 = 3.5794574116e10
    assert np.allclose(k[k > 0] / k0, np.sqrt((8e-3 + 20e-6) / 8e-3), rtol=1e-6)
    assert any("wear.nc" in str(i) for i in io.parse_provenance(ds)["inputs"])
    bad = tmp_path / "bad.nc"
    io.save(xr.Dataset({"other": depth}), bad)
    assert main(["sim", "cycle", "--out", str(out), "--wear", str(bad), "--overwrite"]) == 3
    assert "has no 'wear_depth'" in capsys.readouterr().err
