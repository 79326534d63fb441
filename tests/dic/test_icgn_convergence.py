"""The IC-GN's convergence test: the classic step criterion and the propagation's measured
contraction (a point stops when the predicted remaining error, contraction x step, is below the
tolerance). Truth: the same matches iterated to a tolerance of 1e-9 px, and the synthetic
displacement field."""

from __future__ import annotations

from dataclasses import asdict

import numpy as np
import pytest

from jointwear.datasets import speckle as sp
from jointwear.dic import CorrelationParams, SubsetCorrelator
from jointwear.dic.icgn._drive import CONTRACTION_FLOOR
from jointwear.dic.icgn._solve import make_work, solve_point


def _edge_norm(d: np.ndarray, half: int) -> np.ndarray:
    """Size of parameter differences (N, 12) in pixels at the subset's edge (affine terms)."""
    grad = d[:, 1] ** 2 + d[:, 2] ** 2 + d[:, 7] ** 2 + d[:, 8] ** 2
    return np.sqrt(d[:, 0] ** 2 + d[:, 6] ** 2 + half * half * grad)


def _run(field, speckle: dict, **options):
    pair = sp.speckle_pair((192, 192), field, params=sp.SpeckleParams(**speckle), seed=4)
    base = {"subset_size": 29, "step": 6, "threads": 1, **options}
    corr = SubsetCorrelator(pair.reference, params=CorrelationParams(**base))
    res = corr.match(pair.deformed)
    strict = SubsetCorrelator(
        pair.reference,
        params=CorrelationParams(**{**base, "tolerance": 1e-9, "max_iterations": 200}),
    ).match(pair.deformed, initial_guess=res.params.copy())
    return pair, corr, res, strict


@pytest.mark.parametrize(
    ("field", "speckle", "options"),
    [
        (sp.RigidField((3.3, -2.7)), {"noise_std": 2.0}, {}),
        (sp.RigidField((1.0, 0.5), theta_deg=4.0, center=(96, 96)), {"noise_std": 2.0, "speckle_size": 3.0}, {}),
        (sp.SinusoidalField((1.5, 0.5), 80.0), {"noise_std": 2.0}, {"shape": "quadratic"}),
        (sp.RigidField((0.4, -2.2)), {"noise_std": 5.0, "speckle_size": 4.0, "contrast": 0.3}, {"subset_size": 21}),
    ],
    ids=["shift-2gl", "rotation-3px", "quadratic-wave", "low-contrast-5gl"],
)  # fmt: skip
def test_stopping_early_moves_no_match_by_more_than_a_tenth_of_its_own_uncertainty(
    field, speckle, options
):
    """The matches of the default run (most points stopped by the measured contraction) agree
    with the fully converged ones within the tolerance at the subset's edge, and their (u, v)
    within 15 % of the point's own standard uncertainty (which then grows by < 1.2 %)."""
    _, corr, res, strict = _run(field, speckle, **options)
    ok = res.ok & strict.ok
    assert ok.sum() > 100  # the edge rows leave the image: not judged here
    d = res.params[ok] - strict.params[ok]
    assert _edge_norm(d, corr.params.half).max() < 4 * corr.params.tolerance
    duv = np.hypot(d[:, 0], d[:, 6])
    sigma = np.hypot(res.sigma[ok, 0], res.sigma[ok, 1])
    assert np.all(duv < 0.15 * sigma)


def test_a_noisy_shift_stops_after_one_iteration_and_keeps_its_accuracy():
    """On 2 grey levels of noise each neighbour's guess is off by the noise (more than the
    tolerance): the classic test takes every point through a second, verifying iteration; the
    measured contraction (a few per cent) stops nearly all after the first, and the errors
    against the true shift do not change."""
    pair, corr, res, strict = _run(sp.RigidField((3.3, -2.7)), {"noise_std": 2.0})
    ok = res.ok
    assert res.iterations[ok].mean() < 1.2
    tu, tv = pair.truth(corr.centres[:, 0], corr.centres[:, 1])
    err_default = np.hypot(res.params[ok, 0] - tu[ok], res.params[ok, 6] - tv[ok])
    err_strict = np.hypot(strict.params[ok, 0] - tu[ok], strict.params[ok, 6] - tv[ok])
    rms_default = np.sqrt(np.mean(err_default**2))
    rms_strict = np.sqrt(np.mean(err_strict**2))
    assert abs(rms_default / rms_strict - 1.0) < 0.01


def test_guessed_points_keep_the_classic_test():
    """Frame-to-frame use (every point guessed with the same 0.4 px offset, ``initial_guess``):
    the start offsets are common, so stopping short would be a bias; the guessed path keeps
    the classic test and its matches stay within 2e-4 px of full convergence in the mean."""
    pair = sp.speckle_pair((288, 288), sp.RigidField((3.3, -2.7)), seed=4)
    # more than 16 points in each of the 64 chunks of the parallel refinement
    corr = SubsetCorrelator(pair.reference, subset_size=29, step=5, threads=1)
    assert corr.n_points > 64 * 20
    guess = np.tile([3.0, -3.0], (corr.n_points, 1))
    res = corr.match(pair.deformed, initial_guess=guess)
    strict = SubsetCorrelator(
        pair.reference, params=CorrelationParams(**{**asdict(corr.params), "tolerance": 1e-9})
    ).match(pair.deformed, initial_guess=guess)
    ok = res.ok & strict.ok
    assert ok.sum() > 100
    assert abs(np.mean(res.params[ok, 0] - strict.params[ok, 0])) < 2e-5
    assert abs(np.mean(res.params[ok, 6] - strict.params[ok, 6])) < 2e-5


def test_a_large_contraction_keeps_the_iterations():
    """Where the contraction is large (second-order shape on a wave) the propagation does not
    assume the floor: points still take more than two iterations on average."""
    _, _, res, _ = _run(sp.SinusoidalField((2.0, 0.5), 60.0), {"noise_std": 2.0}, shape="quadratic")
    assert res.iterations[res.ok].mean() > 2.0


def test_solve_point_classic_test_and_assumed_contraction():
    """One point from a guess 0.3 px off: with ``rho = 1`` (classic) the last step is below the
    tolerance; with the floor contraction the point stops as soon as ``rho x step`` is, sooner
    or at the same iteration, and the two matches agree within the tolerance."""
    pair = sp.speckle_pair((128, 128), sp.RigidField((1.7, -0.4)), seed=2)
    corr = SubsetCorrelator(pair.reference, subset_size=31, step=16)
    dspl, dinv, _ = corr._prepare_deformed(pair.deformed)
    ref, dfm = corr._kernel_args(dspl, dinv)
    opts = corr._solver_options()
    tol = opts[3]
    i = corr.n_points // 2
    xc, yc = corr.centres[i]
    kappa = corr._kappa_of_points()[i]
    out = {}
    for rho in (1.0, CONTRACTION_FLOOR):
        p = np.zeros(12)
        p[0], p[6] = 1.4, -0.1
        work = make_work(opts[0])
        z, it, fl = solve_point(ref, dfm, opts, xc, yc, p, work, kappa, rho)
        assert fl == 0
        w = work[4]
        assert rho * w[3, 1] < tol  # the last step
        if it >= 2:
            assert not rho * w[3, 0] < tol  # the one before did not stop it
        if it >= 3:  # past its second step a point stops on the classic test only
            assert w[3, 1] < tol
        out[rho] = (p.copy(), it)
    assert out[CONTRACTION_FLOOR][1] <= out[1.0][1]
    d = out[1.0][0] - out[CONTRACTION_FLOOR][0]
    assert _edge_norm(d[None, :], opts[0])[0] < tol
    tu, tv = pair.truth(xc, yc)
    assert abs(out[1.0][0][0] - tu) < 0.01 and abs(out[1.0][0][6] - tv) < 0.01


def test_a_point_that_never_converges_is_not_stopped_on_the_assumed_contraction():
    """Weak texture (contrast 0.05, 2 grey levels of noise): some points wander without
    converging in 40 iterations under the classic test. None of them is reported ok by the
    default run, whose assumed contraction applies to a point's first two steps only (a
    wandering point's step, sometimes small, would otherwise stop it at a random place)."""
    pair = sp.speckle_pair(
        (256, 256),
        sp.RigidField((0.4, -0.3)),
        params=sp.SpeckleParams(contrast=0.05, noise_std=2.0),
        seed=5,
    )
    out = {}
    for probes in (0, None):  # 0: the classic test throughout; None: the default
        corr = SubsetCorrelator(pair.reference, subset_size=21, step=6, threads=1, zncc_min=0.5)
        corr._contraction_probes = probes
        out[probes] = corr.match(pair.deformed)
    classic, default = out[0], out[None]
    wandering = classic.flag == 1  # not_converged
    assert wandering.sum() >= 5
    assert not np.any(default.ok & ~classic.ok)
