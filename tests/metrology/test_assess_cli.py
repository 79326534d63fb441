"""Whole-scan assessment and the command line, on generated instrument files with known truth."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from jointwear import io
from jointwear.cli import main
from jointwear.datasets.instruments import generate, write
from jointwear.errors import BadInputError
from jointwear.metrology import cylindricity
from jointwear.metrology.assess import CentringWarning, assess


@pytest.fixture(scope="module")
def scan():
    return generate(n_layers=5, n_points=1800, seed=5, eccentricity=(3e-6, 2e-6), tilt=(2e-4, 0))


def test_assess_values_against_truth(scan):
    ds = scan.truth[["radius"]]
    res = assess(ds, max_harmonic=20)
    # MZ is the narrowest reference everywhere
    for ref in ("LS", "MI", "MC"):
        assert np.all(res["RONt_MZ"].values <= res[f"RONt_{ref}"].values + 1e-12)
        assert float(res["CYLt_MZ"]) <= float(res[f"CYLt_{ref}"]) + 1e-12
    assert float(res["CYLt_MZ"]) == pytest.approx(cylindricity(ds), rel=1e-12)
    # parameters are consistent: t = p + v
    np.testing.assert_allclose(res["RONt_LS"], res["RONp_LS"] + res["RONv_LS"], rtol=1e-12)
    # set-up recovered on the unworn bore (wear has a first harmonic that moves the LS centre):
    # the eccentricity grows along z with the imposed tilt (instrument -> canonical frame is a
    # rotation/reflection, the magnitude is invariant)
    unworn = generate(
        n_layers=5, n_points=1800, seed=5, eccentricity=(3e-6, 2e-6), tilt=(2e-4, 0), wear=None
    )
    res_u = assess(unworn.truth[["radius"]], references=("LS",), max_harmonic=20)
    z = res_u["z"].values
    expected = np.hypot(3e-6 + 2e-4 * z, 2e-6)
    np.testing.assert_allclose(res_u["eccentricity"].values, expected, atol=0.02e-6)
    # spectrum of the unworn form: the imposed 12-UPR harmonic (0.05 µm) is seen in every layer
    assert np.all(np.abs(res["harmonic_amplitude"].sel(harmonic=12).values - 0.05e-6) < 0.03e-6)


def test_assess_warns_on_large_eccentricity():
    sc = generate(
        n_layers=2, n_points=720, eccentricity=(300e-6, 0), tilt=(0, 0), seed=1, wear=None
    )
    with pytest.warns(CentringWarning, match="limaçon approximation is off"):
        res = assess(sc.truth[["radius"]])
    assert res.attrs["limacon_error_max"] == pytest.approx(300e-6**2 / (4 * 8e-3), rel=0.01)


def test_assess_filter_and_outliers(scan):
    ds = scan.truth[["radius"]].copy(deep=True)
    ds["radius"].values[2, 100] += 20e-6
    raw = assess(ds, references=("MZ",))
    clean = assess(ds, references=("MZ",), outliers=5)
    assert clean["outliers_removed"].values[2] >= 1
    truth = assess(scan.truth[["radius"]], references=("MZ",))
    assert float(raw["RONt_MZ"][2]) > float(truth["RONt_MZ"][2]) + 5e-6
    assert float(clean["RONt_MZ"][2]) == pytest.approx(float(truth["RONt_MZ"][2]), abs=0.05e-6)
    filt = assess(ds, references=("MZ",), outliers=5, filter_upr=15)
    assert np.all(filt["RONt_MZ"].values < clean["RONt_MZ"].values)
    assert filt.attrs["filter"] == "gaussian 15 UPR"
    with pytest.raises(BadInputError, match="must have dims"):
        assess(ds["radius"].isel(z=0))


def test_cli_end_to_end(tmp_path, scan, capsys):
    write(scan, tmp_path / "worn", layout="folder")
    nc = tmp_path / "scan.nc"
    code = main(["metrology", "import", str(tmp_path / "worn"), "--out", str(nc)])
    assert code == 3
    assert "never guesses" in capsys.readouterr().err
    assert (
        main(
            [
                "metrology",
                "import",
                str(tmp_path / "worn"),
                "--out",
                str(nc),
                "--angle-zero",
                "+y",
                "--angle-direction",
                "counterclockwise",
            ]
        )
        == 0
    )
    ds = io.load(nc)
    np.testing.assert_allclose(
        ds["radial_deviation"].values + scan.nominal_radius, scan.truth["radius"].values, atol=2e-10
    )
    csv = tmp_path / "form.csv"
    assert (
        main(
            [
                "metrology",
                "assess",
                str(nc),
                "--filter",
                "50",
                "--csv",
                str(csv),
                "--out",
                str(tmp_path / "form.nc"),
                "-r",
                "MZ",
                "-r",
                "LS",
            ]
        )
        == 0
    )
    out = capsys.readouterr().out
    assert "RONt_MZ_um" in out and "bore" in out
    table = pd.read_csv(csv)
    assert list(table["layer"])[-1] == "bore" and len(table) == 6
    wear = tmp_path / "wear.nc"
    # the generator's two wear lobes cover 55 % of the circumference of a lobed bore: without a
    # before-scan wear cannot be separated from form - refused, asking for --before
    assert main(["metrology", "wearmap", str(nc), "--out", str(wear)]) == 3
    assert "--before" in capsys.readouterr().err
    before = generate(
        n_layers=5,
        n_points=1800,
        seed=5,
        eccentricity=(3e-6, 2e-6),
        tilt=(2e-4, 0),
        wear=None,
        noise_seed=9,
    )
    write(before, tmp_path / "before", layout="folder")
    bnc = tmp_path / "before.nc"
    conv = ["--angle-zero", "+y", "--angle-direction", "counterclockwise"]
    assert main(["metrology", "import", str(tmp_path / "before"), "--out", str(bnc), *conv]) == 0
    assert (
        main(
            [
                "metrology",
                "wearmap",
                str(nc),
                "--before",
                str(bnc),
                "--out",
                str(wear),
                "--plot",
                str(tmp_path / "wear.png"),
            ]
        )
        == 0
    )
    assert "± 0.0000" not in capsys.readouterr().out
    w = io.load(wear)
    assert w["theta"].attrs["angle_zero"] == "-x"
    assert float(w["wear_depth"].max()) == pytest.approx(20e-6, abs=3e-6)
    assert (tmp_path / "wear.png").stat().st_size > 10_000
    assert (
        main(["metrology", "plot", str(wear), "--out", str(tmp_path / "p.svg"), "--layers", "0,4"])
        == 0
    )
    assert (tmp_path / "p.svg").read_text().lstrip().startswith("<?xml")


def test_cli_batch_import_and_generator(tmp_path, capsys):
    root = tmp_path / "scans"
    for i, layout in enumerate(["folder", "long"]):
        target = root / (f"s{i}" if layout == "folder" else f"s{i}.txt")
        assert (
            main(
                [
                    "datasets",
                    "instruments",
                    str(target),
                    "--layers",
                    "3",
                    "--points",
                    "360",
                    "--layout",
                    layout,
                    "--seed",
                    str(i),
                ]
            )
            == 0
        )
    out = tmp_path / "nc"
    assert (
        main(
            [
                "metrology",
                "import",
                str(root),
                "--batch",
                "--out",
                str(out),
                "--angle-zero",
                "+y",
                "--angle-direction",
                "ccw",
            ]
        )
        == 0
    )
    assert sorted(p.name for p in out.iterdir()) == ["s0.nc", "s1.nc"]
    assert main(["metrology", "assess", str(out / "s0.nc"), str(out / "s1.nc")]) == 0
    assert capsys.readouterr().out.count("bore") == 2


def test_cli_pattern_skips_other_files(tmp_path, scan, capsys):
    write(scan, tmp_path / "s", layout="folder")
    (tmp_path / "s" / "README.md").write_text("Bearing 7, measured by Anna\n")
    args = [
        "metrology",
        "import",
        str(tmp_path / "s"),
        "--out",
        str(tmp_path / "x.nc"),
        "--angle-zero",
        "+y",
        "--angle-direction",
        "ccw",
    ]
    assert main(args) == 3
    assert "README.md': no table of numbers" in capsys.readouterr().err
    assert main([*args, "--pattern", "layer*.txt", "--instrument", "Talyrond 565H"]) == 0
    scan = io.load(tmp_path / "x.nc")
    # generated files say "Data origin: synthetic" in their header, and the import keeps it
    assert scan.attrs["source"] == "synthetic: Talyrond 565H"
    assert scan.attrs["data_origin"] == "synthetic"
