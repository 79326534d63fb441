"""The demo's measured side, generated with a known truth (used by :mod:`.demo`).

The synthetic bore's roundness scans (the "true" wear: the simulated map 10 % deeper and turned
by 6 degree, :func:`measured_wear_function`), read and made into wear maps as a user would, and
the stereo footage of a virtual rig whose crank runs :data:`MOTION_SPEED_FACTOR` faster than
the simulated one, calibrated and tracked through :mod:`jointwear.dic`.
"""

from __future__ import annotations

import importlib
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import xarray as xr

from jointwear import io

if TYPE_CHECKING:
    from jointwear.reports.demo import DemoSize

__all__ = [
    "INSTRUMENT_CONVENTION",
    "MEASURED_ROTATION_DEG",
    "MEASURED_SCALE",
    "MOTION_SPEED_FACTOR",
    "measured_wear_function",
    "rig_speed_rpm",
]

#: How the plausible "measured" wear map is made from the simulated one.
MEASURED_SCALE = 1.10
MEASURED_ROTATION_DEG = 6.0
#: The virtual rig's crank runs this much faster than the simulated one: the motion truth is not
#: the simulated linkage's own kinematics but a rig whose drive speed differs within its
#: tolerance (0.5 %, inside a drive's usual ±1 % speed regulation).
MOTION_SPEED_FACTOR = 1.005
INSTRUMENT_CONVENTION = ("+y", "counterclockwise")


def _say(msg: str) -> None:
    import typer

    typer.echo(msg, err=True)


def _available(module: str, *names: str) -> bool:
    try:
        mod = importlib.import_module(module)
    except ImportError:
        return False
    return all(hasattr(mod, n) for n in names)


def measured_wear_function(sim_wear: xr.Dataset) -> Any:
    """The demo's "true" wear of the tested bearing, built from the simulated map [m].

    ``h(theta, z) = 1.10 h_sim(theta - 6 degree, z)``: 10 % deeper and turned by 6 degree
    (:func:`jointwear.datasets.simulated_wear.wear_from_simulation`, the same function as
    ``jointwear datasets instruments --wear-from``).
    """
    from jointwear.datasets.simulated_wear import wear_from_simulation

    return wear_from_simulation(sim_wear, scale=MEASURED_SCALE, rotation_deg=MEASURED_ROTATION_DEG)


def _measure_wear(
    folder: Path, sim_wear_path: Path, size: DemoSize, *, cycles: float = 0.0, tag: str = ""
) -> tuple[Path, Path]:
    """The synthetic bore scanned at ``cycles`` (default ``size.cycles``) and its wear map
    ``metrology_wear<tag>.nc``; the before-scan is written once (``talyrond_before``)."""
    from jointwear.datasets import instruments
    from jointwear.metrology import wear_map
    from jointwear.metrology.readers import read_talyrond

    sim_wear = io.load(sim_wear_path)
    t0 = time.perf_counter()
    cycles = cycles or size.cycles
    # an earlier snapshot's scan: the bearing mounted once more, its own instrument noise
    mounting = {"eccentricity": (7e-6, -3e-6), "tilt": (-0.4e-3, 0.6e-3)} if tag else {}
    scan = instruments.generate(
        n_layers=13,
        n_points=size.instrument_points,
        radius=float(sim_wear.attrs.get("bearing_radius_m", 8e-3)),
        wear=measured_wear_function(sim_wear),
        convention=INSTRUMENT_CONVENTION,
        seed=2023,
        noise_seed=2026 if tag else 2024,
        **mounting,
    )
    raw = folder / f"talyrond_worn{tag}"
    raw_before = folder / "talyrond_before"
    instruments.write(scan, raw, layout="folder")
    if not (tag and raw_before.exists()):  # the earlier snapshot's map reuses the compared one's
        _write_before(raw_before, size, float(sim_wear.attrs.get("bearing_radius_m", 8e-3)))
    # the user's side: import the instrument files (stating where its 0 degree is) ...
    worn_ds = read_talyrond(raw, convention=INSTRUMENT_CONVENTION)
    before_ds = read_talyrond(raw_before, convention=INSTRUMENT_CONVENTION)
    # ... and compute the wear map against the before-scan (set-up change fitted and removed)
    wm = wear_map(worn_ds, before_ds)
    wm.attrs.update(
        {
            "title": "measured wear map of the bearing bore (virtual Talyrond scan)",
            "cycles": float(cycles),
            "source": "synthetic: virtual Talyrond 565H scans (jointwear.datasets.instruments)",
        }
    )
    out = io.save(
        wm,
        folder / f"metrology_wear{tag}.nc",
        inputs=[raw, raw_before],
        parameters={
            "instrument_convention": list(INSTRUMENT_CONVENTION),
            "measured_wear": {
                "scale": MEASURED_SCALE,
                "rotation_deg": MEASURED_ROTATION_DEG,
            },
        },
        parents=[sim_wear],
    )
    _say(
        f"  measured wear map at {cycles:g} cycles: 13 layers x {size.instrument_points} points, "
        f"worn and before-wear scans read from {raw.name}/ and {raw_before.name}/ "
        f"({time.perf_counter() - t0:.0f} s)"
    )
    return out, raw


def _write_before(raw_before: Path, size: DemoSize, radius: float) -> None:
    """The bearing's scan before the test (written once; every wear map is made against it)."""
    from jointwear.datasets import instruments

    # the same bearing scanned before the test, mounted again (another eccentricity and tilt)
    before = instruments.generate(
        n_layers=13,
        n_points=size.instrument_points,
        radius=radius,
        wear=None,
        convention=INSTRUMENT_CONVENTION,
        eccentricity=(-5e-6, 12e-6),
        tilt=(0.5e-3, 1.0e-3),
        seed=2023,  # same bore form ...
        noise_seed=2025,  # ... but independent instrument noise in the second scan
    )
    instruments.write(before, raw_before, layout="folder")


def _rig_out_of_plane(sim_motion: xr.Dataset, crank_angle0_deg: float) -> tuple[float, float]:
    """Amplitude [m] and phase [degree] of joint C's out-of-plane motion for the virtual rig.

    The virtual rig prescribes ``z_C(t) = A sin(omega t + phase)``. The demo takes the first
    harmonic (in crank angle) of the simulated follower centre's z motion over the last whole
    cycle; the follower hangs on the ball joint D, so joint C moves twice as far as its centre.
    """
    phi = np.unwrap(np.asarray(sim_motion["crank_angle"].values, dtype=float))
    z = np.asarray(sim_motion["follower_position"].sel(axis="z").values, dtype=float)
    last = phi >= phi[-1] - 2 * np.pi
    a = np.column_stack([np.sin(phi[last]), np.cos(phi[last]), np.ones(last.sum())])
    (s, c, _), *_ = np.linalg.lstsq(a, z[last], rcond=None)
    amplitude = 2.0 * float(np.hypot(s, c))
    beta = float(np.degrees(np.arctan2(c, s)))  # z ~ B sin(phi + beta)
    # rig: sin(omega t + phase) with crank angle phi = phi0 + omega t  ->  phase = beta + phi0
    return amplitude, (beta + crank_angle0_deg) % 360.0


def rig_speed_rpm(sim_motion: xr.Dataset) -> float:
    """The virtual rig's crank speed [rev/min]: the simulated crank's mean speed (a straight
    line through its unwrapped angle) times :data:`MOTION_SPEED_FACTOR`."""
    t = np.asarray(sim_motion["time"].values, dtype=float)
    phi = np.unwrap(np.asarray(sim_motion["crank_angle"].values, dtype=float))
    omega = float(np.polyfit(t, phi, 1)[0])
    return abs(omega) * 60.0 / (2.0 * np.pi) * MOTION_SPEED_FACTOR


def _measure_motion(
    folder: Path, size: DemoSize, sim_motion_path: Path | None
) -> tuple[Path | None, str | None]:
    """Stereo footage of the virtual rig, calibrated and tracked through jointwear.dic."""
    if not (
        _available("jointwear.datasets.rig", "generate_rig", "RigConfig")
        and _available(
            "jointwear.dic", "track_footage", "read_bodies", "calibrate_stereo", "CalibrationBoard"
        )
    ):
        return None, (
            "motion: the stereo DIC chain (jointwear.datasets.rig, jointwear.dic footage "
            "tracking) is not available in this installation, so the simulated motion was not "
            "compared with measured motion"
        )
    if size.rig_size is None:
        return None, (
            "motion: skipped with --quick (rendering, calibrating and tracking the stereo "
            "footage takes about a minute); run 'jointwear demo' without --quick to include it"
        )
    if sim_motion_path is None:
        return None, "motion: nothing to compare the footage with (no simulated motion)"
    from jointwear.datasets.rig import RigConfig, generate_rig
    from jointwear.dic import CalibrationBoard, calibrate_stereo, read_bodies, track_footage

    t0 = time.perf_counter()
    sim_motion = io.load(sim_motion_path)
    base = RigConfig()
    amplitude, phase = _rig_out_of_plane(sim_motion, base.crank_angle0_deg)
    rpm = rig_speed_rpm(sim_motion)
    width, height = size.rig_size
    cfg = RigConfig(
        width=width,
        height=height,
        duration=size.rig_duration,
        z_amplitude=amplitude,
        z_phase_deg=phase,
        crank_speed_rpm=rpm,
        seed=7,
    )
    rig = folder / "rig"
    written = generate_rig(rig, cfg, video=False, images=True)
    board = CalibrationBoard(
        "chessboard", cfg.board_squares[0], cfg.board_squares[1], cfg.board_square_size
    )

    def images(cam: str) -> list[Path]:
        return sorted((written["calibration"] / cam).glob("*.png"))

    lefts, rights = images("left"), images("right")
    cal = calibrate_stereo(lefts, rights, board, world_view=len(lefts) - 1)
    cal_path = folder / "calibration.nc"
    cal.save(cal_path, inputs=[written["calibration"]], parameters={"board": board.__dict__})
    track_cfg, bodies = read_bodies(written["bodies"])
    out = folder / "dic_motion.nc"
    track_footage(
        written["left_images"],
        written["right_images"],
        bodies=bodies,
        calibration=cal,
        config=track_cfg,
        fps=cfg.fps,
        out=out,
        inputs=(written["left_images"], written["right_images"], written["bodies"], cal_path),
    )
    # the footage was rendered, not filmed: the tracked motion is synthetic (data contract)
    tracked = io.load(out)
    tracked.attrs["data_origin"] = "synthetic"
    io.save(tracked, out, command="jointwear demo (the footage is rendered: data_origin synthetic)")
    _say(
        f"  measured motion: {cfg.n_frames} stereo frames of {width} x {height} px rendered, "
        f"calibrated ({cal.rms:.3f} px RMS) and tracked ({time.perf_counter() - t0:.0f} s)"
    )
    return out, None


def _in_plane(ds: xr.Dataset) -> xr.Dataset:
    """The DIC record's follower velocity, in-plane components only (see the demo notes)."""
    keep = [v for v in ("follower_velocity", "follower_velocity_u") if v in ds]
    return ds[keep].sel(axis=["x", "y"])
