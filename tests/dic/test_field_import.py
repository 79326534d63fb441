"""Importing VIC-3D CSV exports and DICe solution files as field datasets."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from jointwear import io
from jointwear.cli import main
from jointwear.datasets import speckle as sp
from jointwear.dic import measure_field, read_field, write_field_csv
from jointwear.errors import BadInputError

GT4 = Path(__file__).parent / "data" / "dice_gt4"

X = np.array([100.0, 120.0, 140.0])
Y = np.array([50.0, 50.0, 50.0])
POS = np.array([[-3.0, 1.0, 0.1], [0.0, 1.0, 0.2], [3.0, 1.0, 0.3]])  # mm
DISP = np.array([[0.01, -0.02, 0.003], [0.011, -0.021, 0.004], [0.0, 0.0, 0.0]])  # mm


def _vic(path, disp, sigma):
    rows = ['"x","y","u","v","sigma","X","Y","Z","U","V","W","exx"']
    for i in range(3):
        vals = [X[i], Y[i], 1.5, -0.5, sigma[i], *POS[i], *disp[i], 1e-4]
        rows.append(",".join(f"{v:.9g}" for v in vals))
    path.write_text("\n".join(rows) + "\n")


def test_vic3d_csv_files_become_a_field_in_metres(tmp_path):
    _vic(tmp_path / "spec_0000_0.csv", np.zeros((3, 3)), [0.01, 0.01, 0.01])
    _vic(tmp_path / "spec_0001_0.csv", DISP, [0.01, 0.012, -1.0])
    ds = read_field(str(tmp_path / "spec_*_0.csv"), format="vic3d-csv", length_unit="mm",
                    data_origin="measured")  # fmt: skip
    np.testing.assert_allclose(ds.position.values, POS * 1e-3)
    np.testing.assert_allclose(ds.displacement.values[1, :2], DISP[:2] * 1e-3)
    failed = ds.flag.attrs["flag_meanings"].split().index("failed_in_source")
    assert list(ds.flag.values[1]) == [0, 0, failed]  # sigma -1: VIC-3D did not solve it
    assert np.isnan(ds.displacement.values[1, 2]).all()
    assert np.isnan(ds.foreign_sigma.values[1, 2])
    assert np.isnan(ds.displacement_u.values).all()  # not assessed, never zero
    assert ds.foreign_sigma.values[1, 1] == pytest.approx(0.012)
    assert ds.attrs["data_origin"] == "measured"
    with pytest.raises(BadInputError, match="length_unit=None"):
        read_field(str(tmp_path / "spec_*_0.csv"), format="vic3d-csv", data_origin="measured")
    with pytest.raises(BadInputError, match="no column 'COORDINATE_X'"):
        read_field(tmp_path / "spec_0000_0.csv", format="dice", length_unit="mm",
                   data_origin="measured")  # fmt: skip


def test_dice_solution_files_and_mismatched_points(tmp_path):
    head = "***\n*** DICe solution\n***\nSUBSET_ID,COORDINATE_X,COORDINATE_Y,DISPLACEMENT_X,"
    head += "DISPLACEMENT_Y,SIGMA,GAMMA,STATUS_FLAG\n"
    files = []
    for k, (u, v) in enumerate([(0.0, 0.0), (0.25, -0.5)]):
        body = "".join(
            f"{i},{X[i]},{Y[i]},{u * (i + 1)},{v},{0.005 if i < 2 else -1},0.001,0\n"
            for i in range(3)
        )
        f = tmp_path / f"DICe_solution_{k}.txt"
        f.write_text(head + body)
        files.append(f)
    ds = read_field(files, format="dice", data_origin="synthetic")
    assert ds.displacement.attrs["units"] == "pixel" and "position" not in ds
    np.testing.assert_allclose(ds.displacement.values[1, :2, 0], [0.25, 0.5])
    failed = ds.flag.attrs["flag_meanings"].split().index("failed_in_source")
    assert list(ds.flag.values[1]) == [0, 0, failed]
    assert np.isnan(ds.displacement.values[1, 2]).all()
    files[1].write_text(head + "0,101,50,0,0,0.1,0,0\n1,120,50,0,0,0.1,0,0\n2,140,50,0,0,0.1,0,0\n")
    with pytest.raises(BadInputError, match="points .* differ"):
        read_field(files, format="dice", data_origin="synthetic")


def test_own_csv_export_round_trips_through_the_importer_and_cli(tmp_path):
    frames = sp.speckle_sequence((96, 96), [None, sp.RigidField((0.6, -0.3))], seed=2)
    ds = measure_field(frames, subset_size=21, step=12, strain_window=3)
    write_field_csv(ds, tmp_path / "f.csv")
    back = read_field(str(tmp_path / "f_*.csv"), format="vic3d-csv", data_origin="synthetic")
    np.testing.assert_allclose(back.displacement.values, ds.displacement.values, atol=1e-8)
    out = tmp_path / "imp.nc"
    args = ["dic", "import-field", str(tmp_path / "f_*.csv"), "--format", "vic3d-csv"]
    assert main([*args, "--origin", "synthetic", "--out", str(out)]) == 0
    np.testing.assert_allclose(io.load(out).displacement.values, ds.displacement.values, atol=1e-8)
    assert main([*args, "--out", str(out)]) == 2  # the origin must be said


def test_dice_gt4_failed_subsets_are_flagged_nan_not_measured_zeros(tmp_path, capsys):
    """DICe writes 0 displacement on the 4 subsets per frame it could not correlate (MATCH -1)."""
    files = [GT4 / "DICe_solution_0.txt", GT4 / "DICe_solution_5.txt"]
    raw = np.loadtxt(files[1], delimiter=",", skiprows=1)
    match_failed = raw[:, -1] == -1  # the MATCH column, read independently
    assert match_failed.sum() == 4 and (raw[match_failed, 5:7] == 0).all()
    ds = read_field(files, format="dice", data_origin="measured")
    failed = ds.flag.attrs["flag_meanings"].split().index("failed_in_source")
    np.testing.assert_array_equal(ds.flag.values[1] == failed, match_failed)
    assert np.isnan(ds.displacement.values[1][match_failed]).all()  # every component
    assert np.isnan(ds.foreign_quality.values[1][match_failed]).all()
    assert np.isfinite(ds.displacement.values[1][~match_failed]).all()
    np.testing.assert_allclose(ds.displacement.values[1][~match_failed], raw[~match_failed, 5:7])
    assert "MATCH < 0" in ds.flag.attrs["comment"]
    out = tmp_path / "gt4.nc"
    args = ["dic", "import-field", *map(str, files), "--format", "dice", "--origin", "measured"]
    assert main([*args, "--out", str(out)]) == 0
    assert (
        "119/123 points with data in the last image (4 failed_in_source)" in capsys.readouterr().out
    )
    assert (io.load(out).flag.values[1] == failed).sum() == 4


def test_own_csv_flags_come_back_as_flags_not_as_data(tmp_path):
    """A jointwear CSV's flagged rows (blank values, the flag's name) import with that flag."""
    frames = sp.speckle_sequence((96, 96), [None, sp.RigidField((0.6, -0.3))], seed=2)
    ds = measure_field(frames, subset_size=21, step=12, strain_window=3)
    ds["flag"][1, :3] = [2, 7, 1]  # low_correlation, diverged, not_converged
    ds["displacement"][1, :3] = np.nan
    write_field_csv(ds, tmp_path / "f.csv")
    back = read_field(str(tmp_path / "f_*.csv"), format="vic3d-csv", data_origin="synthetic")
    np.testing.assert_array_equal(back.flag.values, ds.flag.values)
    assert np.isnan(back.displacement.values[1, :3]).all()
