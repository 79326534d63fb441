"""``jointwear report`` on a foreign (non-jointwear) CF netCDF file says so like ``compare``: one
plain ``warning:`` line on stderr, not a Python ``UserWarning`` with a file:line prefix."""

from __future__ import annotations

import warnings

import _jw_synth as syn

from jointwear.cli import main


def _foreign_wear(path):
    ds = syn.meas_wear(u=1e-6, scale=1.1)  # contract names, units and angle convention stated
    ds.attrs["source"] = "CMM export"
    ds.to_netcdf(path)  # no jointwear provenance: another tool's file


def _stderr_of(capsys, args):
    capsys.readouterr()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        code = main([str(a) for a in args])
    return code, capsys.readouterr().err, [str(w.message) for w in caught]


def test_report_warns_about_a_foreign_file_in_one_plain_line_like_compare(
    tmp_path, capsys, report_files
):
    foreign = tmp_path / "cmm.nc"
    _foreign_wear(foreign)
    sim = report_files["sim_wear"]

    code, err, caught = _stderr_of(
        capsys, ["report", "--sim", sim, "--metrology", foreign, "--out", tmp_path / "r.html"]
    )
    assert code in (0, 1)
    assert (tmp_path / "r.html").is_file()
    lines = [ln for ln in err.splitlines() if "not written by jointwear" in ln]
    assert len(lines) == 1 and lines[0].startswith(f"warning: '{foreign}' was not written")
    assert "UserWarning" not in err and "builder.py" not in err
    assert not [m for m in caught if "not written by jointwear" in m]

    code, err_compare, _ = _stderr_of(capsys, ["compare", sim, foreign, "--out", tmp_path / "m.nc"])
    assert code in (0, 1)
    assert [ln for ln in err_compare.splitlines() if "not written by jointwear" in ln] == lines
