"""Figure outputs: the file name's suffix decides the format, or the name is refused up front.

Found by the CLI fuzz: ``metrology plot wear.nc --out o.nc`` and ``sim calibrate-kw`` given a
measured map as SIMULATED ended in "This is a bug"; ``sim wear --figure map.pdf`` wrote PNG bytes
into a .pdf.
"""

from __future__ import annotations

import pytest
from _small_map import small_wear_map

from jointwear import io
from jointwear.cli import main
from jointwear.errors import BadInputError

MAGIC = {".png": b"\x89PNG", ".pdf": b"%PDF", ".svg": b"<?xml"}


@pytest.fixture
def wear_map(tmp_path):
    path = tmp_path / "wear.nc"
    io.save(small_wear_map(), path)
    return path


def test_plot_to_a_netcdf_name_is_refused_and_the_advice_works(wear_map, tmp_path, capsys):
    bad = tmp_path / "o.nc"
    assert main(["metrology", "plot", str(wear_map), "--out", str(bad)]) == 3
    err = capsys.readouterr().err
    assert "--out" in err and "'.nc'" in err and ".png" in err
    assert "This is a bug" not in err
    assert not bad.exists()
    good = tmp_path / "o.png"  # the refusal's own example
    assert main(["metrology", "plot", str(wear_map), "--out", str(good)]) == 0
    assert good.read_bytes().startswith(MAGIC[".png"])


@pytest.mark.parametrize("suffix", [".png", ".pdf", ".svg"])
def test_save_figure_writes_the_format_its_name_says(tmp_path, suffix):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots()
    ax.plot([0, 1], [0, 1])
    path = io.save_figure(fig, tmp_path / f"f{suffix}")
    plt.close(fig)
    assert path.read_bytes().startswith(MAGIC[suffix])


def test_figure_format_refuses_before_anything_is_written(tmp_path):
    with pytest.raises(BadInputError, match=r"--figure '.*x\.nc'.*\.png"):
        io.figure_format(tmp_path / "x.nc", what="--figure")
    assert io.figure_format(tmp_path / "x") == "png"
    assert io.figure_format(tmp_path / "x.PDF") == "pdf"


def test_sim_wear_refuses_an_unwritable_figure_name_before_simulating(tmp_path, capsys):
    out = tmp_path / "w.nc"
    code = main(["sim", "wear", "--cycles", "1e4", "--out", str(out), "--figure", "map.nc"])
    assert code == 3
    assert "--figure" in capsys.readouterr().err
    assert not out.exists()  # refused up front: nothing simulated, nothing written


def test_calibrate_kw_refuses_a_measured_map_given_as_the_simulation(wear_map, capsys):
    code = main(["sim", "calibrate-kw", str(wear_map), "--map", str(wear_map)])
    err = capsys.readouterr().err
    assert code == 3
    assert "SIMULATED" in err and "not a wear run" in err
    assert "This is a bug" not in err
