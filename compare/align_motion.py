"""Putting a simulated and a measured motion record on one time base, in phase.

See :mod:`jointwear.compare.align` (module docstring, "Time series").
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import xarray as xr

from jointwear import conventions
from jointwear.compare._choices import ALIGN_METHOD, ALIGN_METHODS, MOTION_VARIABLES
from jointwear.compare.budget import to_standard
from jointwear.errors import BadInputError, ConventionError

__all__ = ["align_time_series", "MOTION_VARIABLES"]


def _time(ds: xr.Dataset, what: str) -> np.ndarray:
    if "time" not in ds.coords:
        raise BadInputError(f"{what} has no 'time' coordinate")
    t = np.asarray(ds["time"].values, dtype=float)
    if t.size < 4:
        raise BadInputError(f"{what} has only {t.size} time samples; at least 4 are needed")
    if np.any(np.diff(t) <= 0):
        raise BadInputError(f"{what}: time is not strictly increasing")
    units = ds["time"].attrs.get("units", "s")
    if units != "s":
        raise ConventionError(f"{what}: time has units {units!r}, the contract says 's'")
    return t


def _period_from_crank(ds: xr.Dataset) -> float | None:
    if "crank_angle" not in ds:
        return None
    t = np.asarray(ds["time"].values, dtype=float)
    phi = np.unwrap(np.asarray(ds["crank_angle"].values, dtype=float))
    if t.size < 2 or not np.all(np.isfinite(phi)):
        return None
    slope = np.polyfit(t - t[0], phi, 1)[0]
    if abs(slope) < 1e-12:
        return None
    return float(2 * math.pi / abs(slope))


def _common_variables(
    sim: xr.Dataset, meas: xr.Dataset, variables: Sequence[str] | None
) -> list[str]:
    if variables is not None:
        missing = [v for v in variables if v not in sim or v not in meas]
        if missing:
            raise BadInputError(
                f"variable(s) {', '.join(missing)} are not in both the simulation and the "
                f"measurement (simulation has {', '.join(map(str, sim.data_vars))}; measurement "
                f"has {', '.join(map(str, meas.data_vars))})"
            )
        return list(variables)
    found = [
        v
        for v in MOTION_VARIABLES
        if v in sim and v in meas and "time" in sim[v].dims and "time" in meas[v].dims
    ]
    if not found:
        raise BadInputError(
            "the simulation and the measurement have no motion variable in common (looked for "
            f"{', '.join(MOTION_VARIABLES)}); simulation has {', '.join(map(str, sim.data_vars))}, "
            f"measurement has {', '.join(map(str, meas.data_vars))}"
        )
    return found


def _components(sim_da: xr.DataArray, meas_da: xr.DataArray, name: str) -> list[str] | None:
    if "axis" not in sim_da.dims and "axis" not in meas_da.dims:
        return None
    if "axis" not in sim_da.dims or "axis" not in meas_da.dims:
        raise BadInputError(f"'{name}' has an 'axis' dimension on one side only")
    common = [
        str(a) for a in meas_da["axis"].values if str(a) in set(map(str, sim_da["axis"].values))
    ]
    if not common:
        raise BadInputError(f"'{name}': the two sides have no vector component in common")
    return common


def _unit_check(sim_da: xr.DataArray, meas_da: xr.DataArray, name: str) -> str:
    us, um = sim_da.attrs.get("units"), meas_da.attrs.get("units")
    if us != um:
        raise ConventionError(
            f"'{name}' has units {us!r} in the simulation and {um!r} in the measurement; convert "
            "one of them to the contract units before comparing"
        )
    return str(us)


def _crank_period(
    sim: xr.Dataset, meas: xr.Dataset, ts: np.ndarray, period_s: float | None
) -> float:
    """The crank period [s]: given, else from the simulation's crank angle, else the
    measurement's; the simulation must cover one whole period."""
    period = period_s if period_s is not None else _period_from_crank(sim)
    if period is None:
        period = _period_from_crank(meas)
    if period is None or not (np.isfinite(period) and period > 0):
        raise BadInputError(
            "cannot tell the crank period: neither record has a usable 'crank_angle'; pass "
            "period_s= (or --period) [s]"
        )
    if ts[-1] - ts[0] < period * (1 - 1e-9):
        raise BadInputError(
            f"the simulated motion covers {ts[-1] - ts[0]:.4g} s, less than one crank cycle "
            f"({period:.4g} s); simulate at least one whole cycle"
        )
    return period


def _alignment_method(method: str, sim: xr.Dataset, meas: xr.Dataset) -> str:
    """``method`` with ``"auto"`` resolved: by crank angle when both records have one."""
    if method not in ALIGN_METHODS:
        raise BadInputError(
            f"method must be one of {', '.join(map(repr, ALIGN_METHODS))}, got {method!r}"
        )
    has_crank = "crank_angle" in sim and "crank_angle" in meas
    if method == "auto":
        method = "crank_angle" if has_crank else "cross_correlation"
    if method == "crank_angle" and not has_crank:
        raise BadInputError("method='crank_angle' needs 'crank_angle' in both records")
    return method


@dataclass(frozen=True)
class _Window:
    """The measurement samples compared and the simulated record they are taken from."""

    ts: np.ndarray  # simulated time [s]
    keep: np.ndarray  # mask of the measurement's samples kept
    time: np.ndarray  # the measurement's time at the kept samples [s]
    period: float  # crank period [s]
    n_cycles: float  # crank cycles of the measurement kept
    note: str  # what was kept, for the interpolation statement

    @property
    def t0(self) -> float:
        """Start of the simulation's last whole cycle [s]."""
        return self.ts[-1] - self.period

    def sim_at(self, t_sim: np.ndarray, values: np.ndarray) -> np.ndarray:
        """``values`` of the simulation at ``t_sim``, its last whole cycle repeated."""
        phase = self.t0 + np.mod(t_sim - self.t0, self.period)
        return np.interp(phase, self.ts, values)


def _window(ts: np.ndarray, tm: np.ndarray, period: float, whole_cycles: bool) -> _Window:
    """The measurement window: whole cycles from its start (or all of it)."""
    n_cycles = (tm[-1] - tm[0] + np.median(np.diff(tm))) / period
    if whole_cycles and n_cycles >= 1:
        n_keep = int(math.floor(n_cycles + 1e-9))
        keep = tm < tm[0] + n_keep * period - 1e-12
        note = f"{n_keep} whole crank cycle(s) of the measurement"
    else:
        keep = np.ones_like(tm, dtype=bool)
        n_keep = float(n_cycles)
        note = f"the whole measurement ({n_cycles:.3g} cycles; less than one whole cycle)"
    return _Window(ts, keep, tm[keep], period, n_keep, note)


def _phase_by_crank_angle(
    sim: xr.Dataset, meas: xr.Dataset, w: _Window
) -> tuple[np.ndarray, float]:
    """Each kept frame matched to the simulated instant at the same crank angle: that instant
    [s] per frame, and the time shift [s] (measurement minus simulation, circular mean)."""
    phi_s = np.unwrap(np.asarray(sim["crank_angle"].values, dtype=float))
    phi_m = np.asarray(meas["crank_angle"].values, dtype=float)[w.keep]
    sign = 1.0 if phi_s[-1] >= phi_s[0] else -1.0
    ps = sign * phi_s
    if np.any(np.diff(ps) <= 0):
        raise BadInputError(
            "the simulated crank angle is not monotonic in time; cannot align by crank angle "
            "(use method='cross_correlation')"
        )
    start = ps[-1] - 2 * math.pi
    target = start + np.mod(sign * phi_m - start, 2 * math.pi)
    t_sim = np.interp(target, ps, w.ts)
    # shift = measurement time - simulation time, modulo the period (circular mean)
    ang = 2 * math.pi * (w.time - t_sim) / w.period
    shift = math.atan2(np.mean(np.sin(ang)), np.mean(np.cos(ang))) * w.period / (2 * math.pi)
    return t_sim, shift


def shift_uncertainty(method: str, w_time: np.ndarray, t_sim: np.ndarray, period: float):
    """Standard uncertainty of the alignment's time shift [s] and how it was obtained.

    By crank angle: the scatter of the per-frame shifts (circular standard deviation) over the
    square root of the frames (the mean's), the frame interval's rounding (interval/√12) added
    in quadrature. By cross-correlation: the frame interval/√12 (where between two frames the
    correlation's peak lies is not resolved better than the sampling).
    """
    dt = float(np.median(np.diff(w_time))) if w_time.size > 1 else float("nan")
    rounding = dt / math.sqrt(12.0)
    if method != "crank_angle":
        return rounding, f"frame interval {dt * 1e3:.3g} ms / sqrt(12)"
    ang = 2 * math.pi * (w_time - t_sim) / period
    r = float(np.hypot(np.mean(np.sin(ang)), np.mean(np.cos(ang))))
    circ = math.sqrt(max(-2.0 * math.log(max(r, 1e-300)), 0.0)) * period / (2 * math.pi)
    u = math.hypot(circ / math.sqrt(ang.size), rounding)
    return u, (
        f"scatter of the per-frame shifts ({circ * 1e3:.3g} ms) / sqrt({ang.size} frames) and "
        f"the frame interval {dt * 1e3:.3g} ms / sqrt(12), in quadrature"
    )


def _phase_by_cross_correlation(
    sim: xr.Dataset, meas: xr.Dataset, names: list[str], w: _Window
) -> tuple[np.ndarray, float]:
    """The time shift [s] maximising the summed correlation of the normalised signals of every
    common component (the simulation's last whole cycle repeated): the simulated instant [s]
    per kept frame, and the shift."""
    pairs = []
    for name in names:
        comps = _components(sim[name], meas[name], name)
        for c in comps or [None]:
            s = sim[name] if c is None else sim[name].sel(axis=c)
            m = meas[name] if c is None else meas[name].sel(axis=c)
            sv = np.asarray(s.transpose("time").values, dtype=float)
            mv = np.asarray(m.transpose("time").values, dtype=float)[w.keep]
            ok = np.isfinite(mv)
            if ok.sum() < 4 or np.nanstd(mv) == 0:
                continue
            pairs.append((sv, (mv - np.nanmean(mv)) / np.nanstd(mv), ok))
    if not pairs:
        raise BadInputError("no usable signal for the cross-correlation (all constant or NaN)")

    def score(tau: float) -> float:
        total = 0.0
        for sv, mz, ok in pairs:
            x = w.sim_at(w.time[ok] - tau, sv)
            sd = x.std()
            if sd == 0:
                continue
            total += float(np.mean((x - x.mean()) / sd * mz[ok]))
        return total

    from scipy.optimize import minimize_scalar

    period = w.period
    grid = np.linspace(0.0, period, 720, endpoint=False)
    scores = np.array([score(t) for t in grid])
    best = grid[int(np.argmax(scores))]
    step = period / 720
    res = minimize_scalar(
        lambda t: -score(t),
        bounds=(best - step, best + step),
        method="bounded",
        options={"xatol": period * 1e-7},
    )
    tau = float(res.x) if -res.fun >= scores.max() else float(best)
    shift = (tau + period / 2) % period - period / 2
    return w.t0 + np.mod(w.time - shift - w.t0, period), shift


_ALIGNMENTS = {
    "crank_angle": "by crank angle (each frame matched to the simulated instant at the same "
    "crank angle)",
    "cross_correlation": "by cross-correlation of the normalised signals over whole cycles (the "
    "simulation's last whole cycle repeated periodically)",
}


def _axis_union(comps_of: dict[str, list[str] | None]) -> list[str]:
    """The output's vector components: x, y, z first, then any other in name order."""
    union = [c for c in ("x", "y", "z") if any(c in (v or []) for v in comps_of.values())]
    union += sorted({c for v in comps_of.values() for c in (v or []) if c not in union})
    return union


def _columns(
    da: xr.DataArray,
    comps: list[str] | None,
    union: list[str],
    w: _Window,
    times: np.ndarray | None,
) -> np.ndarray:
    """Values on the output grid: sampled at ``times`` in the simulation (None: kept rows)."""
    ts, keep = w.ts, w.keep
    if comps is None or "axis" not in da.dims:
        v = np.asarray(da.transpose("time", ...).values, dtype=float).reshape(da.sizes["time"])
        v = v[keep] if times is None else np.interp(times, ts, v)
        return v if comps is None else np.repeat(v[:, None], len(union), axis=1)
    result = np.full((w.time.size, len(union)), np.nan)
    for c in comps:
        v = np.asarray(da.sel(axis=c).transpose("time").values, dtype=float)
        result[:, union.index(c)] = v[keep] if times is None else np.interp(times, ts, v)
    return result


def _add_variable(
    out: xr.Dataset,
    name: str,
    sim: xr.Dataset,
    meas: xr.Dataset,
    comps: list[str] | None,
    w: _Window,
    t_sim: np.ndarray,
) -> None:
    """Add ``<name>_sim``, ``_meas``, ``_diff`` and the uncertainties given to ``out``."""
    union = list(map(str, out["axis"].values)) if "axis" in out.coords else []
    units = _unit_check(sim[name], meas[name], name)
    long = meas[name].attrs.get("long_name", sim[name].attrs.get("long_name", name))
    dims = ("time", "axis") if comps is not None else ("time",)
    svals = _columns(sim[name], comps, union, w, t_sim)
    mv = _columns(meas[name], comps, union, w, None)
    out[f"{name}_sim"] = (dims, svals, {"units": units, "long_name": f"simulated {long}"})
    out[f"{name}_meas"] = (dims, mv, {"units": units, "long_name": f"measured {long}"})
    out[f"{name}_diff"] = (
        dims,
        svals - mv,
        {"units": units, "long_name": f"{long}: simulation minus measurement"},
    )
    for side, src in (("meas", meas), ("sim", sim)):
        uname = f"{name}_u"
        if uname not in src:
            continue
        uv = _columns(src[uname], comps, union, w, None if side == "meas" else t_sim)
        uv, note = to_standard(uv, src[uname].attrs, f"{uname} of the {side} record")
        out[f"{name}_{side}_u"] = (
            dims,
            uv,
            {
                "units": units,
                "long_name": f"standard uncertainty of {name}_{side}",
                "coverage_factor": 1.0,
                "basis": f"{uname}: {note}",
            },
        )
        out[f"{name}_{side}"].attrs["ancillary_variables"] = f"{name}_{side}_u"


def align_time_series(
    sim: xr.Dataset,
    meas: xr.Dataset,
    *,
    variables: Sequence[str] | None = None,
    method: str = ALIGN_METHOD,
    period_s: float | None = None,
    whole_cycles: bool = True,
) -> xr.Dataset:
    """Put a simulated and a measured motion record on one time base, in phase.

    Parameters
    ----------
    sim : Dataset
        Simulated motion over ``time`` [s] (any, e.g. variable, step), with ``crank_angle``
        [rad] when available; must cover at least one whole crank cycle.
    meas : Dataset
        Measured motion over ``time`` [s] (e.g. DIC at 50 frames/s).
    variables : sequence of str, optional
        Variables to compare (default: those of :data:`MOTION_VARIABLES` present in both).
    method : {"auto", "crank_angle", "cross_correlation"}
        Phase alignment. ``"auto"``: by crank angle when both sides have ``crank_angle``,
        else by cross-correlation.
    period_s : float, optional
        Crank period [s]; default from the simulation's crank angle rate.
    whole_cycles : bool
        Keep only an integer number of crank cycles of the measurement (default True).

    Returns
    -------
    Dataset
        Over the measurement's ``time`` (and ``axis``): ``<var>_sim``, ``<var>_meas``,
        ``<var>_diff`` (sim - meas), ``<var>_meas_u`` / ``<var>_sim_u`` when given, and
        ``sim_time`` (the simulated instant each sample was taken from). Attributes:
        ``alignment_method``, ``time_shift_s``, ``time_shift_deg`` (crank degrees),
        ``time_shift_u_s`` (its standard uncertainty, :func:`shift_uncertainty`),
        ``period_s``, ``n_cycles``, ``interpolation``.
    """
    ts = _time(sim, "simulated motion")
    tm = _time(meas, "measured motion")
    names = _common_variables(sim, meas, variables)
    period = _crank_period(sim, meas, ts, period_s)
    method = _alignment_method(method, sim, meas)
    w = _window(ts, tm, period, whole_cycles)
    if method == "crank_angle":
        t_sim, shift = _phase_by_crank_angle(sim, meas, w)
    else:
        t_sim, shift = _phase_by_cross_correlation(sim, meas, names, w)

    shift_u, shift_basis = shift_uncertainty(method, w.time, t_sim, period)
    time = xr.DataArray(w.time, dims="time", attrs=dict(meas["time"].attrs))
    time.attrs.setdefault("units", "s")
    time.attrs.setdefault("long_name", conventions.COORDINATES["time"][1])
    out = xr.Dataset(coords={"time": time})
    comps_of = {name: _components(sim[name], meas[name], name) for name in names}
    union = _axis_union(comps_of)
    if union:
        out = out.assign_coords(
            axis=xr.DataArray(
                np.array(union, dtype=str), dims="axis", attrs={"long_name": "vector component"}
            )
        )
    for name in names:
        _add_variable(out, name, sim, meas, comps_of[name], w, t_sim)
    out["sim_time"] = (
        "time",
        t_sim,
        {"units": "s", "long_name": "time in the simulated record each sample is taken from"},
    )
    if "crank_angle" in meas:
        out["crank_angle_meas"] = (
            "time",
            np.asarray(meas["crank_angle"].values, dtype=float)[w.keep],
            {"units": "rad", "long_name": "measured crank angle"},
        )
    fps = 1.0 / float(np.median(np.diff(tm)))
    out.attrs.update(
        {
            "title": "simulated and measured motion on a common time base",
            "alignment_method": method,
            "alignment": _ALIGNMENTS[method],
            "time_shift_s": float(shift),
            "time_shift_deg": float(shift / period * 360.0),
            "time_shift_u_s": float(shift_u),
            "time_shift_u_basis": shift_basis,
            "period_s": float(period),
            "n_cycles": float(w.n_cycles),
            "interpolation": (
                f"common time base: the measurement's samples ({fps:.4g} per s), {w.note}; "
                "simulation interpolated linearly onto them after the phase alignment"
            ),
        }
    )
    return out
