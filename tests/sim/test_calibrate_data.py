"""Calibration data (jointwear.sim.calibrate): reported-values files, the wear field, the
likelihood's run scatter and a measured map's u and corrected maximum, against closed forms."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from jointwear import io
from jointwear.conventions import CANONICAL
from jointwear.errors import BadInputError
from jointwear.reported import read_reported
from jointwear.sim.calibrate._data import band_quantities, map_data, volume_weights
from jointwear.sim.calibrate._emulator import fit_emulator
from jointwear.sim.calibrate._reported import reported_data
from jointwear.wear_field import field_bins, field_means, field_u, split_u

UM = 1e-6
CANONICAL_ATTRS = {"angle_zero": CANONICAL.zero, "angle_direction": CANONICAL.direction}


def reported_toml(path: Path, *, reference="MZ", baseline=True, z_centre='"1 mm"', first='"+z"'):
    """A reported file: 3 layers 2 mm apart, a new-bore and a worn cylindricity, a depth."""
    base = (
        f"""[quantity.cyl0]
kind = "cylindricity"
value = 5.0
unit = "um"
cycles = 0
layers = "all"
reference = "{reference}"
source = "table 1"
uncertainty = {{ standard = 0.5 }}
"""
        if baseline
        else ""
    )
    path.write_text(
        f"""schema = "jointwear.reported/1"
[source]
citation = "test sheet"
[layers]
count = 3
spacing = "2 mm"
z_centre = {z_centre}
first = {first}
{base}
[quantity.cyl]
kind = "cylindricity"
value = 12.0
unit = "um"
cycles = 2e5
layers = "all"
reference = "{reference}"
source = "table 1"
uncertainty = {{ standard = 1.0 }}
[quantity.depth_top]
kind = "max_wear_depth"
value = 8.0
unit = "um"
cycles = 2e5
layer = 1
source = "table 2"
uncertainty = {{ accuracy = "0.3 um" }}
[quantity.depth_all]
kind = "max_wear_depth"
value = 9.0
unit = "um"
cycles = 2e5
layers = "all"
source = "table 2"
uncertainty = {{ standard = 0.2 }}
"""
    )
    return path


def test_reported_file_gives_growth_places_and_u(tmp_path):
    path = reported_toml(tmp_path / "rep.toml")
    bands, data, notes = reported_data(read_reported(path), path, first_band=2)
    by = {d.source.split("#")[1]: d for d in data}
    assert set(by) == {"cyl", "depth_top", "depth_all"}  # the new bore is the baseline only
    cyl = by["cyl"]  # growth C(N) - C(0), the new bore's form rectangular
    assert cyl.quantity == "cylindricity" and cyl.cycles == 2e5
    assert cyl.value == pytest.approx(7.0 * UM)
    assert cyl.u_d == pytest.approx(math.sqrt(1.0 + 0.25 + 25.0 / 3.0) * UM)
    assert by["depth_top"].u_d == pytest.approx(0.3 / math.sqrt(3) * UM)
    # layers centred at z = +1 mm, 2 mm apart; layer 1 at the +z end
    z_all = bands[by["depth_all"].band - 2].z
    np.testing.assert_allclose(z_all, [-1e-3, 1e-3, 3e-3])
    np.testing.assert_allclose(bands[by["depth_top"].band - 2].z, [3e-3])
    # the worn cylindricity and the depth over all layers share a band (one run moves both)
    assert by["cyl"].band == by["depth_all"].band != by["depth_top"].band
    assert all(d.band >= 2 for d in data) and notes == []


@pytest.mark.parametrize(
    ("kwargs", "names"),
    [
        ({"reference": "unstated"}, "reference = 'LS' or 'MZ'"),
        ({"baseline": False}, "new bore's value at cycles = 0"),
        ({"z_centre": '"unstated"'}, "state layers.z_centre"),
        ({"first": '"unstated"'}, "state layers.first"),
    ],
)
def test_reported_file_refusals_name_the_field(tmp_path, kwargs, names):
    path = reported_toml(tmp_path / "rep.toml", **kwargs)
    with pytest.raises(BadInputError, match=names.replace("(", r"\(").replace(")", r"\)")):
        reported_data(read_reported(path), path, first_band=0)


def test_reported_ls_cylindricity_is_reduced_against_the_ls_cylinder(tmp_path):
    path = reported_toml(tmp_path / "rep.toml", reference="LS")
    bands, data, _ = reported_data(read_reported(path), path, first_band=0)
    cyl = next(d for d in data if d.quantity == "cylindricity")
    band = bands[cyl.band]
    assert band.cylindricity_reference == "LS"
    # a broad lobe growing along z: the least-squares zone is about 12 % wider than the minimum
    zz, tt = np.meshgrid(band.z, band.theta, indexing="ij")
    h = 2e-6 * np.exp(-(((tt - 90) / 30) ** 2)) * (1 + zz / 3e-3)
    ls = band.quantities(h, 8e-3)["cylindricity"]
    mz = band_quantities(h, band.z, band.theta, 8e-3, reference="MZ")["cylindricity"]
    assert ls > mz * 1.05  # the LS zone, not the minimum zone


def test_wear_field_bins_means_and_u_closed_form():
    bins = field_bins(5, 24, 2, 4)  # 5 layers -> 3 + 2, 24 angles -> 4 x 6
    assert [(len(i), len(j)) for i, j in bins[:5]] == [(3, 6)] * 4 + [(2, 6)]
    h = np.add.outer(np.arange(5.0), np.zeros(24))  # depth = layer index
    np.testing.assert_allclose(field_means(h, bins), [1.0] * 4 + [3.5] * 4)
    u = np.full((5, 24), 0.3)
    # all independent: sqrt(n) u / n; none independent: u (fully correlated within a bin)
    np.testing.assert_allclose(field_u(u, u, bins)[:4], 0.3 / math.sqrt(18))
    np.testing.assert_allclose(field_u(u, None, bins), 0.3)
    half = field_u(u, np.full((5, 24), 0.3 * math.sqrt(0.5)), bins)[0]
    assert half == pytest.approx(math.hypot(0.3 * math.sqrt(0.5), 0.3 * math.sqrt(0.5 / 18)))


def test_split_u_hand_computation():
    # u = 5 of which 3 independent -> 4 correlated; no stated part -> all correlated; no u ->
    # nothing (NaN, left out of a bin); a part above u by round-off -> capped, all independent
    u = np.array([[5.0, 2.0, np.nan, 1.0]])
    rnd = np.array([[3.0, np.nan, 1.0, 1.0 + 1e-9]])
    sys_part, ind = split_u(u, rnd)
    np.testing.assert_array_equal(sys_part, [[4.0, 2.0, np.nan, 0.0]])
    np.testing.assert_array_equal(ind, [[3.0, 0.0, 0.0, 1.0]])
    one_bin = [(np.array([0]), np.arange(4))]
    # three points with a u: mean correlated part (4 + 2 + 0) / 3, independent sqrt(9 + 1) / 3
    assert field_u(u, rnd, one_bin)[0] == pytest.approx(math.hypot(2.0, math.sqrt(10.0) / 3))


def test_an_independent_part_above_its_u_is_refused_naming_the_file():
    ds = map_dataset(np.full((3, 8), 1e-6), 1e-7, u_random=True)
    ds["wear_depth_u_random"] = ds["wear_depth_u"].copy()
    ds["wear_depth_u_random"][1, 2] = 1.5e-7  # more than the whole u of that point
    with pytest.raises(
        BadInputError,
        match=r"m\.nc: wear_depth_u_random exceeds wear_depth_u at 1 of 24 points \(up to 1\.5 x\)",
    ):
        map_data(ds, Path("m.nc"), 0, 1, ("worn_volume",), 8e-3)
    with pytest.raises(BadInputError, match="m.nc"):
        map_data(ds, Path("m.nc"), 0, 1, ("wear_field",), 8e-3)
    ds["wear_depth_u_random"][1, 2] = 1e-7 * (1 + 1e-9)  # round-off: capped at u
    _, [d] = map_data(ds, Path("m.nc"), 0, 1, ("worn_volume",), 8e-3)
    w = volume_weights(np.linspace(-6e-3, 6e-3, 3), np.arange(8) * 45.0, 8e-3)
    assert d.u_d == pytest.approx(1e-7 * math.sqrt(np.sum(w**2)), rel=1e-12)


def test_volume_u_of_a_partly_independent_u_by_hand():
    ds = map_dataset(np.full((3, 8), 1e-6), 1e-7, u_random=True)
    ds["wear_depth_u_random"] = ds["wear_depth_u"] * 0.6  # 0.6 independent, 0.8 correlated
    _, [d] = map_data(ds, Path("m.nc"), 0, 1, ("worn_volume",), 8e-3)
    w = volume_weights(np.linspace(-6e-3, 6e-3, 3), np.arange(8) * 45.0, 8e-3)
    hand = math.hypot(0.8e-7 * w.sum(), 0.6e-7 * math.sqrt(np.sum(w**2)))
    assert d.u_d == pytest.approx(hand, rel=1e-12)


def map_dataset(depth: np.ndarray, u: float, *, u_random: bool, stated_max: float | None = None):
    nz, nt = depth.shape
    z = np.linspace(-6e-3, 6e-3, nz)
    th = np.arange(nt) * 360.0 / nt
    ds = xr.Dataset(
        {
            "wear_depth": (("z", "theta"), depth, {"units": "m"}),
            "wear_depth_u": (("z", "theta"), np.full(depth.shape, u), {"units": "m"}),
        },
        coords={
            "z": ("z", z, {"units": "m"}),
            "theta": ("theta", th, {"units": "degree", **CANONICAL_ATTRS}),
        },
        attrs={"bearing_radius_m": 8e-3},
    )
    if u_random:
        ds["wear_depth_u_random"] = ds["wear_depth_u"]
    if stated_max is not None:
        ds["max_wear_depth"] = xr.DataArray(stated_max, attrs={"units": "m"})
        ds["max_wear_depth_u"] = xr.DataArray(0.1 * u, attrs={"units": "m"})
    return ds


def test_volume_u_sums_the_independent_part_in_quadrature(tmp_path):
    depth = np.full((5, 24), 2e-6)
    q = ("worn_volume",)
    _, [corr] = map_data(map_dataset(depth, 1e-7, u_random=False), Path("m.nc"), 0, 1, q, 8e-3)
    _, [rand] = map_data(map_dataset(depth, 1e-7, u_random=True), Path("m.nc"), 0, 1, q, 8e-3)
    w = volume_weights(np.linspace(-6e-3, 6e-3, 5), np.arange(24) * 15.0, 8e-3)
    assert (
        corr.value
        == pytest.approx(2e-6 * w.sum())
        == pytest.approx(2e-6 * 2 * math.pi * 8e-3 * 12e-3)
    )
    assert corr.u_d == pytest.approx(1e-7 * w.sum())  # fully correlated: an upper bound
    assert rand.u_d == pytest.approx(1e-7 * math.sqrt(np.sum(w**2)))


def test_a_stated_corrected_maximum_is_used_with_the_same_averaging(tmp_path):
    nt = 3600  # metrology averages the maximum over about 1 degree: 11 samples here
    depth = np.zeros((3, nt))
    depth[1, 100] = 11e-6  # one sample high: its 11-sample mean is 1 um
    ds = map_dataset(depth, 1e-8, u_random=True, stated_max=0.9e-6)
    band, [d] = map_data(ds, Path("m.nc"), 0, 1, ("max_wear_depth",), 8e-3)
    assert band.win == 11
    assert d.value == 0.9e-6 and d.u_d == pytest.approx(1e-9)  # the map's own, corrected
    assert band.quantities(depth, 8e-3)["max_wear_depth"] == pytest.approx(1e-6)  # averaged too
    plain, [d0] = map_data(map_dataset(depth, 1e-8, u_random=True), Path("m.nc"), 0, 1,
                           ("max_wear_depth",), 8e-3)  # fmt: skip
    assert plain.win == 1 and d0.value == pytest.approx(11e-6)


def test_emulator_scatter_correlation_is_the_runs(tmp_path):
    rng = np.random.default_rng(4)
    x = rng.random((120, 1))
    common, own = rng.standard_normal((2, 120))
    rho = 0.6  # planted correlation of the two quantities' scatter about their trends
    y = np.column_stack(
        [1 + x[:, 0] + 0.05 * common, 2 - x[:, 0] + 0.05 * (rho * common + 0.8 * own)]
    )
    emu = fit_emulator(x, y, seed=0)
    c = emu.correlation
    assert c.shape == (2, 2) and np.allclose(np.diag(c), 1.0)
    assert abs(c[0, 1] - rho) < 0.15


TRUTH_KW = 1.2e-15
RIG = (
    "[joint]\nn_layers = 5\nn_points = 24\naxial_grading = 0.0\n"
    '[wear]\nscheme = "fixed"\ndn = 100\nsettle_cycles = 0.25\ninitial_settle_cycles = 0.5\n'
)


@pytest.fixture(scope="module")
def truth(tmp_path_factory):
    """The truth's map after 200 cycles (kw = TRUTH_KW) on a 5 x 24 bore with even layers, 1 %
    independent noise per point; and a kept training design for the calibrations below."""
    import dataclasses

    from jointwear.params import from_mapping, read_toml
    from jointwear.sim import WearSettings, load_parameters, simulate_wear

    folder = tmp_path_factory.mktemp("truth")
    (folder / "base.toml").write_text(RIG)
    p = load_parameters(folder / "base.toml")
    w = from_mapping(WearSettings, read_toml(folder / "base.toml")["wear"], where="wear")
    ds = simulate_wear(p, cycles=200, settings=dataclasses.replace(w, kw=TRUTH_KW))
    clean = ds["wear_depth"].isel(cycles=-1)
    u = 0.01 * float(clean.max())
    m = clean.to_dataset(name="wear_depth")
    noise = u * np.random.default_rng(7).standard_normal(clean.shape)
    m["wear_depth"] = (clean + noise).assign_attrs(ds["wear_depth"].attrs)
    m["wear_depth_u"] = (m["wear_depth"] * 0 + u).assign_attrs(units="m")
    m["wear_depth_u_random"] = m["wear_depth_u"]
    m.attrs = {"data_origin": "synthetic", "bearing_radius_m": 8e-3}
    io.save(m, folder / "meas-200.nc")
    return folder, clean


def calibrated(folder: Path, name: str, data: str, extra: str = ""):
    from jointwear.sim.calibrate import calibrate

    spec = folder / f"{name}.toml"
    spec.write_text(
        f'[calibrate]\ndata = ["{data}"]\ncycles = 200\nsamples = 24\nseed = 2\n'
        f"u_num_rel = 0.02\n{extra}"
        '[parameters."wear.kw"]\ndistribution = "uniform"\nbounds = [4.5e-16, 1.8e-15]\n'
    )
    design = folder / "design.nc"  # the training runs do not depend on the data: reused
    target = folder / f"{name}.design-200.nc"
    if design.is_file():
        target.write_bytes(design.read_bytes())
    post = calibrate(spec, out=folder / f"{name}.nc", params=folder / "base.toml", workers=0,
                     resume=True)  # fmt: skip
    if not design.is_file():
        design.write_bytes(target.read_bytes())
    return post


@pytest.mark.slow  # about 30 CPU s: 24 training runs once, two calibrations
def test_wear_field_and_reported_file_calibrations_recover_the_truth(truth):
    folder, clean = truth
    # each bin's mean is emulated: on 24 runs a bin at the worn patch's edge has an emulated
    # mean's error about its datum's u (measured 1.0 for 2 x 6 bins), above the default limit
    bins = 'quantities = ["wear_field"]\nfield_bins_z = 2\nfield_bins_theta = 6\n'
    post = calibrated(folder, "field", "meas-200.nc", bins + "emulator_max_fraction = 1.5\n")
    n_bins = 2 * 6
    assert [str(q) for q in post["datum_quantity"].values] == [
        f"wear_field_{k}" for k in range(n_bins)
    ]
    assert float(post["posterior_q025"][0]) <= TRUTH_KW <= float(post["posterior_q975"][0])
    assert float(post["posterior_sd"][0] / post["posterior_mean"][0]) < 0.1
    # the truth's numbers as a lab sheet reports them: the largest depth over the 5 layers and
    # the growth of the MZ cylindricity from a new bore of 1 nm, 3 % standard uncertainty
    from jointwear.sim.calibrate._data import Band, on_band

    z = np.asarray(clean["z"].values)
    nan = np.full((5, 360), np.nan)
    band = Band(z, np.arange(360.0), nan, nan, 8e-3)
    q = band.quantities(on_band(clean, band), 8e-3)
    depth, cyl = q["max_wear_depth"] / UM, q["cylindricity"] / UM
    sheet = reported_toml(folder / "sheet.toml", z_centre='"0 mm"')
    text = sheet.read_text().replace(
        'spacing = "2 mm"', f'spacing = "{float(z[1] - z[0]) * 1e3!r} mm"'
    )
    text = text.replace("count = 3", "count = 5").replace("value = 5.0", "value = 0.001")
    text = text.replace("value = 12.0", f"value = {cyl + 0.001!r}").replace(
        "cycles = 2e5", "cycles = 200"
    )
    text = text.replace("value = 9.0", f"value = {depth!r}").replace(
        "standard = 1.0", f"standard = {0.03 * cyl!r}"
    )
    text = text.replace("standard = 0.2", f"standard = {0.03 * depth!r}")
    cut = text.index("[quantity.depth_top]")
    sheet.write_text(text[:cut] + text[text.index("[quantity.depth_all]") :])
    # the emulated mean's error is about the 3 % u at 200 cycles (2 wear updates: the start
    # phase scatters the runs), as for the field above
    post = calibrated(folder, "from-sheet", "sheet.toml", "emulator_max_fraction = 1.5\n")
    assert sorted(str(q) for q in post["datum_quantity"].values) == [
        "cylindricity",
        "max_wear_depth",
    ]
    assert float(post["posterior_q025"][0]) <= TRUTH_KW <= float(post["posterior_q975"][0])
    assert float(post["posterior_sd"][0] / post["posterior_mean"][0]) < 0.2
