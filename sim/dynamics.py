"""Running the simulator (four-bar or slider-crank): initial state, integration in chunks,
results as xarray.

The equations of motion (minimal coordinates, see ``docs/sim.md``) and the contact model run
in numba (:mod:`jointwear.sim.kernels`); this module packs parameters, drives the integrator
chunk by chunk (progress, errors with the partial record) and has the record built: the
mechanism's own part by :mod:`jointwear.sim._four_bar_record` or
:mod:`jointwear.sim._slider_record`, the rest by :mod:`jointwear.sim._record`.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable

import numpy as np
import xarray as xr

from jointwear import conventions
from jointwear.errors import BadInputError, ParameterError, SimulationError
from jointwear.sim._record import CONTACT_MODES, add_maps, dataset
from jointwear.sim._record import layers as _layers
from jointwear.sim.contact import contact_constant
from jointwear.sim.kernels import _layout as kn
from jointwear.sim.kernels._integrator import integrate
from jointwear.sim.mechanisms import mechanism_of
from jointwear.sim.parameters import AUTO_VECTOR_RTOL_FACTOR, SimParameters
from jointwear.sim.validity import contact_validity, penetration_stop_advice

__all__ = [
    "SimState",
    "CycleResult",
    "run_cycles",
    "initial_state",
    "CONTACT_MODES",
    "wear_depth_on_grid",
]


@dataclasses.dataclass(frozen=True)
class SimState:
    """Where a simulation stopped, to continue it (picklable).

    Attributes
    ----------
    time : float
        Simulated time since the documented initial configuration [s].
    y : ndarray
        State vector (see :mod:`jointwear.sim.kernels`).
    step : float
        Last step size [s].
    impact_velocity : ndarray
        Remembered approach velocities of the contacts in progress (per axial slice, then the
        two end faces) [m/s]; 0 = not in contact.
    model : str
        ``"clearance"`` or ``"ideal"``.
    mechanism : str
        ``"four_bar"`` or ``"slider_crank"`` (the state vectors have the same length).
    """

    time: float
    y: np.ndarray
    step: float
    impact_velocity: np.ndarray
    model: str
    mechanism: str = "four_bar"


@dataclasses.dataclass(frozen=True)
class CycleResult:
    """Result of :func:`run_cycles`.

    Attributes
    ----------
    dataset : xarray.Dataset or None
        Record over ``time`` (None with ``record=False``).
    wear_work : ndarray (Nl, Nd)
        Integral of p |ds| at each bearing point over the run [Pa m] (p normal contact pressure,
        ds sliding increment).
    point_area : ndarray (Nl, Nd)
        Area each point represents [m2]; sum(wear_work * point_area) == normal_work with the
        default ``contact.wear_pressure = "hertz"`` (``"conformal"``: at least normal_work, the
        pressure's resultant being the force, so a wide arc carries more pressure than force).
    normal_work : float
        Integral of F_n |v_t| dt over all bore contacts [N m].
    state : SimState
        State at the end, to continue with ``run_cycles(..., state=result.state)``.
    cycles : float
        Crank cycles simulated.
    axial_normal_work : float
        Integral of F_n |v_t| dt over the end-face (thrust) contacts [N m]; not part of the bore
        wear.
    normal_impulse : float
        Integral of the summed normal bore-contact force over time [N s].
    n_steps : int
        Accepted integration steps.
    sliding_distance : ndarray (Nl, Nd)
        Integral of |ds| at each bearing point while it is in contact [m].
    max_penetration : float
        Largest penetration (bore or end faces) at the end of an accepted step [m]; NaN = not
        known (a result not made by :func:`run_cycles`).
    """

    dataset: xr.Dataset | None
    wear_work: np.ndarray
    point_area: np.ndarray
    normal_work: float
    state: SimState
    cycles: float
    axial_normal_work: float = 0.0
    normal_impulse: float = 0.0
    n_steps: int = 0
    sliding_distance: np.ndarray | None = None
    max_penetration: float = math.nan


def _side(params: SimParameters):
    """The module with the mechanism's own packing, angle flags and record variables."""
    return mechanism_of(params).record_module()


def _pack(params: SimParameters) -> tuple[np.ndarray, np.ndarray]:
    """Kernel parameter arrays: the mechanism's slots, then the joint, contact and solver."""
    j, c, f, s = params.joint, params.contact, params.friction, params.solver
    P = np.zeros(kn.NP)
    IP = np.zeros(kn.NIP, dtype=np.int64)
    _side(params).pack_mechanism(params, P, IP)
    IP[kn.MECH] = mechanism_of(params).kernel_flag
    P[kn.RJ], P[kn.LJ], P[kn.RB], P[kn.WB] = (
        j.journal_radius,
        j.journal_length,
        j.bearing_radius,
        j.bearing_width,
    )
    P[kn.CA], P[kn.RHO] = j.axial_clearance, j.thrust_radius
    kfac, k0 = contact_constant(params)
    P[kn.KFAC], P[kn.K0] = kfac, k0
    P[kn.NEXP], P[kn.CE], P[kn.VFLOOR] = c.exponent, c.restitution, c.impact_velocity_floor
    P[kn.KAX] = c.axial_stiffness if c.axial_stiffness > 0 else k0
    P[kn.MUS], P[kn.MUD] = f.static_coefficient, f.dynamic_coefficient
    P[kn.VS], P[kn.VD] = f.stick_velocity, f.slide_velocity
    P[kn.MUON] = 1.0 if f.enabled else 0.0
    P[kn.BAUM] = s.baumgarte
    P[kn.DPHI] = 2 * math.pi / j.n_points
    P[kn.KTILT], P[kn.CTILT] = j.tilt_stiffness, j.tilt_damping
    IP[kn.IDEAL] = 1 if j.model == "ideal" else 0
    IP[kn.PER_POINT] = 1 if c.formulation == "per_point" else 0
    IP[kn.KVARY] = 1 if c.stiffness == "time_varying" else 0
    IP[kn.KDEN_WORN] = 1 if c.worn_radius_in_denominator else 0
    IP[kn.NL], IP[kn.ND] = j.n_layers, j.n_points
    IP[kn.WPROJ] = {
        "local_conserving": kn.WPROJ_CONSERVING,
        "local": kn.WPROJ_LOCAL,
        "lumped": kn.WPROJ_LUMPED,
    }[c.wear_projection]
    IP[kn.LATCH] = 1 if c.impact_latch == "layer" else 0
    IP[kn.GRADED] = 1 if j.axial_grading > 0 else 0
    return P, IP


def _rate_scale(params: SimParameters) -> str:
    """``solver.rate_error_scale`` resolved: ``"auto"`` is ``"vector"`` with a tilt spring or
    damper on the clearance joint, else ``"component"``; the ideal joint has no rotating body
    state to measure, so it is always ``"component"``."""
    if params.joint.model != "clearance":
        return "component"
    scale = params.solver.rate_error_scale
    if scale == "auto":
        tilt = params.joint.tilt_stiffness > 0 or params.joint.tilt_damping > 0
        scale = "vector" if tilt else "component"
    return scale


def _error_flags(params: SimParameters) -> np.ndarray:
    """What the integrator measures each state component's local error against (the kernels'
    ``ERR_*``): the mechanism's angle flags, and the rotating body's angular velocity as one
    vector when ``solver.rate_error_scale`` says so (``"auto"``: with a tilt spring or damper)."""
    flags = _side(params).ANGLE_FLAGS[params.joint.model].copy()
    if _rate_scale(params) == "vector":
        flags[kn.Y_OMEGA : kn.Y_OMEGA + 3] = kn.ERR_VECTOR
    return flags


def _effective_rtol(params: SimParameters) -> float:
    """The relative tolerance the integrator holds: ``solver.rtol``, times
    :data:`~jointwear.sim.parameters.AUTO_VECTOR_RTOL_FACTOR` when ``"auto"`` chose the vector
    scale (the vector scale alone biases the wear rate of a tilt rig; docs/sim-wear.md)."""
    rtol = float(params.solver.rtol)
    if params.solver.rate_error_scale == "auto" and _rate_scale(params) == "vector":
        rtol *= AUTO_VECTOR_RTOL_FACTOR
    return rtol


def _mechanism(params: SimParameters) -> str:
    return mechanism_of(params).name


def initial_state(params: SimParameters) -> SimState:
    """The documented initial configuration.

    Crank at ``initial_crank_angle_deg`` turning at the nominal speed, the other bodies at the
    ideal mechanism's positions and rates, the journal centred in the bearing and aligned with
    it (:func:`jointwear.sim._four_bar_record.initial_vector`,
    :func:`jointwear.sim._slider_record.initial_vector`).
    """
    side, model = _side(params), params.joint.model
    y = side.initial_vector(params)
    nl = params.joint.n_layers
    return SimState(0.0, y, side.INITIAL_STEP[model], np.zeros(nl + 2), model, _mechanism(params))


def _check_wear(params: SimParameters, wear_depth: np.ndarray | None) -> np.ndarray:
    shape = (params.joint.n_layers, params.joint.n_points)
    if wear_depth is None:
        return np.zeros(shape)
    h = np.asarray(wear_depth, dtype=float)
    if h.shape != shape:
        raise BadInputError(
            f"wear_depth has shape {h.shape}, expected (joint.n_layers, joint.n_points) = "
            f"{shape}; resample the profile to the simulation grid"
        )
    if not np.all(np.isfinite(h)):
        raise BadInputError("wear_depth contains NaN or infinite values")
    c = params.joint.radial_clearance
    if h.min() < -0.9 * c:
        raise BadInputError(
            f"wear_depth has values down to {h.min():g} m: material added beyond 90 % of the "
            f"radial clearance ({c:g} m) would jam the journal; check the sign (wear > 0)"
        )
    return np.ascontiguousarray(h)


def point_area(params: SimParameters, wear_depth: np.ndarray | None = None) -> np.ndarray:
    """Area represented by each bearing point (n, m) [m2] (trapezoidal in z, worn radius)."""
    h = _check_wear(params, wear_depth)
    _, w = _layers(params)
    j = params.joint
    dz = w * j.bearing_width
    return dz[:, None] * (j.bearing_radius + h) * (2 * math.pi / j.n_points)


def wear_depth_on_grid(
    wear_depth: xr.DataArray, params: SimParameters, *, cycles: float | None = None
) -> np.ndarray:
    """Resample a wear map onto the simulation grid (Nl, Nd) for ``run_cycles(wear_depth=...)``.

    Parameters
    ----------
    wear_depth : DataArray
        Wear depth [m] over ``z`` [m] and ``theta`` [degree] (any stated angle convention; it
        is converted to the canonical one), optionally with a ``cycles`` dimension.
    params : SimParameters
        Gives the grid: layer n at z_n of :func:`jointwear.sim.wearmap.layer_positions`
        (``joint.axial_grading``), point m at m 360/Nd degrees.
    cycles : float, optional
        Snapshot to take along ``cycles`` (nearest); default the last.

    Returns
    -------
    ndarray (Nl, Nd)
        Linear interpolation in z (layers outside the map's z range take its edge values) and
        periodic linear interpolation in theta.
    """
    da = wear_depth
    if not isinstance(da, xr.DataArray):
        raise BadInputError("wear_depth must be an xarray DataArray over (z, theta)")
    if "cycles" in da.dims:
        da = da.isel(cycles=-1) if cycles is None else da.sel(cycles=cycles, method="nearest")
    missing = [d for d in ("z", "theta") if d not in da.dims]
    if missing or da.ndim != 2:
        raise BadInputError(
            f"wear_depth map has dims {da.dims}, expected (z, theta) [+ cycles]; missing "
            f"{', '.join(missing) or 'nothing'}"
        )
    units = da.attrs.get("units")
    if units not in (None, "m"):
        raise BadInputError(f"wear_depth map has units {units!r}, expected 'm'")
    da = conventions.to_canonical(da).transpose("z", "theta").sortby("z")
    th = np.asarray(da.theta.values, dtype=float)
    z = np.asarray(da.z.values, dtype=float)
    vals = np.asarray(da.values, dtype=float)
    if not np.all(np.isfinite(vals)):
        raise BadInputError("wear_depth map contains NaN or infinite values")
    th_ext = np.concatenate([th[-1:] - 360.0, th, th[:1] + 360.0])
    v_ext = np.concatenate([vals[:, -1:], vals, vals[:, :1]], axis=1)
    j = params.joint
    tgt_th = np.arange(j.n_points) * 360.0 / j.n_points
    tgt_z, _ = _layers(params)
    by_theta = np.stack([np.interp(tgt_th, th_ext, row) for row in v_ext])  # (nz, Nd)
    if z.size == 1:
        return np.repeat(by_theta, j.n_layers, axis=0)
    zc = np.clip(tgt_z, z[0], z[-1])
    out = np.empty((j.n_layers, j.n_points))
    for m in range(j.n_points):
        out[:, m] = np.interp(zc, z, by_theta[:, m])
    return out


_STATUS = {
    1: "the step size collapsed below solver.min_step (the contact became too stiff to resolve)",
    2: "the penetration exceeded contact.max_penetration_fraction of the radial clearance",
    3: "the state became NaN or infinite",
    4: "the journal axis turned more than 60 degrees from the bearing axis",
}


def _span(params: SimParameters, cycles: float, duration: float | None) -> tuple[float, float]:
    """(cycles, duration [s]) of a run given in cycles or, with ``duration``, in seconds."""
    period = params.mechanism.period
    if duration is not None:
        if not (duration > 0 and math.isfinite(duration)):
            raise ParameterError(f"duration must be a positive number of seconds, got {duration!r}")
        cycles = duration / period if math.isfinite(period) else 0.0
    else:
        if not (cycles > 0 and math.isfinite(cycles)):
            raise ParameterError(f"cycles must be a positive number, got {cycles!r}")
        if not math.isfinite(period):
            raise ParameterError(
                "mechanism.crank_speed_rpm is 0: a crank cycle has no duration; pass duration="
            )
        duration = cycles * period
    return cycles, duration


def _check_state(st: SimState, params: SimParameters) -> None:
    """Refuse a state from another mechanism, contact model or number of layers."""
    model = params.joint.model
    if st.mechanism != _mechanism(params):
        raise BadInputError(
            f"state comes from a {st.mechanism} run; these parameters are a "
            f"{_mechanism(params)}'s - pass state=None to start from the initial configuration"
        )
    if st.model != model or st.impact_velocity.shape != (params.joint.n_layers + 2,):
        raise BadInputError(
            f"state comes from a '{st.model}' run with {st.impact_velocity.shape[0] - 2} layers; "
            f"these parameters need a '{model}' state with {params.joint.n_layers} layers - pass "
            "state=None to start from the initial configuration"
        )


def run_cycles(
    params: SimParameters,
    *,
    cycles: float = 1.0,
    wear_depth: np.ndarray | None = None,
    state: SimState | None = None,
    record: bool = True,
    progress: Callable[[float], None] | None = None,
    duration: float | None = None,
) -> CycleResult:
    """Simulate the mechanism with its clearance joint over a number of crank cycles.

    The four-bar (clearance joint C) or the slider-crank (``PARAMETER_SETS["slider_crank"]``,
    docs/sim.md), chosen by the type of ``params.mechanism``.

    Parameters
    ----------
    params : SimParameters
        Parameters (e.g. ``PARAMETER_SETS["zhang2023"]`` or :func:`load_parameters`).
    cycles : float
        Duration in crank revolutions at the nominal crank speed (fractions allowed).
    wear_depth : ndarray (Nl, Nd), optional
        Wear depth h [m] of each bearing point: layer n at the grid's z_n (n = 0 at z = +wb/2;
        the positions depend on ``joint.axial_grading``, see
        :func:`jointwear.sim.wearmap.layer_positions`), point m at phi_m = m 360/Nd degrees (0
        along -x of the bearing frame, clockwise seen from +z). A bare array carries no
        positions: resample a map from another grid with :func:`wear_depth_on_grid`. The
        worn radius Rb + h enters the contact geometry and K(t). Default: unworn.
    state : SimState, optional
        Continue from ``CycleResult.state`` of a previous run; default: :func:`initial_state`.
    record : bool
        Build the Dataset over time (False: only the accumulated wear work).
    progress : callable, optional
        Called with the fraction done (0..1) after every chunk (1/50 cycle).
    duration : float, optional
        Simulated time [s] instead of ``cycles`` (needed when the crank speed is 0).

    Returns
    -------
    CycleResult

    Raises
    ------
    SimulationError
        Excessive penetration, step-size collapse or a non-finite state; the message names the
        time and crank angle, ``.partial`` holds the Dataset recorded so far.
    """
    cycles, duration = _span(params, cycles, duration)
    h = _check_wear(params, wear_depth)
    P, IP = _pack(params)
    st = state if state is not None else initial_state(params)
    model = params.joint.model
    _check_state(st, params)
    s = params.solver
    t0 = st.time
    t_end = t0 + duration
    n_out = int(math.floor(duration / s.output_interval + 1e-9)) + 1 if record else 0
    t_rel = np.arange(n_out) * s.output_interval
    t_out = t0 + t_rel
    diag = np.full((max(n_out, 0), kn.ND_DIAG), np.nan)
    zl, wl = _layers(params)
    hmin = h.min(axis=1).copy()
    area = point_area(params, h)
    conformal = params.contact.wear_pressure == "conformal"
    ww = np.zeros((4 if conformal else 2, *h.shape))  # 4: the contacts' centres too
    acc = np.zeros(4)  # normal work, axial normal work, normal impulse, max penetration
    y = st.y.astype(float).copy()
    vimp = st.impact_velocity.astype(float).copy()
    hstep = float(st.step)
    t = t0
    i_out = 0
    # chunks of 1/50 cycle (at most 0.01 s) for progress reports and responsiveness
    n_chunks = max(1, math.ceil(cycles * 50 - 1e-9), math.ceil(duration / 0.01 - 1e-9))
    pen_limit = params.contact.max_penetration_fraction * params.joint.radial_clearance
    nacc_total = 0
    inputs = (P, IP, h, hmin, zl, wl, area, vimp, ww, acc)
    solver = (
        _error_flags(params),
        _effective_rtol(params),
        float(s.atol),
        float(s.max_step),
        float(s.min_step),
        float(s.onset_penetration),
        float(pen_limit),
    )
    for k in range(n_chunks):
        t_chunk = t0 + duration * (k + 1) / n_chunks if k < n_chunks - 1 else t_end
        status, t, hstep, i_out, nacc, _nrej = integrate(
            t, y, hstep, t_chunk, (t_out, diag), i_out, inputs, solver
        )
        nacc_total += nacc
        if status != 0:
            partial = _record(params, t_rel[:i_out], diag[:i_out], t0) if record else None
            theta = math.degrees(y[0]) % 360.0
            advice = (
                penetration_stop_advice(params)
                if status == 2
                else "tighten solver tolerances, reduce the time step or check the parameters"
            )
            raise SimulationError(
                f"simulation stopped at t = {t:.6g} s (crank angle {theta:.2f} deg): "
                f"{_STATUS.get(status, 'unknown failure')}; {advice}; the record up to there "
                "is in .partial",
                partial=partial,
            )
        if progress is not None:
            progress((k + 1) / n_chunks)
    new_state = SimState(t, y.copy(), hstep, vimp.copy(), model, _mechanism(params))
    if conformal:
        ww = _conformal_maps(params, ww, h, area)
    ds = _record(params, t_rel, diag, t0) if record else None
    if ds is not None:
        ds = add_maps(ds, params, ww, area)
        if model == "clearance":
            ds.attrs.update(contact_validity(params, float(acc[3]))["attrs"])
    return CycleResult(
        dataset=ds,
        wear_work=ww[0],
        sliding_distance=ww[1],
        point_area=area,
        normal_work=float(acc[0]),
        state=new_state,
        cycles=float(cycles),
        axial_normal_work=float(acc[1]),
        normal_impulse=float(acc[2]),
        n_steps=int(nacc_total),
        max_penetration=float(acc[3]),
    )


def _conformal_maps(
    params: SimParameters, ww: np.ndarray, h: np.ndarray, area: np.ndarray
) -> np.ndarray:
    """(wear work, sliding distance) with the wear work under the conformal (Winkler) pressure
    of ``contact.wear_pressure = "conformal"``, from the contacts' centres the kernel recorded
    in ``ww[2:]`` (:func:`jointwear.sim.wear.conformal_wear_work`)."""
    from jointwear.sim.wear import conformal_wear_work, foundation_modulus

    if np.sum(ww[0] * area) > 0 and not np.any(ww[2] > 0):
        raise SimulationError(
            "contact.wear_pressure = 'conformal': the kernel recorded no contact centre although "
            "the bore wore; its compiled code predates the option (numba's cache does not follow "
            "calls across modules): delete the caches (find . -name '*.nbi' -o -name '*.nbc' | "
            "xargs rm) or set NUMBA_CACHE_DIR to an empty folder"
        )
    j, c = params.joint, params.contact
    lining = c.foundation_thickness
    work = conformal_wear_work(
        ww[2],
        ww[3],
        h,
        area,
        journal_radius=j.journal_radius,
        bearing_radius=j.bearing_radius,
        reduced_modulus=0.75 * contact_constant(params)[0],  # E* = (3/4) 4 / (3 pi (hj + hb))
        foundation=(
            foundation_modulus(c.bearing_modulus, c.bearing_poisson, lining) if lining > 0 else None
        ),
    )
    return np.stack([work, ww[1]])


def _record(params: SimParameters, t_rel: np.ndarray, diag: np.ndarray, t0: float) -> xr.Dataset:
    """The record over time: the mechanism's variables, then the clearance joint's."""
    return dataset(params, _side(params).variables(params, diag), diag, t_rel, t0)
