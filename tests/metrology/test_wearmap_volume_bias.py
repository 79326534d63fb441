"""Worn volume with a before-scan on the reference study's full scan size (13 x 18000 points):
no systematic offset beyond its stated uncertainty.

On that many points u(volume) is a fraction of a nanometre times the bore's area, so a
selection of the unworn points that is one-sided in the noise (the high tail dropped, the low
tail kept) biased the volume high by 1-3.5 u (2-4 % in the issue-20 power study) while a
coverage check on small maps (13 x 1440) could not see it. The input here is that of the power
study: virtual Talyrond scans (instrument noise 20 nm, 1 nm quantisation, form, a change of
set-up between the scans) written and read back, then :func:`wear_map` with the before-scan.
"""

from __future__ import annotations

import numpy as np

from jointwear.datasets.instruments import generate, write
from jointwear.metrology.readers import read_talyrond
from jointwear.metrology.wearmap import wear_map, worn_volume

CONV = ("+y", "counterclockwise")
SEEDS = (0, 1, 2, 3)


def _z_scores(tmp_path, depth):
    common = {"n_layers": 13, "n_points": 18000, "radius": 8e-3, "convention": CONV, "seed": 7}

    def wear(theta_deg, z):  # a patch 80 degree wide at 100 degree, deeper at one end
        dth = (np.asarray(theta_deg) - 100.0 + 180.0) % 360.0 - 180.0
        patch = np.where(np.abs(dth) < 40.0, np.cos(np.radians(dth) * 90.0 / 40.0) ** 2, 0.0)
        return depth * patch * (0.6 + 0.4 * (np.asarray(z) + 6e-3) / 12e-3)

    out = []
    for s in SEEDS:
        worn = generate(**common, wear=wear, noise_seed=100 + s)
        before = generate(
            **common,
            wear=None,
            eccentricity=(-5e-6, 12e-6),
            tilt=(0.5e-3, 1e-3),
            noise_seed=200 + s,
        )
        paths = []
        for name, scan in (("worn", worn), ("before", before)):
            write(scan, tmp_path / f"{name}{s}", layout="folder")
            paths.append(read_talyrond(tmp_path / f"{name}{s}", convention=CONV))
        wm = wear_map(*paths)
        t = worn.truth
        truth = worn_volume(t.wear_depth.values, t.z.values, t.theta.values, 8e-3)
        out.append((truth - wm.worn_volume.item()) / wm.worn_volume_u.item())
    return np.asarray(out)


def test_worn_volume_with_a_before_scan_has_no_offset_beyond_u(tmp_path):
    z = _z_scores(tmp_path, 1e-6)
    # each within 2 u; their mean, N(0, 1/n) if u holds, within 2/sqrt(n). Before: -1.9 to
    # -3.5 each (every replicate read 0.2-0.35 nm x area high: one-sided noise rejection, and
    # the worn scan's axis fitted to its unworn arc alone)
    assert np.all(np.abs(z) < 2.0), z
    assert abs(z.mean()) < 2.0 / np.sqrt(z.size), z


def test_faint_tails_of_a_wide_groove_do_not_hide_volume_beyond_u():
    """Gaussian grooves 30-37 degree wide (sigma) leave wear below the noise far around the
    bore among the unworn points; it pulls the reference up and the volume read 2.6-3.1 u low
    (the one-sided noise rejection used to offset part of that). The faint-tail correction
    (twice the change when a further 10 degree band is left out) brings it within 2 u."""
    from test_wearmap_form import TH, R, Z, _bore

    z = []
    for k, (depth, width, centre) in enumerate(
        [(8.0, 37, 40.0), (0.3, 33, 200.0), (3.0, 30, 300.0)]
    ):
        worn, wear = _bore(20, 0.5, depth, width, seed=300 + k, centre_deg=centre)
        before, _ = _bore(20, 0.5, 0.0, width, seed=600 + k, centre_deg=centre)
        out = wear_map(worn, before)
        z.append(
            (out["worn_volume"].item() - worn_volume(wear, Z, TH, R)) / out["worn_volume_u"].item()
        )
    assert np.all(np.abs(z) < 2.0), z
    assert abs(np.mean(z)) < 2.0 / np.sqrt(len(z)), z
