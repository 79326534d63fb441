"""Wear spread round the bore (issue 42): decided by consequence, not refused for its tails.

The reference rig with ``joint.tilt_stiffness = 1000`` N m/rad, simulated to 4e5 cycles
(``data/tilt_stiff_wear.nc``: the last snapshot of ``jointwear sim wear --cycles 4e5``), wears
the bore over its whole width and leaves 2-20 nm between its two lobes: on the study's layout
(13 layers 1 mm apart) a before-scan map used to be refused ("faint tails reach around the
bore"), or, on another noise seed, read the volume 8 u low with exit 0. The map now carries
the consequence of the wear its selection cannot see (:mod:`jointwear.metrology._wear_unseen`)
and is refused only where that bound exceeds 30 % of the volume or the maximum depth; the
command line takes the unworn arcs (``--unworn``) and a refusal prints the command to run.
"""

from __future__ import annotations

import re
import shlex
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from jointwear import io
from jointwear.cli import main
from jointwear.conventions import CANONICAL, theta_coord, z_coord
from jointwear.datasets.instruments import generate
from jointwear.datasets.simulated_wear import wear_from_simulation
from jointwear.errors import BadInputError
from jointwear.metrology.form import cylinder_zone
from jointwear.metrology.wearmap import wear_map, worn_volume

R = 8e-3
DATA = Path(__file__).parent / "data"
QUANTITIES = ("worn_volume", "max_wear_depth", "wear_cylindricity")


def truth_values(wear: np.ndarray, z: np.ndarray, theta: np.ndarray) -> dict:
    """The truth's band values: volume [m^3], maximum depth and MZ cylindricity [m]."""
    zz, tt = np.broadcast_to(z[:, None], wear.shape), np.broadcast_to(theta, wear.shape)
    return {
        "worn_volume": worn_volume(wear, z, theta, R),
        "max_wear_depth": float(wear.max()),
        "wear_cylindricity": cylinder_zone(zz, tt, wear).total,
    }


def standardised(out: xr.Dataset, truth: dict) -> dict:
    """(map - truth) / u of each quantity."""
    return {k: (out[k].item() - v) / out[f"{k}_u"].item() for k, v in truth.items()}


def tilt_stiff_pair(noise_seed: int, n_points: int = 1440):
    """Worn and before scans of the simulated tilt-stiff wear on 13 layers at 1 mm (generator:
    exact set-ups, form, 20 nm noise, 1 nm quantisation), and the truth's band values."""
    wear = wear_from_simulation(xr.load_dataset(DATA / "tilt_stiff_wear.nc"))
    common = {"n_layers": 13, "n_points": n_points, "radius": R, "seed": 1}
    worn = generate(**common, wear=wear, noise_seed=10 + noise_seed)
    before = generate(
        **common,
        wear=None,
        noise_seed=20 + noise_seed,
        eccentricity=(22e-6, 5e-6),
        tilt=(2e-3, 1e-3),
    )
    t = worn.truth
    depth = t.wear_depth.transpose("z", "theta").values
    truth = truth_values(depth, t.z.values, t.theta.values)
    return worn.truth[["radius"]], before.truth[["radius"]], truth


@pytest.mark.parametrize("seed", [1, 2, 3, 4, 5])
def test_tilt_stiff_truth_on_the_reference_layout_maps_within_2u(seed):
    """Issue 42: mapped on every noise seed, volume, maximum depth and cylindricity within 2 u
    of the truth's band values (13 layers x 1440 points; the full 18000 in the benchmark)."""
    worn, before, truth = tilt_stiff_pair(seed)
    out = wear_map(worn, before)
    z = standardised(out, truth)
    assert all(abs(v) < 2.0 for v in z.values()), z
    assert "unseen wear" in out["worn_volume_u"].attrs["comment"]


def test_the_unseen_wear_term_is_what_covers_the_tilt_stiff_volume():
    """The check can fail: the same map without the unseen-wear term (its u read back from the
    comment) misses the volume; the wear on the unworn points pulls the reference up."""
    worn, before, truth = tilt_stiff_pair(2)
    out = wear_map(worn, before)
    comment = out["worn_volume_u"].attrs["comment"]
    term = float(comment.split("unseen wear (")[1].split(":")[0])
    u = out["worn_volume_u"].item()
    err = out["worn_volume"].item() - truth["worn_volume"]
    assert err < 0  # reads low: wear absorbed into the reference
    assert abs(err) > 2.0 * np.sqrt(max(u**2 - term**2, 0.0)), (err, u, term)


# -- a generated family of wear spread round the bore ------------------------------------

NZ, NT = 13, 1440
Z = (np.arange(NZ) - 6) * 1e-3
TH = np.arange(NT) * 360.0 / NT
RAD = np.radians(TH)


def spread_pair(fraction, depth, tail, seed, lobes=2, length_deg=40.0, sigma=20e-9, centre=None):
    """Worn and before scans (radius, different set-ups, the same lobed form) of a bore worn
    over ``fraction`` of its circumference by ``lobes`` cos^2 lobes (the first ``depth`` [m]
    deep, the others 0.3-1 x that), with tails of ``tail`` [m] at their edges decaying over
    ``length_deg`` into the rest, deeper at the top layer (the first lobe at ``centre``
    [degree], random by default); returns (worn, before, wear)."""
    rng = np.random.default_rng(seed)
    width = fraction * 360.0 / lobes
    first = rng.uniform(0, 360) if centre is None else centre
    centres = first + np.arange(lobes) * 360.0 / lobes
    profile, dist = np.zeros(NT), np.full(NT, np.inf)
    for k, c in enumerate(centres):
        d = np.abs((TH - c + 180.0) % 360.0 - 180.0)
        amp = depth * (1.0 if k == 0 else rng.uniform(0.3, 1.0))
        profile += np.where(d < width / 2, amp * np.cos(np.pi * d / width) ** 2, 0.0)
        dist = np.minimum(dist, np.maximum(d - width / 2, 0.0))
    profile += tail * np.exp(-dist / length_deg)
    wear = profile[None, :] * (0.6 + 0.4 * (Z[:, None] - Z[0]) / np.ptp(Z))
    form = 0.5e-6 * np.cos(2 * RAD + 0.3 + 40 * Z[:, None]) + 0.3e-6 * np.cos(3 * RAD + 1.0)

    def scan(ex, ey, tx, ty, w, noise_seed):
        setup = (ex + tx * Z[:, None]) * np.cos(RAD) + (ey + ty * Z[:, None]) * np.sin(RAD)
        noise = sigma * np.random.default_rng(noise_seed).standard_normal(w.shape)
        return xr.Dataset(
            {
                "radius": (
                    ("z", "theta"),
                    R + form + setup + w + noise,
                    {"units": "m", "long_name": "radius"},
                )
            },
            coords={"z": z_coord(Z), "theta": theta_coord(TH, CANONICAL)},
            attrs={"data_origin": "synthetic"},
        )

    worn = scan(12e-6, -7e-6, 1.5e-3, 0.8e-3, wear, 1000 + seed)
    before = scan(-5e-6, 9e-6, 0.5e-3, -1e-3, np.zeros_like(wear), 2000 + seed)
    return worn, before, wear


def spread_family(n: int, seed: int = 5):
    """``n`` bores worn over 60-100 % of the circumference (1-3 lobes 0.1-8 um deep, tails
    0.1-10 nm): (parameters, worn, before, wear)."""
    rng = np.random.default_rng(seed)
    for i in range(n):
        p = {
            "fraction": rng.uniform(0.6, 1.0),
            "depth": float(rng.choice([0.1e-6, 0.5e-6, 2e-6, 8e-6])),
            "tail": 10 ** rng.uniform(-10, -8),
            "lobes": int(rng.choice([1, 2, 3])),
        }
        yield (p, *spread_pair(seed=i, **p))


def test_wear_spread_round_the_bore_is_mapped_within_u_or_refused():
    """Every bore of the family is mapped with volume, maximum depth and cylindricity within
    3 u of the truth (no exit-0 misread), or refused naming the fix; a refusal by consequence
    names both figures (the bound and the quantity). Without the unseen-wear term 3 of these 8
    read the volume 9-11 u low with exit 0 (shallow lobes absorbed into the change of set-up)."""
    mapped = 0
    for p, worn, before, wear in spread_family(8):
        try:
            out = wear_map(worn, before)
        except BadInputError as exc:
            msg = str(exc)
            assert "unworn" in msg, msg
            if "could change the" in msg:
                assert re.search(r"\(([-\d.e+]+) (mm³|µm)\) by up to [\d.e+-]+ \2 \(\d+%", msg)
            continue
        mapped += 1
        z = standardised(out, truth_values(wear, Z, TH))
        assert all(abs(v) < 3.0 for v in z.values()), (p, z)
    assert mapped >= 2


# -- the command line: --unworn, and the refusal's command run as printed -----------------


def _write(tmp_path: Path, worn, before) -> tuple[Path, Path]:
    paths = tmp_path / "worn.nc", tmp_path / "before.nc"
    for ds, path in zip((worn, before), paths, strict=True):
        io.save(ds, path, source="test")
    return paths


def test_cli_unworn_arcs_make_the_mask(tmp_path, capsys):
    """--unworn START:END[,…] (canonical degrees, wrapping through 0) and --unworn-z-mm are the
    explicit mask through the CLI; a malformed value is a usage error (exit 2)."""
    worn, before, _ = spread_pair(0.4, 2e-6, 1e-12, seed=3, lobes=1, centre=100.0)
    w, b = _write(tmp_path, worn, before)
    out = tmp_path / "wear.nc"
    args = ["metrology", "wearmap", str(w), "--before", str(b), "--out", str(out)]
    code = main([*args, "--unworn", "330:10,200:260", "--unworn-z-mm", "-3:6"])
    assert code == 0, capsys.readouterr()
    ds = io.load(out)
    flag = ds["unworn"].values.astype(bool)
    in_arc = (TH >= 330) | (TH <= 10) | ((TH >= 200) & (TH <= 260))
    in_z = (Z >= -3e-3 - 1e-12) & (Z <= 6e-3 + 1e-12)
    np.testing.assert_array_equal(flag, in_z[:, None] & in_arc[None, :])
    assert "330..10" in ds.attrs["unworn_selection"]
    capsys.readouterr()
    assert main([*args, "--unworn", "330-30", "--overwrite"]) == 2
    assert "START:END" in capsys.readouterr().err


def test_a_refusal_by_consequence_prints_a_command_that_runs(tmp_path, capsys):
    """A shallow wear spread round the bore (0.5 um lobes over 80 %): the bound of the unseen
    wear exceeds 30 % of the volume, refused (exit 3) with both figures and a command with the
    least-worn arcs. Run as printed (shlex-split, through the CLI) it maps within 3 u of the
    truth or refuses again for a narrower reason: the arcs given cannot rule the wear out. (It
    used to map them as known unworn, exit 0, the volume 70 u high: the arcs held lobe flanks.)"""
    worn, before, wear = spread_pair(0.8, 0.5e-6, 0.3e-9, seed=10, lobes=2)
    w, b = _write(tmp_path, worn, before)
    out = tmp_path / "m.nc"
    code = main(["metrology", "wearmap", str(w), "--before", str(b), "--out", str(out)])
    msg = " ".join(capsys.readouterr().err.split())
    assert code == 3, msg
    assert re.search(r"could change the worn volume \([\d.]+ mm³\) by up to [\d.]+ mm³", msg)
    argv = shlex.split(msg.split("run: ")[1])
    assert argv[:3] == ["jointwear", "metrology", "wearmap"] and "--unworn" in argv
    code = main(argv[1:])
    again = " ".join(capsys.readouterr().err.split())
    if code == 0:
        z = standardised(io.load(out), truth_values(wear, Z, TH))
        assert all(abs(v) < 3.0 for v in z.values()), z
    else:
        assert code == 3 and "the points given as unworn" in again, again


# -- the maximum depth's extreme-value bias (issue 38 item 8) ------------------------------


def test_max_depth_of_a_flat_top_is_not_biased_up_by_noise():
    """A flat-topped wear (1 um over 40 degree, the worst case) with 20 nm noise: the maximum
    of the averaged map reads the top plus the expected maximum of its noisy values (about 27
    independent ones: +2 sigma of the average, +1.0 u); less its extreme-value bias, simulated
    on the map's own top, the mean standardised error over 150 noise realisations is +0.56
    (closed-form truth: the top is 1 um). The noisy top is more ragged than the truth's, so
    the simulation is short there; peaked grooves read -0.03 u on average (benchmark)."""
    from jointwear.metrology.wear_quantities import derived_quantities

    nt, sigma = 720, 20e-9
    th = np.arange(nt) * 360.0 / nt
    d = np.abs((th - 180.0 + 180.0) % 360.0 - 180.0)
    top = np.where(d < 20.0, 1e-6, 1e-6 * np.exp(-0.5 * ((d - 20.0) / 5.0) ** 2))[None, :]
    z0, wts = np.zeros(1), np.full((1, nt), 1e-9)
    rng = np.random.default_rng(3)
    z, raw = [], []
    for _ in range(150):
        wear = top + sigma * rng.standard_normal(top.shape)
        args = (np.zeros_like(wear), sigma**2, 1.0, np.zeros(1), np.zeros((1, 1)), wts, z0, th)
        v, u, _ = derived_quantities(wear, *args, noise=sigma)["max_wear_depth"]
        v0, _, _ = derived_quantities(wear, *args)["max_wear_depth"]  # no correction
        z.append((v - 1e-6) / u)
        raw.append((v0 - 1e-6) / u)
    assert np.mean(raw) > 0.8  # the uncorrected maximum reads high: the test can fail
    assert np.mean(z) < min(0.7, np.mean(raw) - 0.3), (np.mean(z), np.mean(raw))
