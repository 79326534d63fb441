"""Sizes of the reference-study run, :class:`StudySize` with :data:`FULL` and :data:`REDUCED`
(public from :mod:`jointwear.datasets.reference_study`): one source for the library and
``jointwear datasets reference-study``, whose help states them (light: no numpy)."""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["FULL", "REDUCED", "StudySize"]


@dataclass(frozen=True)
class StudySize:
    """Size of the reference-study run.

    Parameters
    ----------
    layers, points : int
        Bearing grid (layers over the width, points per layer).
    levels : tuple of int
        Fixed wear-update intervals dN [cycles] of the verification study, coarse to fine; the
        last (finest) is the compared simulation.
    ensemble_runs : int
        Members of the input-uncertainty ensemble (0: none, u_input not assessed).
    ensemble_dn : int
        Update interval of the ensemble members [cycles].
    seed : int
        Seed of the Latin hypercube.
    training_runs : int
        Training runs of the calibration on the 4e5 growth (the emulator's design).
    prediction_runs : int
        Simulations at posterior samples run to 1.2e6 cycles (the validated prediction).
    """

    layers: int = 20
    points: int = 200
    levels: tuple[int, ...] = (100_000, 50_000, 25_000)
    ensemble_runs: int = 10
    ensemble_dn: int = 50_000
    seed: int = 11
    training_runs: int = 32  # 20 left the emulator's error at 0.81 of the datum's u (refused)
    prediction_runs: int = 6


#: the benchmark's size: the study's grid (20 x 200)
FULL = StudySize()
#: the CI test's size: a coarse grid, coarse intervals, three members
REDUCED = StudySize(
    layers=8,
    points=72,
    levels=(400_000, 200_000, 100_000),
    ensemble_runs=3,
    ensemble_dn=400_000,
    training_runs=16,
    prediction_runs=4,
)
