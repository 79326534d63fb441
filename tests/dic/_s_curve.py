"""The sub-pixel bias ("S-curve") of the 2D engine: noise-free 8-bit speckle shifted along x by
sub-pixel amounts, matched with the central-difference image gradients the engine uses or with
the interpolant's exact derivative. Shared by tests/dic/test_icgn_gradients.py and
benchmarks/bench_field.py."""

from __future__ import annotations

import dataclasses

import numpy as np

from jointwear.datasets import speckle as sp
from jointwear.dic import SubsetCorrelator
from jointwear.dic.icgn._interp import prefilter


def s_curve(
    speckle_size: float, gradient: str, shifts: np.ndarray, size: int
) -> tuple[np.ndarray, np.ndarray]:
    """Mean error of u [pixel] at each shift [pixel], and the fraction of subsets matched.

    ``gradient``: ``"central"`` (the engine's) or ``"spline"`` (the quintic interpolant's exact
    derivative); ``size`` x ``size`` images, 21-pixel subsets every 6 pixels, seed 7.
    """
    params = sp.SpeckleParams(speckle_size=speckle_size)
    errors, matched = [], []
    for s in shifts:
        pair = sp.speckle_pair((size, size), sp.RigidField((s, 0.0)), params=params, seed=7)
        corr = SubsetCorrelator(pair.reference, subset_size=21, step=6)
        if gradient == "spline":
            ref = prefilter(corr.reference_raw, "quintic", gradient="spline")
            corr.ref = dataclasses.replace(corr.ref, gx=ref.gx, gy=ref.gy)
        ds = corr.correlate(pair.deformed, initial_guess=np.array([s, 0.0]))
        errors.append(float(np.nanmean(ds.u.values - s)))
        matched.append(float((ds.flag.values == 0).mean()))
    return np.array(errors), np.array(matched)
