"""Footage tracking: the result dataset, its file, and resuming a partial result."""

from __future__ import annotations

import json
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from jointwear.dic.footage._config import FRAME_FLAGS, TrackConfig
from jointwear.dic.footage._rigid import (
    derivative_truncation,
    position_noise,
    rotation_angle_z,
    time_derivative,
)
from jointwear.dic.footage._video import FrameSource
from jointwear.errors import BadInputError

#: tracking options that may change between a partial run and its resumption
_RESUMABLE_CHANGES = ("workers", "chunk_size")


def _load_partial(out, L: FrameSource, R: FrameSource | None, cfg, bodies) -> xr.Dataset | None:
    """The partial result in ``out`` to resume, after checking it belongs to this run."""
    from jointwear import io

    if out is None:
        raise BadInputError("resume needs the output file of the interrupted run (out=..., --out)")
    out = Path(out)
    if not out.exists():
        return None  # nothing to resume: a fresh run
    prev = io.load(out)
    what = f"'{out}'"
    if prev.attrs.get("title") != "jointwear rig footage tracking":
        raise BadInputError(f"{what} is not a `jointwear dic track` result; cannot resume it")
    problems = []
    for name, src in (("left", L), ("right", R)):
        want = str(src.path) if src is not None else ""
        if str(prev.attrs.get(f"{name}_footage", "")) != want:
            problems.append(
                f"{name} footage was '{prev.attrs.get(f'{name}_footage', '')}', now '{want}'"
            )
    old = io.parse_provenance(prev).get("parameters", {})
    new = json.loads(json.dumps(_parameters(cfg, bodies)))  # as the file records them
    old_track = {k: v for k, v in old.get("track", {}).items() if k not in _RESUMABLE_CHANGES}
    new_track = {k: v for k, v in new["track"].items() if k not in _RESUMABLE_CHANGES}
    for key in sorted(set(old_track) | set(new_track)):
        if old_track.get(key) != new_track.get(key):
            problems.append(f"track.{key} was {old_track.get(key)!r}, now {new_track.get(key)!r}")
    if old.get("bodies") != new["bodies"]:
        problems.append("the bodies (regions of interest) differ")
    if problems:
        raise BadInputError(
            f"cannot resume {what}: it was made with other inputs or options ("
            + "; ".join(problems)
            + "); run again with the same ones, or without resume to start afresh"
        )
    return prev


def _restore_rows(prev: xr.Dataset, states, times, flags, duplicates, stereo: bool, out) -> None:
    """Fill the states' rows, times, flags and duplicates from a partial result."""
    img = "" if stereo else "_image"
    for st in states:
        name = st.spec.name
        pts = prev[f"{name}_points"].values
        n_ref = len(st.ref3d)
        if pts.shape[1] != n_ref or not np.allclose(
            pts[0],
            st.ref3d,
            atol=1e-6 * max(1.0, float(np.nanmax(np.abs(st.ref3d)))),
            equal_nan=True,
        ):
            raise BadInputError(
                f"cannot resume '{out}': body '{name}' has {pts.shape[1]} subsets there but "
                f"{n_ref} (or other reference positions) now; the reference frames or the "
                "calibration differ - run again without resume"
            )
        columns = {
            "R": prev[f"{name}_rotation"].values,
            "poi": prev[f"{name}{img}_position"].values,
            "poi_u": prev[f"{name}{img}_position_u"].values,
            "n": prev[f"{name}_n_points"].values,
            "rms": prev[f"{name}_fit_rms"].values,
            "points": pts,
            "points_u": prev[f"{name}_points_u"].values,
            "zncc": prev[f"{name}_zncc"].values,
            "reinit": (
                prev[f"{name}_reinitialised"].values
                if f"{name}_reinitialised" in prev
                else np.zeros(len(pts), dtype=np.int8)
            ),
        }
        st.rows = {key: list(val) for key, val in columns.items()}
    times.extend(float(t) for t in prev["time"].values)
    raw = FRAME_FLAGS["duplicated"] | FRAME_FLAGS["tracking_failed"]  # the others are derived
    flags.extend(int(f) & raw for f in prev["frame_flag"].values)
    dup = prev.attrs.get("duplicated_frames", "[]")
    duplicates.extend(int(i) for i in (json.loads(dup) if isinstance(dup, str) else dup))


def _parameters(cfg: TrackConfig, bodies) -> dict[str, Any]:
    """The parameters recorded in a tracking result's provenance (and checked on resume)."""
    return {"track": asdict(cfg), "bodies": [asdict(b) for b in bodies]}


def _write(ds: xr.Dataset, out, inputs, cfg, bodies) -> None:
    from jointwear import io

    if cfg.data_origin:
        ds.attrs["data_origin"] = cfg.data_origin
    io.save(
        ds,
        out,
        inputs=inputs,
        parameters=_parameters(cfg, bodies),
        source="jointwear (dic.track)",
    )


def velocity_budget(t, pos, pos_u, vel, gain, cfg: TrackConfig, calibration) -> dict:
    """Standard uncertainty of a tracked point's velocity (time, axis) and its parts.

    * noise: the positions' noise times the differentiator's noise gain; the noise is the
      larger of the propagated uncertainty (median over frames) and the empirical scatter
      about a local polynomial (:func:`~jointwear.dic.footage._rigid.position_noise`);
    * truncation: the differentiator's model error,
      :func:`~jointwear.dic.footage._rigid.derivative_truncation` (dominant for fast mechanisms at a
      few tens of frames per second);
    * calibration: the calibration's relative length uncertainty ``length_scale_u_rel`` times
      the speed, on every axis (a scale error of the world frame changes every component in
      proportion, an orientation error of the same relative size moves speed between axes);
      None when the calibration does not state it (imported or exact cameras).
    """
    sigma = _nanmedian(pos_u)
    emp = position_noise(t, pos, window=cfg.velocity_window, order=cfg.velocity_order)
    sigma = np.where(np.isfinite(emp), np.fmax(sigma, emp), sigma)
    noise = gain[:, None] * sigma[None, :]
    trunc = derivative_truncation(t, pos, window=cfg.velocity_window, order=cfg.velocity_order)
    trunc = np.where(np.isfinite(trunc), trunc, 0.0)
    cal = None
    u_rel = getattr(calibration, "length_scale_u_rel", None) if calibration is not None else None
    if u_rel is not None:
        speed = np.linalg.norm(vel, axis=1, keepdims=True)
        cal = np.broadcast_to(u_rel * speed, vel.shape)
    total = np.sqrt(noise**2 + trunc**2 + (cal**2 if cal is not None else 0.0))
    total = np.where(np.isfinite(vel), total, np.nan)
    return {"noise": noise, "truncation": trunc, "calibration": cal, "total": total}


def _nanmedian(a) -> np.ndarray:
    """Median over time ignoring NaN; NaN (without a warning) where nothing is valid."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        return np.nanmedian(np.asarray(a, dtype=float), axis=0)


def _med(a) -> list[float]:
    return [float(v) for v in _nanmedian(a)]


def _frame_gaps(t: np.ndarray, flag_arr: np.ndarray, fps: float) -> tuple[np.ndarray, int]:
    """Gaps in the frame times (dropped frames): flags the frames after a gap in ``flag_arr``
    and returns their indices and the estimated number of dropped frames."""
    dt = np.diff(t)
    nominal = 1.0 / fps
    gaps = np.flatnonzero(dt > 1.5 * nominal) + 1
    flag_arr[gaps] |= FRAME_FLAGS["after_gap"]
    dropped = int(np.sum(np.rint(dt[dt > 1.5 * nominal] / nominal) - 1)) if len(dt) else 0
    return gaps, dropped


def _body_variables(st, t, poi, poi_u, vel, axes, unit, stereo) -> tuple[dict, dict]:
    """A tracked body's variables (point of interest, rigid fit, subsets) and coordinates."""
    rows, name = st.rows, st.spec.name
    img = "" if stereo else "_image"  # one camera: pixels, not the contract's metres
    tpa = ("time", f"{name}_point", f"{name}_point_axis")
    pts = np.asarray(rows["points"], dtype=np.float32)
    data = {
        f"{name}{img}_position": (
            ("time", "axis"),
            poi,
            {
                "units": unit,
                "long_name": f"position of the {name}'s point of interest (world frame)",
                "ancillary_variables": f"{name}{img}_position_u",
            },
        ),
        f"{name}{img}_position_u": (
            ("time", "axis"),
            poi_u,
            {"units": unit, "long_name": f"standard uncertainty of {name}{img}_position"},
        ),
        f"{name}{img}_velocity": (
            ("time", "axis"),
            vel,
            {"units": f"{unit} s-1", "long_name": f"velocity of the {name}'s point of interest"},
        ),
        f"{name}_n_points": (
            "time",
            np.asarray(rows["n"]),
            {"units": "1", "long_name": f"subsets used in the {name}'s rigid fit"},
        ),
        f"{name}_fit_rms": (
            "time",
            np.asarray(rows["rms"], dtype=float),
            {"units": unit, "long_name": f"RMS residual of the {name}'s rigid fit"},
        ),
        f"{name}_rotation": (
            ("time", f"{name}_row", f"{name}_col"),
            np.asarray(rows["R"], dtype=float),
            {"units": "1", "long_name": f"rotation of the {name} since the reference frame"},
        ),
        f"{name}_points": (
            tpa,
            pts,
            {
                "units": unit,
                "long_name": f"tracked subset centres of the {name} (world frame)",
                "ancillary_variables": f"{name}_points_u",
            },
        ),
        f"{name}_points_u": (
            tpa,
            np.asarray(rows["points_u"], dtype=np.float32),
            {"units": unit, "long_name": f"standard uncertainty of {name}_points (propagated)"},
        ),
        f"{name}_zncc": (
            ("time", f"{name}_point"),
            np.asarray(rows["zncc"], dtype=np.float32),
            {"units": "1", "long_name": f"ZNCC of the {name}'s subsets (lower of the two cameras)"},
        ),
        f"{name}_subset_displacement": (
            tpa,
            pts - pts[:1],
            {
                "units": unit,
                "long_name": f"displacement of the {name}'s subsets since the reference frame",
            },
        ),
        f"{name}_reinitialised": (
            "time",
            np.asarray(rows.get("reinit", np.zeros(len(t))), dtype=np.int8),
            {
                "units": "1",
                "long_name": f"1 where the {name}'s tracking was lost and found again from SIFT "
                "features of the reference images",
            },
        ),
    }
    d = st.ref3d.shape[1]
    coords = {
        f"{name}_row": (f"{name}_row", np.arange(d)),
        f"{name}_col": (f"{name}_col", np.arange(d)),
        f"{name}_point_axis": (f"{name}_point_axis", axes),
    }
    return data, coords


def _noise_attrs(st, calibration) -> dict[str, float]:
    """The body's median match uncertainty [pixel] and (stereo) its out-of-plane noise floor."""
    name = st.spec.name
    sig_med = float(np.median(st.sigma_px))
    attrs = {f"{name}_match_sigma_px": sig_med}
    if calibration is not None:
        from jointwear.dic.calibration import stereo_noise_floor

        floor = stereo_noise_floor(calibration, np.nanmean(st.ref3d, axis=0), sig_med)
        attrs[f"{name}_noise_floor_z_per_point_m"] = floor
        attrs[f"{name}_noise_floor_z_body_m"] = floor / np.sqrt(len(st.ref3d))
    return attrs


def _follower_variables(poi, poi_u, vel, budget, cfg, unit) -> dict:
    """The contract's follower position and velocity with their uncertainties (stereo)."""
    from jointwear import conventions as C

    return {
        "follower_position": (
            ("time", "axis"),
            poi,
            C.variable_attrs("follower_position", ancillary_variables="follower_position_u"),
        ),
        "follower_position_u": (
            ("time", "axis"),
            poi_u,
            {"units": unit, "long_name": "standard uncertainty of follower_position"},
        ),
        "follower_velocity": (
            ("time", "axis"),
            vel,
            C.variable_attrs(
                "follower_velocity",
                ancillary_variables="follower_velocity_u",
                method=f"Savitzky-Golay on frame times, window {cfg.velocity_window} "
                f"samples, order {cfg.velocity_order}",
            ),
        ),
        "follower_velocity_u": (
            ("time", "axis"),
            budget["total"],
            {
                "units": f"{unit} s-1",
                "long_name": "standard uncertainty of follower_velocity: position noise "
                "through the differentiator, its truncation error and the calibration's "
                "length and orientation uncertainty, combined in quadrature",
                "noise_median": _med(budget["noise"]),
                "truncation_median": _med(budget["truncation"]),
                "calibration_median": (
                    _med(budget["calibration"])
                    if budget["calibration"] is not None
                    else "not assessed (the calibration carries no length_scale_u_rel)"
                ),
            },
        ),
    }


def _journal_variables(poi, poi_u, unit, stereo) -> dict:
    """The journal's displacement since the reference frame with its uncertainty."""
    jname = "journal_displacement" if stereo else "journal_image_displacement"
    return {
        jname: (
            ("time", "axis"),
            poi - poi[:1],
            {
                "units": unit,
                "long_name": "displacement of the journal since the reference frame (z = out of plane)",
                "ancillary_variables": f"{jname}_u",
            },
        ),
        f"{jname}_u": (
            ("time", "axis"),
            poi_u * np.sqrt(2),
            {"units": unit, "long_name": "standard uncertainty of journal_displacement"},
        ),
    }


def _crank_variables(st, flag_arr, stereo, attrs_extra) -> dict:
    """The crank angle; flags the frames lost without a time gap that its steps reveal (in
    ``flag_arr``, counted in ``attrs_extra``)."""
    from jointwear import conventions as C

    ang = np.unwrap(rotation_angle_z(np.asarray(st.rows["R"], dtype=float)))
    if not stereo:  # image y points down: a counter-clockwise turn looks clockwise
        ang = -ang
    ang = ang + np.deg2rad(st.spec.reference_angle_deg)
    # a crank turning at constant speed also reveals frames lost without a time gap
    # (constant-rate video containers): a step of about k >= 2 median steps
    step = np.diff(ang)
    ok = np.isfinite(step)
    if ok.sum() >= 3:
        med = np.median(step[ok])
        if abs(med) > 1e-6:
            k = np.rint(step / med)
            jumps = np.flatnonzero(ok & (k >= 2) & (np.abs(step / med - k) < 0.25)) + 1
            jumps = [int(j) for j in jumps if not flag_arr[j] & FRAME_FLAGS["after_gap"]]
            flag_arr[jumps] |= FRAME_FLAGS["crank_step_gap"]
            attrs_extra["dropped_frames_from_crank"] = json.dumps(
                {str(j): int(k[j - 1] - 1) for j in jumps}
            )
    return {
        "crank_angle": (
            "time",
            ang,
            C.variable_attrs(
                "crank_angle",
                note=f"rotation of the tracked crank about the world z axis plus reference_angle_deg = {st.spec.reference_angle_deg}",
            ),
        )
    }


def _journal_offset(states) -> dict:
    """The journal's point of interest in the bearing's frame (stereo, both bodies tracked)."""
    from jointwear import conventions as C

    roles = {st.spec.role: st for st in states}
    if "journal" not in roles or "bearing" not in roles:
        return {}
    rb = np.asarray(roles["bearing"].rows["R"], dtype=float)
    pb = np.asarray(roles["bearing"].rows["poi"], dtype=float)
    pj = np.asarray(roles["journal"].rows["poi"], dtype=float)
    offset = np.einsum("nji,nj->ni", rb, pj - pb)  # R_b^T (p_j - p_b)
    return {
        "journal_offset": (
            ("time", "axis"),
            offset,
            C.variable_attrs(
                "journal_offset",
                note="journal point of interest minus bearing centre, in the bearing frame "
                "(world axes at the reference frame, turning with the bearing body)",
            ),
        )
    }


def _assemble(states, times, flags, duplicates, L, R, cfg, calibration, status) -> xr.Dataset:
    from jointwear import conventions as C

    t = np.asarray(times, dtype=float)
    stereo = R is not None
    unit = "m" if stereo else "pixel"
    axes = ["x", "y", "z"] if stereo else ["x", "y"]
    flag_arr = np.asarray(flags, dtype=np.int8)
    gaps, dropped = _frame_gaps(t, flag_arr, L.fps)
    data: dict[str, Any] = {}
    coords = {
        "time": ("time", t, {"units": "s", "long_name": C.COORDINATES["time"][1]}),
        "axis": ("axis", axes, {"long_name": "vector component"}),
    }
    valid_time = ~(flag_arr & FRAME_FLAGS["duplicated"]).astype(bool)
    attrs_extra: dict[str, float] = {}
    reinit_counts: dict[str, int] = {}
    for st in states:
        poi = np.asarray(st.rows["poi"], dtype=float)
        poi_u = np.asarray(st.rows["poi_u"], dtype=float)
        poi_v = np.where(valid_time[:, None], poi, np.nan)
        vel, gain = time_derivative(t, poi_v, window=cfg.velocity_window, order=cfg.velocity_order)
        budget = velocity_budget(t, poi_v, poi_u, vel, gain, cfg, calibration if stereo else None)
        body, body_coords = _body_variables(st, t, poi, poi_u, vel, axes, unit, stereo)
        data.update(body)
        coords.update(body_coords)
        reinit_counts[st.spec.name] = int(body[f"{st.spec.name}_reinitialised"][1].sum())
        attrs_extra.update(_noise_attrs(st, calibration if stereo else None))
        role = st.spec.role
        if role == "follower" and stereo:
            data.update(_follower_variables(poi, poi_u, vel, budget, cfg, unit))
        elif role == "journal":
            data.update(_journal_variables(poi, poi_u, unit, stereo))
        elif role == "crank":
            data.update(_crank_variables(st, flag_arr, stereo, attrs_extra))
    if stereo:
        data.update(_journal_offset(states))
    data["frame_flag"] = (
        "time",
        flag_arr,
        {
            "units": "1",
            "long_name": "frame quality flags (bit mask)",
            "flag_masks": np.array([1, 2, 4, 8], dtype=np.int8),
            "flag_meanings": "duplicated after_gap tracking_failed crank_step_gap",
        },
    )
    ds = xr.Dataset(data, coords=coords)
    ds.attrs.update(attrs_extra)
    ds.attrs.update(
        {
            "title": "jointwear rig footage tracking",
            "status": status,
            "frames_processed": len(t),
            "duplicated_frames": json.dumps([int(i) for i in duplicates]),
            "dropped_frames_estimated": dropped,
            "sift_reinitialisations": json.dumps(reinit_counts),
            "gaps_after_frames": json.dumps([int(i) for i in gaps]),
            "left_footage": str(L.path),
            "right_footage": str(R.path) if R is not None else "",
            "frame_rate_hz": L.fps,
            "world_frame": calibration.world_frame
            if calibration is not None
            else "left image (pixels)",
            "velocity_method": f"Savitzky-Golay local polynomial on the frame times, window {cfg.velocity_window} samples, order {cfg.velocity_order}",
        }
    )
    return ds
