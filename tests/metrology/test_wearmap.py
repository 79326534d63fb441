"""Wear maps against synthetic scans with a known imposed wear."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from jointwear.conventions import CANONICAL, AngleConvention, theta_coord, z_coord
from jointwear.errors import BadInputError, ConventionError
from jointwear.metrology.wearmap import wear_map, worn_volume

R = 8e-3
NZ, NT = 7, 1440
Z = (np.arange(NZ) - 3) * 1e-3
TH = np.arange(NT) * 360.0 / NT
RAD = np.radians(TH)
WEAR = 15e-6 * np.exp(-(((TH - 100.0) / 25.0) ** 2))[None, :] * (1 - (Z[:, None] + 3e-3) / 10e-3)
FORM = 1e-6 * np.cos(3 * RAD)[None, :] + 0.4e-6 * np.sin(5 * RAD + 200 * Z[:, None])


def _scan(r, convention=CANONICAL, theta=TH):
    return xr.Dataset(
        {"radius": (("z", "theta"), r, {"units": "m", "long_name": "radius"})},
        coords={"z": z_coord(Z), "theta": theta_coord(theta, convention)},
    )


def _setup(ex, ey, tx, ty):
    return (ex + tx * Z[:, None]) * np.cos(RAD)[None, :] + (ey + ty * Z[:, None]) * np.sin(RAD)[
        None, :
    ]


def test_wear_map_with_before_scan_recovers_imposed_wear():
    rng = np.random.default_rng(1)
    sigma = 0.05e-6
    before = R + _setup(12e-6, -4e-6, 1e-3, 0) + FORM + sigma * rng.standard_normal(WEAR.shape)
    worn = R + _setup(-3e-6, 9e-6, 0, 2e-3) + FORM + WEAR + sigma * rng.standard_normal(WEAR.shape)
    out = wear_map(_scan(worn), _scan(before))
    err = out["wear_depth"].values - WEAR
    # the difference of two scans carries sqrt(2) x the noise of one
    assert np.sqrt(np.mean(err**2)) < 1.05 * np.sqrt(2) * sigma
    true_v = worn_volume(WEAR, Z, TH, R)
    assert out["worn_volume"].item() == pytest.approx(true_v, rel=0.01)
    assert out["cylindricity_after"].item() > out["cylindricity_before"].item()
    # uncertainty estimate matches the actual scatter
    assert out["wear_depth_u"].mean().item() == pytest.approx(np.sqrt(2) * sigma, rel=0.2)
    # its independent part is the noise of the difference (white: correlation length ~1)
    rnd = out["wear_depth_u_random"]
    assert rnd.attrs["units"] == "m" and "noise" in rnd.attrs["comment"]
    assert float(rnd.mean()) == pytest.approx(np.sqrt(2) * sigma, rel=0.1)
    assert bool((rnd <= out["wear_depth_u"]).all())
    assert 1.0 <= rnd.attrs["correlation_length_samples"] < 1.5
    assert out["theta"].attrs["angle_zero"] == "-x"


def test_wear_map_before_scan_in_another_convention_and_registration():
    rng = np.random.default_rng(2)
    sigma = 0.03e-6
    before = R + FORM + sigma * rng.standard_normal(WEAR.shape)
    worn = R + FORM + WEAR + sigma * rng.standard_normal(WEAR.shape)
    # the before scan stated in an instrument convention: zero along +y, counter-clockwise
    inst = AngleConvention("+y", "counterclockwise")
    theta_inst = inst.from_physical(CANONICAL.to_physical(TH))
    b = _scan(before, inst, theta_inst).sortby("theta")
    out = wear_map(_scan(worn), b)
    assert np.sqrt(np.mean((out["wear_depth"].values - WEAR) ** 2)) < 1.05 * np.sqrt(2) * sigma
    # rotate the before scan by 7.5 degrees; registration finds it
    shifted = np.roll(before, -30, axis=1)  # feature at theta now at theta - 7.5 degree
    reg = wear_map(_scan(worn), _scan(shifted), register=True)
    assert reg["angle_offset"].item() == pytest.approx(7.5, abs=0.1)
    given = wear_map(_scan(worn), _scan(shifted), angle_offset_deg=7.5)
    assert np.sqrt(np.mean((given["wear_depth"].values - WEAR) ** 2)) < 1.05 * np.sqrt(2) * sigma


def test_wear_map_without_before_scan():
    rng = np.random.default_rng(3)
    sigma = 0.05e-6
    worn = R + _setup(5e-6, 5e-6, 1e-3, -1e-3) + WEAR + sigma * rng.standard_normal(WEAR.shape)
    out = wear_map(_scan(worn))
    err = out["wear_depth"].values - WEAR
    assert np.sqrt(np.mean(err**2)) < 1.05 * sigma
    assert out["unworn"].values[:, np.abs(TH - 100) < 10].sum() == 0
    assert "unworn part" in out.attrs["wear_reference"]
    assert out["worn_volume"].item() == pytest.approx(worn_volume(WEAR, Z, TH, R), rel=0.01)


def test_wear_map_errors():
    worn = _scan(R + WEAR)
    bare = worn.copy()
    bare["theta"].attrs = {"units": "degree"}
    with pytest.raises(ConventionError, match="does not state its angle convention"):
        wear_map(bare)
    other = xr.Dataset(
        {"radius": (("z", "theta"), np.full((2, NT), R), {"units": "m", "long_name": "r"})},
        coords={"z": z_coord([10e-3, 11e-3]), "theta": theta_coord(TH)},
    )
    with pytest.raises(BadInputError, match="before scan covers z"):
        wear_map(worn, other)
    dev = xr.Dataset(
        {"radial_deviation": (("z", "theta"), WEAR, {"units": "m", "long_name": "dev"})},
        coords={"z": z_coord(Z), "theta": theta_coord(TH)},
    )
    with pytest.raises(BadInputError, match="pass radius="):
        wear_map(dev)
    assert wear_map(dev, radius=R)["worn_volume"].item() > 0
    # a dataset whose values are under another name is refused, naming what it holds
    named = dev.rename({"radial_deviation": "height"})
    with pytest.raises(
        BadInputError,
        match=r"worn scan: .*neither 'radius' nor 'radial_deviation' \(variables: height\)",
    ):
        wear_map(named, radius=R)
    with pytest.raises(
        BadInputError, match=r"before scan: .*neither 'radius'.*\(variables: none\)"
    ):
        wear_map(worn, xr.Dataset())


def test_a_file_without_scan_values_is_refused_naming_the_file(tmp_path, capsys):
    """Two inputs (worn, before): the refusal names the file that holds no scan, not only the role."""
    from jointwear.cli import main
    from jointwear.io import save

    good = tmp_path / "before.nc"
    bad = tmp_path / "wear.nc"
    dev = xr.Dataset(
        {"radius": (("z", "theta"), R + WEAR * 0, {"units": "m", "long_name": "radius"})},
        coords={"z": z_coord(Z), "theta": theta_coord(TH)},
    )
    dev.attrs["data_origin"] = "synthetic"
    save(dev, good, source="test")
    bad_ds = dev.rename({"radius": "wear_depth"})
    bad_ds["wear_depth"].attrs["long_name"] = "wear depth"
    save(bad_ds, bad, source="test")
    code = main(
        ["metrology", "wearmap", str(bad), "--before", str(good), "--out", str(tmp_path / "o.nc")]
    )
    err = capsys.readouterr().err
    assert code == 3
    assert "wear.nc" in err and "neither 'radius' nor 'radial_deviation'" in err
    assert not (tmp_path / "o.nc").exists()
    # the advice followed (a scan: radius over (z, theta)) reads the wear
    worn = dev.copy(data={"radius": R + WEAR})
    save(worn, bad, source="test")
    args = [
        "metrology",
        "wearmap",
        str(bad),
        "--before",
        str(good),
        "--out",
        str(tmp_path / "o.nc"),
    ]
    assert main(args) == 0
    depth = xr.open_dataset(tmp_path / "o.nc")["wear_depth"]
    np.testing.assert_allclose(float(depth.max()), WEAR.max(), rtol=0.02)


def test_exact_centring_with_large_set_up_offsets():
    """Generated scans with an exact (non-limaçon) set-up of 60 µm: the e^2/(4R) term (112 nm)
    would dominate the error; exact re-centring brings it back to the noise of the difference."""
    from jointwear.datasets.instruments import generate

    sigma = 0.02e-6
    kw = dict(n_layers=5, n_points=1440, seed=9, noise=sigma, quantisation=0.0)
    before = generate(**kw, wear=None, eccentricity=(60e-6, 0), tilt=(0, 0), noise_seed=1)
    worn = generate(**kw, eccentricity=(0, -50e-6), tilt=(1e-3, 0), noise_seed=2)
    truth = worn.truth["wear_depth"].values
    exact = wear_map(worn.truth[["radius"]], before.truth[["radius"]])
    rms = np.sqrt(np.mean((exact["wear_depth"].values - truth) ** 2))
    assert rms < 1.1 * np.sqrt(2) * sigma
    assert exact.attrs["centring"].startswith("exact")
    # the limaçon alone leaves the e^2/(4R) term: smooth structure on the unworn points, refused
    with pytest.raises(BadInputError, match="smooth structure"):
        wear_map(worn.truth[["radius"]], before.truth[["radius"]], exact_centring=False)


def test_noise_free_before_scan_is_not_degenerate():
    before = R + FORM
    out = wear_map(_scan(before + WEAR), _scan(before))
    # only the faint tails of the wear patch (taken as unworn) bias the reference, by < 1 nm
    np.testing.assert_allclose(out["wear_depth"].values, WEAR, atol=1e-9)


def test_plot_wear_map(tmp_path):
    import matplotlib.pyplot as plt

    from jointwear.metrology.plot import plot_wear_map

    out = wear_map(_scan(R + WEAR))
    fig = plot_wear_map(out, layers=[0, -1], path=tmp_path / "w.png", title="t")
    ax, *rest = fig.axes
    assert "0 along -x, clockwise" in ax.get_xlabel()
    polar = [a for a in fig.axes if a.name == "polar"][0]
    assert len(polar.lines) == 2
    assert (tmp_path / "w.png").stat().st_size > 5000
    plt.close(fig)
    with pytest.raises(BadInputError, match="out of range"):
        plot_wear_map(out, layers=[99])
    with pytest.raises(BadInputError, match="expected wear_depth over"):
        plot_wear_map(out["wear_depth"].isel(z=0))


def test_circle_per_layer_reference():
    """Layer centres that do not lie on a straight axis: only one circle per layer fits them."""
    rng = np.random.default_rng(4)
    sigma = 0.03e-6
    ex = rng.uniform(-5e-6, 5e-6, (NZ, 1))
    ey = rng.uniform(-5e-6, 5e-6, (NZ, 1))
    worn = R + ex * np.cos(RAD) + ey * np.sin(RAD) + WEAR + sigma * rng.standard_normal(WEAR.shape)
    circ = wear_map(_scan(worn), shape="circle")
    assert np.sqrt(np.mean((circ["wear_depth"].values - WEAR) ** 2)) < 1.05 * sigma
    assert "circle per layer" in circ.attrs["wear_reference"]
    # a straight-axis cylinder cannot hold those centres: refused, never a wrong map
    with pytest.raises(BadInputError, match=r"leaves .* µm RMS.*cannot be separated.*--before"):
        wear_map(_scan(worn), shape="cylinder")
    # the form model (default without a before-scan) has a centre per layer
    form = wear_map(_scan(worn))
    assert np.sqrt(np.mean((form["wear_depth"].values - WEAR) ** 2)) < 1.1 * sigma


def test_tail_bound_is_a_rectangular_u_and_not_added_to_the_selection_term():
    """The undetected tail's bound a enters as a rectangular distribution (a / sqrt(3), GUM
    4.3.7; it was a itself, 2-4 x the scatter), and it and the unworn-selection change - two
    estimates of one effect, the reference's bias by faint tails - are not summed: the larger
    counts (closed forms on a flat map)."""
    from jointwear.metrology._wear_output import reference_bias_terms, tail_term

    z, th = np.array([0.0, 1e-3]), np.arange(0.0, 360.0, 10.0)
    wear = np.zeros((z.size, th.size))
    wear[:, 3] = 1e-6
    wts = np.full(wear.shape, 2e-6)  # areas [m^2]
    a = 30e-9
    shift = np.full(wear.shape, a)
    tail = tail_term(
        {"worn_volume": 0, "max_wear_depth": 0, "wear_cylindricity": 0}, wear, wts, 1.0, shift
    )
    assert tail[0]["worn_volume"] == pytest.approx(a * wts.sum() / np.sqrt(3.0))
    assert tail[0]["max_wear_depth"] == pytest.approx(a / np.sqrt(3.0))
    assert tail[0]["wear_cylindricity"] == 0.0  # a uniform shift leaves the form
    np.testing.assert_allclose(tail[1], a / np.sqrt(3.0))
    # untested tails (NaN) are not assessed, not zero
    assert tail_term({}, wear, wts, float("nan"), shift) is None
    q = {"worn_volume": (1.0, 3.0, "noise"), "max_wear_depth": (1.0, 3.0, "noise")}
    q["wear_cylindricity"] = (1.0, 3.0, "noise")
    sel = ({k: 4.0 for k in q}, np.full(wear.shape, 4.0))
    tl = ({k: 4.0 for k in q}, np.full(wear.shape, 2.0))
    u = reference_bias_terms(q, np.full(wear.shape, 3.0), sel, tl, "note")
    assert q["worn_volume"][1] == pytest.approx(5.0)  # hypot(3, max(4, 4)), not hypot(3, 4, 4)
    np.testing.assert_allclose(u, 5.0)
    assert "the larger counted" in q["worn_volume"][2]
    q2 = {"worn_volume": (1.0, 3.0, "noise")}
    reference_bias_terms(q2, np.full(wear.shape, 3.0), None, None, "not assessed (few points)")
    assert q2["worn_volume"][1] == 3.0
    assert "faint wear tails not assessed" in q2["worn_volume"][2]
