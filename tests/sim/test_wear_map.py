"""Wear-map Dataset: contract, io round trip, cylindricity by the metrology definition, plots."""

from __future__ import annotations

import numpy as np
import pytest

from jointwear import conventions, io
from jointwear.errors import BadInputError
from jointwear.sim import (
    BearingGrid,
    ConstantContact,
    WearSettings,
    plot_wear_history,
    plot_wear_map,
    simulate_wear,
    wear_map_dataset,
)

GRID = BearingGrid(10, 72)
metrology = pytest.importorskip("jointwear.metrology")


def _run(p, cycles=1000):
    return simulate_wear(
        contact=ConstantContact(GRID, pressure=p, sliding=0.02),
        cycles=cycles,
        settings=WearSettings(kw=1e-14),
    )


def test_grid_areas_and_layer_positions():
    assert GRID.point_area.sum() == pytest.approx(2 * np.pi * GRID.radius * GRID.width, rel=1e-12)
    assert GRID.z[0] == pytest.approx(GRID.width / 2)
    assert GRID.z[-1] == pytest.approx(-GRID.width / 2)
    assert GRID.theta_deg[1] == pytest.approx(5.0)


@pytest.mark.skipif(not hasattr(metrology, "cylindricity"), reason="metrology.cylindricity absent")
def test_cylindricity_of_the_worn_bore():
    depth = 1000 * 1e-14 * 1e6 * 0.02  # 0.2 µm
    # uniform wear: still a perfect cylinder
    assert float(_run(np.full(GRID.shape, 1e6))["cylindricity"][-1]) == pytest.approx(0, abs=1e-12)
    # wear proportional to 1 + cos(theta): a shifted circle (pure eccentricity), cylindricity 0
    lobe = 1e6 * (1 + np.cos(np.deg2rad(GRID.theta_deg)))[None, :] * np.ones((GRID.n_layers, 1))
    assert float(_run(lobe)["cylindricity"][-1]) == pytest.approx(0, abs=1e-12)
    # one edge layer worn all round: the zone is the depth of that layer
    p = np.zeros(GRID.shape)
    p[0] = 1e6
    assert float(_run(p)["cylindricity"][-1]) == pytest.approx(depth, rel=1e-6)


def test_wear_map_round_trips_through_netcdf(tmp_path):
    ds = _run(np.full(GRID.shape, 1e6))
    path = io.save(ds, tmp_path / "w.nc", source="jointwear 0.1 (sim.wear)")
    back = io.load(path)
    np.testing.assert_array_equal(back["wear_depth"].values, ds["wear_depth"].values)
    assert conventions.angle_convention_of(back) == conventions.CANONICAL
    assert back.attrs["kw_m2_per_N"] == 1e-14
    assert back["update_dn"].attrs["long_name"].startswith("cycles per update")


def test_wear_map_dataset_refuses_wrong_shapes():
    with pytest.raises(BadInputError, match=r"expected \(K, 10, 72\)"):
        wear_map_dataset(np.zeros((2, 5, 5)), np.array([1.0, 2.0]), GRID)


@pytest.mark.parametrize("kind", ["unrolled", "polar", "both"])
def test_plot_wear_map(kind, tmp_path):
    p = np.zeros(GRID.shape)
    p[0, 10] = 1e6
    ds = _run(p)
    fig = plot_wear_map(ds, kind=kind)
    fig.savefig(tmp_path / "m.png")
    assert (tmp_path / "m.png").stat().st_size > 1000
    polar = [a for a in fig.axes if a.name == "polar"]
    if kind != "unrolled":
        # theta = 0 along -x (west), clockwise: as the canonical convention
        assert polar[0].get_theta_offset() == pytest.approx(np.pi)
        assert polar[0].get_theta_direction() == -1
        line = polar[0].get_lines()[0]  # layer 1
        x, y = line.get_data()
        assert np.rad2deg(x[np.argmax(y)]) == pytest.approx(50.0)
    else:
        assert not polar
        mesh = fig.axes[0].collections[0]
        assert mesh.get_array().max() == pytest.approx(0.2, rel=1e-9)  # µm
    import matplotlib.pyplot as plt

    plt.close(fig)


def test_plot_wear_history(tmp_path):
    ds = _run(np.full(GRID.shape, 1e6), cycles=5000)
    fig = plot_wear_history(ds, measured_cylindricity={2000: 1e-7})
    left, right = fig.axes
    x, y = left.get_lines()[0].get_data()
    np.testing.assert_allclose(x, ds["cycles"].values)
    np.testing.assert_allclose(y, ds["max_wear_depth"].values * 1e6)
    assert right.get_yscale() == "log"
    fig.savefig(tmp_path / "h.png")
    import matplotlib.pyplot as plt

    plt.close(fig)
