"""Wear map without a before-scan (issue 22): outcome and coverage over random tapered, lobed
bores with a known wear groove, and the time of one map at the reference size (13 x 18000).

Each bore (taper 0-40 µm over the band, lobing 0-2 µm at 2 and 3 UPR drifting along z, a
Gaussian groove 0.3-8 µm deep and 8-35 degree wide at a random angle, 20 nm probe noise, an
eccentric tilted set-up) is either refused (exit 3, asking for --before) or mapped; for a map
the standardised errors (estimate - truth) / u of the worn volume and the maximum depth are
collected. A map outside 3 u is an exit-0 misread and is counted. The signed mean of the
volume's standardised errors shows a systematic offset (N(0, 1/n) if u holds).

At the reference study's size (13 x 18000, generator scans with an exact set-up, form, 20 nm
noise, 1 nm quantisation, a before-scan with another set-up): (truth - D) / u of the volume for
three grooves (a cos^2 patch, Gaussians 10 and 20 degree wide) over noise realisations, and the
relative error of the noise-free maps.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT.parent / "tests" / "metrology"))

from _common import write_results  # noqa: E402
from test_wearmap_form import TH, R, Z, _bore  # noqa: E402
from test_wearmap_truth import GROOVES, _pair  # noqa: E402

from jointwear.errors import BadInputError  # noqa: E402
from jointwear.metrology.wearmap import wear_map, worn_volume  # noqa: E402


def main(n_cases: int = 40) -> None:
    rng = np.random.default_rng(123)
    z_scores, refused, misread, mapped, z_vol = [], 0, 0, 0, []
    for i in range(n_cases):
        taper = rng.uniform(0, 40)
        lobe = float(rng.choice([0, 0.3, 1.0, 2.0]))
        depth = float(rng.choice([0.3, 1, 3, 8]))
        width = rng.uniform(8, 35)
        centre = rng.uniform(0, 360)
        scan, wear = _bore(taper, lobe, depth, width, seed=100 + i, centre_deg=centre)
        try:
            out = wear_map(scan)
        except BadInputError:
            refused += 1
            continue
        mapped += 1
        zv = (out["worn_volume"].item() - worn_volume(wear, Z, TH, R)) / out["worn_volume_u"].item()
        zm = (out["max_wear_depth"].item() - wear.max()) / out["max_wear_depth_u"].item()
        z_scores += [zv, zm]
        z_vol.append(zv)
        misread += abs(zv) > 3 or abs(zm) > 3
    # with a before-scan (same bore, another noise realisation): grooves up to 45 degree wide
    rng = np.random.default_rng(7)
    zb, refused_b, misread_b, zb_vol = [], 0, 0, []
    for i in range(25):
        taper, lobe = rng.uniform(0, 40), float(rng.choice([0, 0.5, 1.5]))
        depth, width = float(rng.choice([0.3, 1, 3, 8])), rng.uniform(8, 45)
        centre = rng.uniform(0, 360)
        worn, wear = _bore(taper, lobe, depth, width, seed=300 + i, centre_deg=centre)
        before, _ = _bore(taper, lobe, 0.0, width, seed=600 + i, centre_deg=centre)
        try:
            out = wear_map(worn, before)
        except BadInputError:
            refused_b += 1
            continue
        zv = (out["worn_volume"].item() - worn_volume(wear, Z, TH, R)) / out["worn_volume_u"].item()
        zm = (out["max_wear_depth"].item() - wear.max()) / out["max_wear_depth_u"].item()
        zb += [zv, zm]
        zb_vol.append(zv)
        misread_b += abs(zv) > 3 or abs(zm) > 3
    full = _reference_size()
    # time of one map at the reference size
    from jointwear.datasets.instruments import generate

    sc = generate(n_layers=13, n_points=18000, seed=1, noise_seed=2)
    t = time.perf_counter()
    try:
        wear_map(sc.truth[["radius"]])
        outcome = "mapped"
    except BadInputError as exc:  # the generator's bore has form up to 12 UPR
        outcome = f"refused: {str(exc)[:80]}"
    t_ref = time.perf_counter() - t
    write_results(
        "wearmap_form",
        {
            "cases": n_cases,
            "grid": f"{Z.size} layers x {TH.size} points",
            "mapped": mapped,
            "refused": refused,
            "misread_outside_3u": int(misread),
            "rms_standardised_error": float(np.sqrt(np.mean(np.square(z_scores)))),
            "mean_standardised_volume_error": float(np.mean(z_vol)),
            "max_abs_standardised_error": float(np.max(np.abs(z_scores))),
            "before_cases": 25,
            "before_refused": refused_b,
            "before_misread_outside_3u": int(misread_b),
            "before_rms_standardised_error": float(np.sqrt(np.mean(np.square(zb)))),
            "before_mean_standardised_volume_error": float(np.mean(zb_vol)),
            **full,
            "seconds_13x18000_default_wear": t_ref,
            "outcome_13x18000_default_wear": outcome,
        },
    )


def _reference_size(seeds=(1, 2, 3)) -> dict:
    """(truth - D) / u of the volume at 13 x 18000 with a before-scan, and noise-free errors."""
    z, rel = [], []
    for wear in GROOVES.values():
        worn, before, truth, _ = _pair(wear, 0, noisy=False)
        rel.append(abs(wear_map(worn, before)["worn_volume"].item() / truth - 1.0))
        for seed in seeds:
            worn, before, truth, _ = _pair(wear, seed)
            out = wear_map(worn, before)
            z.append((truth - out["worn_volume"].item()) / out["worn_volume_u"].item())
    return {
        "before_13x18000_grooves": list(GROOVES),
        "before_13x18000_volume_truth_minus_D_over_u": z,
        "before_13x18000_max_abs": float(np.max(np.abs(z))),
        "before_13x18000_mean": float(np.mean(z)),
        "before_13x18000_rms": float(np.sqrt(np.mean(np.square(z)))),
        "before_13x18000_noise_free_max_relative_error": float(np.max(rel)),
    }


if __name__ == "__main__":
    main()
