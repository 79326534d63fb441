"""Footage tracking: the options (``[track]``), bodies (``[bodies.<name>]``) and frame flags."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal

from jointwear.errors import ParameterError
from jointwear.params import from_mapping, read_toml

__all__ = ["BodySpec", "TrackConfig", "read_bodies", "FRAME_FLAGS"]

#: Frame quality flags (bit mask) of the ``frame_flag`` output variable.
FRAME_FLAGS = {
    "ok": 0,
    "duplicated": 1,
    "after_gap": 2,
    "tracking_failed": 4,
    "crank_step_gap": 8,
}


@dataclass(frozen=True, eq=False)
class BodySpec:
    """A tracked rigid body.

    Parameters
    ----------
    name : str
        Body name (``follower``, ``journal``, ``crank``, ...).
    role : {"follower", "journal", "bearing", "crank", "other"}
        What the body is: the follower's centroid velocity, the journal's displacement and the
        crank's angle go into the contract variables; with a journal and a bearing (whose
        ``centroid`` is the bearing centre) the journal's offset in the bearing frame is given.
    polygon : list of [x, y]
        Region of interest in the left reference image [pixel] (3 or more vertices).
    centroid : [x, y, z] or None
        Body-fixed point whose motion is reported, in the world frame at the reference frame
        [m] (the follower's centre of mass). Default: the centroid of the tracked points.
    centroid_mechanism : [x, y, z] or None
        The same in the mechanism frame, used when the calibration's world frame is a board on
        the mechanism plane (the point is shifted by the board origin given in ``world_origin``).
    reference_angle_deg : float
        Crank angle at the reference frame [degree] (crank bodies).
    """

    name: str
    role: Literal["follower", "journal", "bearing", "crank", "other"] = "other"
    polygon: list[list[float]] = field(default_factory=list)
    centroid: list[float] | None = None
    centroid_mechanism: list[float] | None = None
    reference_angle_deg: float = 0.0


@dataclass(frozen=True, eq=False)
class TrackConfig:
    """Options of ``jointwear dic track`` (TOML table ``[track]``).

    Parameters
    ----------
    subset_size : int
        Subset side [pixel] (odd).
    step : int
        Grid spacing of the subsets in each region [pixel].
    chunk_size : int
        Frames per processing chunk (results are saved after each chunk).
    zncc_min : float
        Matches below this ZNCC are discarded.
    max_epipolar_px : float
        Stereo matches farther from the epipolar line are discarded [pixel]. The SIFT matches
        that start stereo tracking use the same gate, but at least 3 px. Raise it (CLI
        ``--max-epipolar-px``) only for a calibration known to be off its images by that much
        (the error message measures the offset).
    min_points : int
        Fewest valid points for a body's pose in a frame (fewer: the frame is flagged).
    velocity_window, velocity_order : int
        Savitzky–Golay differentiator (samples, polynomial degree).
    sigma_px : float
        Standard uncertainty of one subset match [pixel] used for the propagated uncertainty
        (0: estimated from the image noise and the subset's intensity gradients).
    duplicate_threshold : float
        Consecutive frames whose mean absolute difference is below this [grey level] are
        reported as duplicates.
    interpolation : {"cubic", "quintic"}
        B-spline interpolation of the tracked frames. Quintic (default): on rendered 3 px
        speckle its 21 px subsets err 0.0024 px RMS against cubic's 0.0042 px (systematic part
        0.0004 vs 0.0024 px; equal at 5 px speckle), for 19 % more tracking time on the virtual
        rig (9.2 vs 10.9 s, whose outputs do not change: the differentiator and the image noise
        dominate there); ``benchmarks/bench_stereo_interp.py``. Cubic for speed with coarse
        speckle.
    world_origin : [x, y, z]
        Mechanism-frame position of the world origin (the calibration board's first inner
        corner), used to place ``centroid_mechanism`` [m].
    max_reinit : int
        Most SIFT re-initialisations per body after tracking was lost (chunk starts do not
        count); beyond, lost frames are flagged ``tracking_failed`` without another attempt.
        0: never re-initialise. Each one is recorded (``<body>_reinitialised``).
    data_origin : str
        What the footage is: ``"measured"`` (filmed on a rig) or ``"synthetic"`` (rendered,
        e.g. by ``jointwear datasets rig``, which writes it); empty: not stated. Recorded as
        the result's ``data_origin``, which the validation report shows.
    workers : int
        Processes working on chunks in parallel (1: sequential, tracking carried across
        chunks; >1: each chunk starts from SIFT features of the reference images).
    """

    subset_size: int = 21
    step: int = 10
    chunk_size: int = 50
    zncc_min: float = 0.8
    max_epipolar_px: float = 1.0
    min_points: int = 6
    velocity_window: int = 9
    velocity_order: int = 5
    sigma_px: float = 0.0
    duplicate_threshold: float = 0.05
    interpolation: Literal["cubic", "quintic"] = "quintic"
    world_origin: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])
    workers: int = 1
    max_reinit: int = 50
    data_origin: str = ""

    def __post_init__(self) -> None:
        if self.data_origin not in ("", "measured", "synthetic"):
            raise ParameterError(
                f"track.data_origin={self.data_origin!r}: expected 'measured' or 'synthetic'"
            )
        if self.subset_size < 7 or self.subset_size % 2 == 0:
            raise ParameterError(
                f"track.subset_size={self.subset_size}: expected an odd integer >= 7"
            )
        if self.interpolation not in ("cubic", "quintic"):
            raise ParameterError(
                f"track.interpolation={self.interpolation!r}: expected 'cubic' or 'quintic'"
            )
        if self.max_reinit < 0:
            raise ParameterError(f"track.max_reinit={self.max_reinit}: expected >= 0")
        if not self.max_epipolar_px > 0:
            raise ParameterError(
                f"track.max_epipolar_px={self.max_epipolar_px}: expected a positive distance [px]"
            )
        if self.workers < 1:
            raise ParameterError(f"track.workers={self.workers}: expected >= 1")
        if self.step < 1 or self.chunk_size < 1 or self.min_points < 3:
            raise ParameterError("track.step and chunk_size must be >= 1, min_points >= 3")
        if self.velocity_window % 2 == 0 or self.velocity_window <= self.velocity_order:
            raise ParameterError(
                f"track.velocity_window={self.velocity_window} must be odd and larger than "
                f"velocity_order={self.velocity_order}"
            )


def read_bodies(path: str | Path) -> tuple[TrackConfig, list[BodySpec]]:
    """Read the regions-of-interest TOML file: ``[track]`` options and ``[bodies.<name>]``."""
    data = read_toml(path)
    unknown = [k for k in data if k not in ("track", "bodies")]
    if unknown:
        raise ParameterError(
            f"'{path}': unknown table(s) {unknown}; expected [track] and [bodies.<name>]"
        )
    cfg = from_mapping(TrackConfig, data.get("track", {}), where="track")
    bodies = []
    for name, spec in data.get("bodies", {}).items():
        spec = dict(spec)
        body = from_mapping(BodySpec, {"name": name, **spec}, where=f"bodies.{name}")
        if len(body.polygon) < 3:
            raise ParameterError(
                f"'{path}': bodies.{name}.polygon needs at least 3 [x, y] vertices in pixels of "
                "the left reference image"
            )
        bodies.append(body)
    if not bodies:
        raise ParameterError(f"'{path}' defines no [bodies.<name>] with a polygon")
    return cfg, bodies
