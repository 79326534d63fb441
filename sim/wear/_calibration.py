"""Calibration of the wear coefficient kw against measured wear: one snapshot or several.

* :func:`calibrate_kw` - one measurement (max depth, volume, cylindricity growth or a map);
  linear estimate, checked and refined by re-simulation.
* :func:`calibrate_kw_multi` - several snapshots at once (e.g. cylindricity growth after 4e5 and
  1.2e6 cycles): least squares of the log misfit, residual of every snapshot and a
  leave-one-out check (each snapshot predicted by the kw fitted to the others).
* :func:`calibrate_kw_and_parameter` - kw together with one further parameter (e.g.
  ``mechanism.joint_offset``) by re-simulating; reports whether two parameters fit what one
  cannot.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
import xarray as xr

from jointwear import conventions
from jointwear.errors import BadInputError
from jointwear.sim.wear._loop import simulate_wear
from jointwear.sim.wear._settings import CALIBRATION_RTOL, WearSettings
from jointwear.sim.wear._settings import check_kw as _check_kw

__all__ = [
    "KwCalibration",
    "calibrate_kw",
    "resimulator",
    "Measurement",
    "MultiCalibration",
    "calibrate_kw_multi",
    "calibrate_kw_and_parameter",
]


def resimulator(ds: xr.Dataset, parameter: str | None = None) -> Callable[..., xr.Dataset]:
    """A function ``f(kw) -> Dataset`` that repeats the run of the wear map ``ds`` with another kw.

    With ``parameter`` (a dotted simulator parameter such as ``"mechanism.joint_offset"``) the
    function is ``f(kw, value)`` and also sets that parameter (for
    :func:`calibrate_kw_and_parameter`). The contact model and wear settings are rebuilt from the provenance ``ds`` carries (as
    written by ``jointwear sim wear`` or :func:`jointwear.io.save` with
    ``parameters={"contact": model.describe(), "wear": settings}``); the re-run stores the same
    snapshots. Use it as ``calibrate_kw(..., resimulate=resimulator(ds))``.
    """
    from jointwear.io import parse_provenance
    from jointwear.params import from_mapping
    from jointwear.sim.wear._contact import contact_from_description

    params = parse_provenance(ds).get("parameters") or {}
    if "contact" not in params or "wear" not in params:
        raise BadInputError(
            "the wear map does not record its contact model and wear settings in its provenance "
            "(written by 'jointwear sim wear'?); pass a resimulate function instead"
        )
    contact = contact_from_description(params["contact"])
    settings = from_mapping(WearSettings, params["wear"], where="wear")
    snaps = [float(c) for c in np.asarray(ds["cycles"].values)]
    target = max(snaps)

    def run(kw: float) -> xr.Dataset:
        return simulate_wear(
            contact=contact,
            cycles=target,
            settings=dataclasses.replace(settings, kw=kw),
            snapshots=snaps,
        )

    if parameter is None:
        return run
    if not hasattr(contact, "params"):
        raise BadInputError(
            f"--vary {parameter}: the wear map was computed with a prescribed contact model, "
            "which has no simulator parameters to vary"
        )
    from jointwear.params import replace_nested
    from jointwear.sim.wear._contact import DynamicContact

    replace_nested(contact.params, **{parameter: _get(contact.params, parameter)})  # name check

    def run2(kw: float, value: float) -> xr.Dataset:
        params = replace_nested(contact.params, **{parameter: float(value)})
        return simulate_wear(
            contact=DynamicContact(params),
            cycles=target,
            settings=dataclasses.replace(settings, kw=kw),
            snapshots=snaps,
        )

    return run2


def _get(obj: Any, dotted: str) -> Any:
    for part in dotted.split("."):
        if not hasattr(obj, part):
            from jointwear.errors import ParameterError

            raise ParameterError(f"unknown parameter {dotted!r} (no '{part}')")
        obj = getattr(obj, part)
    return obj


@dataclass(frozen=True)
class KwCalibration:
    """Result of :func:`calibrate_kw`.

    Attributes
    ----------
    kw : float
        Calibrated wear coefficient [m²/N].
    kw_linear : float
        The linear estimate ``kw_sim * measured / simulated`` [m²/N].
    quantity : str
        What was matched: ``"max_depth"`` [m], ``"volume"`` [m³], ``"cylindricity"`` [m] or
        ``"map"`` (least-squares scale).
    cycles : float
        Cycle count at which the measurement was compared.
    measured : float
        The measured value (``"map"``: measured max depth) [m or m³].
    iterations : tuple of (kw, simulated value)
        Every simulation used: the given one and each re-simulation.
    linearity_error : float or None
        Relative mismatch of the first re-simulation with ``kw_linear`` (how far wear is from
        linear in kw); None if not re-simulated.
    converged : bool
        Whether the last re-simulation matched the measurement within ``rtol`` (True without
        re-simulation only means "linear estimate, unchecked").
    """

    kw: float
    kw_linear: float
    quantity: str
    cycles: float
    measured: float
    iterations: tuple[tuple[float, float], ...]
    linearity_error: float | None
    converged: bool


def _at_cycles(da: xr.DataArray, cycles: float) -> xr.DataArray:
    """Value of a snapshot variable at ``cycles`` (linear interpolation between snapshots)."""
    c = np.asarray(da["cycles"].values, dtype=float)
    if cycles < 0 or cycles > c.max() * (1 + 1e-12):
        raise BadInputError(
            f"the simulated wear map covers 0 .. {c.max():.6g} cycles; the measurement is at "
            f"{cycles:.6g} cycles - simulate at least that many"
        )
    if np.any(np.isclose(c, cycles, rtol=1e-9, atol=0)):
        return da.isel(cycles=int(np.argmin(np.abs(c - cycles))))
    if cycles < c.min():  # wear is zero at 0 cycles: interpolate from the origin
        return da.isel(cycles=0) * (cycles / c.min())
    return da.interp(cycles=cycles)


def _map_on(measured: xr.DataArray, sim: xr.DataArray) -> tuple[np.ndarray, np.ndarray]:
    """Simulated map interpolated at the measured (z, theta) points, both as flat arrays."""
    meas = conventions.to_canonical(measured)
    sim = conventions.to_canonical(sim)
    # periodic padding in theta
    th = sim["theta"].values
    padded = xr.concat(
        [
            sim.isel(theta=[-1]).assign_coords(theta=[th[-1] - 360.0]),
            sim,
            sim.isel(theta=[0]).assign_coords(theta=[th[0] + 360.0]),
        ],
        dim="theta",
    )
    zmin, zmax = float(sim["z"].min()), float(sim["z"].max())
    mz = meas["z"].values
    if mz.min() < zmin - 1e-9 or mz.max() > zmax + 1e-9:
        raise BadInputError(
            f"the measured map spans z = {mz.min():.4g} .. {mz.max():.4g} m, beyond the simulated "
            f"bearing ({zmin:.4g} .. {zmax:.4g} m); check the axial origin (z = 0 at mid-width)"
        )
    s = padded.interp(z=meas["z"], theta=meas["theta"]).transpose("z", "theta").values
    m = meas.transpose("z", "theta").values
    ok = np.isfinite(m) & np.isfinite(s)
    return m[ok], s[ok]


def _quantity(sim: xr.Dataset, quantity: str, cycles: float, measured: Any) -> tuple[float, float]:
    """(measured value, simulated value) for the calibration quantity."""
    if quantity == "max_depth":
        return float(measured), float(_at_cycles(sim["max_wear_depth"], cycles))
    if quantity == "volume":
        return float(measured), float(_at_cycles(sim["worn_volume"], cycles))
    if quantity == "cylindricity":
        value = float(_at_cycles(sim["cylindricity"], cycles))
        if not np.isfinite(value):
            raise BadInputError(
                "the simulated map has no cylindricity (jointwear.metrology is not available)"
            )
        return float(measured), value
    m, s = _map_on(measured, _at_cycles(sim["wear_depth"], cycles))
    if not np.any(s > 0):
        raise BadInputError("the simulated map shows no wear where the measurement has data")
    scale = float(np.dot(m, s) / np.dot(s, s))  # least squares m ~ scale * s
    # express as (target, simulated) so that target / simulated = scale
    return scale * float(np.max(s)), float(np.max(s))


def calibrate_kw(
    simulated: xr.Dataset,
    measured: float | xr.DataArray | xr.Dataset,
    *,
    quantity: Literal["max_depth", "volume", "cylindricity", "map"] | None = None,
    cycles: float | None = None,
    resimulate: Callable[[float], xr.Dataset] | None = None,
    rtol: float = CALIBRATION_RTOL,
    max_iter: int = 6,
) -> KwCalibration:
    """Estimate kw so that the simulated wear matches a measurement.

    Archard wear is linear in kw only while the profile feedback is weak (the pressure
    distribution does not change much as the bore wears). The first estimate assumes that
    linearity, ``kw1 = kw_sim * measured / simulated``. If ``resimulate`` is given, the
    assumption is checked by simulating again with ``kw1``; the mismatch is reported as
    ``linearity_error`` and the estimate refined with a power-law (secant in log-log) update
    until the re-simulation matches within ``rtol``.

    Parameters
    ----------
    simulated : Dataset
        A wear map from :func:`simulate_wear` (carries ``kw_m2_per_N``).
    measured : float or DataArray or Dataset
        Measured maximum depth [m] (``quantity="max_depth"``), worn volume [m³]
        (``"volume"``), growth of the bore's cylindricity [m] (``"cylindricity"``: measured
        after minus before, the simulated bore starting as a perfect cylinder), or a measured
        wear map ``wear_depth(z, theta)`` [m] with a stated angle
        convention (``"map"``: least-squares scale of the simulated map onto it).
    quantity : {"max_depth", "volume", "cylindricity", "map"}, optional
        Default ``"map"`` for a map, else ``"max_depth"``.
    cycles : float, optional
        Cycle count of the measurement; default the map's ``cycles`` coordinate/attribute, or
        the last simulated snapshot.
    resimulate : callable, optional
        ``f(kw) -> Dataset``: re-runs the simulation with another kw (same snapshots).
    rtol : float
        Relative tolerance of the match after re-simulation.
    max_iter : int
        Maximum number of re-simulations.
    """
    if isinstance(measured, xr.Dataset):
        if "wear_depth" not in measured:
            raise BadInputError("the measured dataset has no 'wear_depth' variable")
        measured = measured["wear_depth"]
    is_map = isinstance(measured, xr.DataArray)
    quantity = quantity or ("map" if is_map else "max_depth")
    if quantity not in ("max_depth", "volume", "cylindricity", "map"):
        raise BadInputError(
            f"quantity must be 'max_depth', 'volume', 'cylindricity' or 'map', got {quantity!r}"
        )
    if is_map:
        if quantity != "map":
            raise BadInputError(f"a measured map needs quantity='map', got {quantity!r}")
        if "cycles" in measured.dims:
            if measured.sizes["cycles"] != 1:
                raise BadInputError("give one measured map (select one cycles value)")
            measured = measured.isel(cycles=0)
        if cycles is None and "cycles" in measured.coords:
            cycles = float(measured["cycles"].values)
        measured = measured.drop_vars("cycles", errors="ignore")
    elif quantity == "map":
        raise BadInputError("quantity='map' needs a measured wear map (DataArray or Dataset)")
    else:
        value = float(measured)
        if not (np.isfinite(value) and value > 0):
            raise BadInputError(f"measured {quantity} must be positive, got {measured!r}")
    if cycles is None:
        cycles = float(simulated["cycles"].values[-1])
    kw0 = _check_kw(simulated.attrs.get("kw_m2_per_N", np.nan), name="kw of the simulated map")
    target, value = _quantity(simulated, quantity, cycles, measured)
    if not value > 0:
        raise BadInputError(f"the simulated {quantity} at {cycles:.6g} cycles is zero")
    if target <= 0:
        raise BadInputError("the measured wear is not positive; kw cannot be calibrated")
    kw_lin = _check_kw(kw0 * target / value, name="calibrated kw")
    iters = [(kw0, value)]
    if resimulate is None:
        return KwCalibration(kw_lin, kw_lin, quantity, cycles, target, tuple(iters), None, False)
    kw = kw_lin
    lin_err = None
    converged = False
    for _ in range(max_iter):
        ds = resimulate(kw)
        t, v = _quantity(ds, quantity, cycles, measured)
        iters.append((kw, v))
        err = v / target - 1.0
        if lin_err is None:
            lin_err = err
        if abs(err) <= rtol:
            converged = True
            break
        (k1, v1), (k2, v2) = iters[-2], iters[-1]
        beta = 1.0
        if k1 != k2 and v1 > 0 and v2 > 0:
            beta = math.log(v2 / v1) / math.log(k2 / k1)
            beta = min(max(beta, 0.2), 2.0)
        kw = _check_kw(kw * (target / v) ** (1.0 / beta), name="calibrated kw")
    return KwCalibration(kw, kw_lin, quantity, cycles, target, tuple(iters), lin_err, converged)


# --- several snapshots ---------------------------------------------------------------------------

_SCALAR = ("max_depth", "volume", "cylindricity")


@dataclass(frozen=True)
class Measurement:
    """One measured snapshot: ``value`` of ``quantity`` after ``cycles`` cycles.

    ``quantity`` is ``"max_depth"`` [m], ``"volume"`` [m³] or ``"cylindricity"`` (growth of the
    bore's cylindricity, measured after minus before) [m].
    """

    quantity: str
    cycles: float
    value: float

    def __post_init__(self) -> None:
        if self.quantity not in _SCALAR:
            raise BadInputError(
                f"measurement quantity must be one of {', '.join(_SCALAR)}, got {self.quantity!r}"
            )
        if not (np.isfinite(self.value) and self.value > 0):
            raise BadInputError(f"measured {self.quantity} must be positive, got {self.value!r}")
        if not (np.isfinite(self.cycles) and self.cycles > 0):
            raise BadInputError(f"measurement cycles must be positive, got {self.cycles!r}")

    def describe(self) -> str:
        """E.g. ``"cylindricity 28.32 µm at 400000 cycles"``."""
        if self.quantity == "volume":
            return f"volume {self.value * 1e9:.4g} mm³ at {self.cycles:.6g} cycles"
        return f"{self.quantity} {self.value * 1e6:.4g} µm at {self.cycles:.6g} cycles"


@dataclass(frozen=True)
class MultiCalibration:
    """Result of :func:`calibrate_kw_multi` / :func:`calibrate_kw_and_parameter`.

    Attributes
    ----------
    kw : float
        Calibrated wear coefficient [m²/N].
    measurements : tuple of Measurement
        The data used.
    simulated : tuple of float
        Simulated value of each measurement at the calibrated parameters (last simulation).
    residuals : tuple of float
        ``simulated / measured - 1`` per measurement.
    rms_log_misfit : float
        RMS of ``ln(simulated / measured)`` over the measurements.
    loo_kw : tuple of float
        kw fitted to all measurements but one (NaN with a single measurement).
    loo_errors : tuple of float
        Relative error of predicting the left-out measurement with ``loo_kw`` (NaN when there
        are no more measurements than fitted parameters: not assessed).
    exponents : tuple of float
        Local power law ``d ln(simulated) / d ln(kw)`` of each measurement (1 = linear in kw).
    simulations : int
        Number of simulations run.
    parameter : str or None
        The further calibrated parameter (two-parameter fit), with ``parameter_value``.
    parameter_value : float or None
    """

    kw: float
    measurements: tuple[Measurement, ...]
    simulated: tuple[float, ...]
    residuals: tuple[float, ...]
    rms_log_misfit: float
    loo_kw: tuple[float, ...]
    loo_errors: tuple[float, ...]
    exponents: tuple[float, ...]
    simulations: int
    parameter: str | None = None
    parameter_value: float | None = None

    def report(self) -> list[str]:
        """Human-readable lines: the data used, each residual, the leave-one-out check."""
        lines = [f"data used ({len(self.measurements)} snapshot(s)):"]
        for k, m in enumerate(self.measurements):
            loo = self.loo_errors[k]
            loo_txt = "not assessed" if not np.isfinite(loo) else f"{100 * loo:+.1f} %"
            scale, unit = (1e9, "mm³") if m.quantity == "volume" else (1e6, "µm")
            lines.append(
                f"  {m.describe()}: simulated {self.simulated[k] * scale:.4g} {unit}"
                f" -> residual {100 * self.residuals[k]:+.1f} %; left out, predicted {loo_txt}"
            )
        fitted = f"kw = {self.kw:.4g} m²/N"
        if self.parameter is not None:
            fitted += f", {self.parameter} = {self.parameter_value:.6g}"
        lines.append(
            f"fit: {fitted} (least squares of the log misfit, RMS {100 * self.rms_log_misfit:.1f} "
            f"%, {self.simulations} simulation(s))"
        )
        return lines


def _values(ds: xr.Dataset, meas: tuple[Measurement, ...]) -> np.ndarray:
    return np.array([_quantity(ds, m.quantity, m.cycles, m.value)[1] for m in meas])


def _check_sim(values: np.ndarray, meas: tuple[Measurement, ...]) -> None:
    bad = [m.describe() for m, v in zip(meas, values, strict=True) if not (v > 0)]
    if bad:
        raise BadInputError(f"the simulation shows no wear for: {'; '.join(bad)}")


def _fit_log(resid: np.ndarray, beta: np.ndarray, keep: np.ndarray | None = None) -> float:
    """Gauss-Newton step in ln kw for residuals ``ln(meas / sim)`` with exponents ``beta``."""
    if keep is not None:
        resid, beta = resid[keep], beta[keep]
    return float(np.sum(beta * resid) / np.sum(beta * beta))


def calibrate_kw_multi(
    simulated: xr.Dataset,
    measurements: list[Measurement] | tuple[Measurement, ...],
    *,
    resimulate: Callable[[float], xr.Dataset] | None = None,
    rtol: float = 0.005,
    max_iter: int = 6,
) -> MultiCalibration:
    """Fit kw to several measured snapshots at once (least squares of the log misfit).

    Each simulated value is modelled locally as a power law in kw, ``s_i ~ kw^beta_i``
    (``beta_i = 1`` while wear is linear in kw; the exponents are measured from successive
    re-simulations). kw minimises ``sum_i ln(s_i(kw) / m_i)^2``; the residual of every snapshot
    is reported, and a leave-one-out check fits kw to all snapshots but one and predicts the
    left-out one (with the local power law around the optimum, no further simulation). Large
    leave-one-out errors of opposite sign mean no single kw fits the data: the model misses
    something that changes the shape of the wear history (e.g. running-in).

    Parameters
    ----------
    simulated : Dataset
        A wear map from :func:`simulate_wear` covering the measurement cycles (carries
        ``kw_m2_per_N``).
    measurements : sequence of Measurement
        The measured snapshots.
    resimulate : callable, optional
        ``f(kw) -> Dataset`` (e.g. :func:`resimulator`); without it the exponents are taken as 1
        (linear estimate, unchecked).
    rtol : float
        Stop when the kw step is below this relative size.
    max_iter : int
        Maximum number of re-simulations.
    """
    meas = tuple(measurements)
    if not meas:
        raise BadInputError("give at least one measured snapshot")
    m = np.array([x.value for x in meas])
    kw = _check_kw(simulated.attrs.get("kw_m2_per_N", np.nan), name="kw of the simulated map")
    s = _values(simulated, meas)
    _check_sim(s, meas)
    beta = np.ones(len(meas))
    n_sim = 0
    for _ in range(max_iter + 1):
        step = _fit_log(np.log(m / s), beta)
        if resimulate is None or abs(step) <= rtol or n_sim == max_iter:
            if resimulate is None:
                kw, s = kw * math.exp(step), s * np.exp(beta * step)
            break
        kw_new = _check_kw(kw * math.exp(step), name="calibrated kw")
        s_new = _values(resimulate(kw_new), meas)
        n_sim += 1
        _check_sim(s_new, meas)
        beta = np.clip(np.log(s_new / s) / math.log(kw_new / kw), 0.2, 2.0)
        kw, s = kw_new, s_new
    return _result(kw, meas, s, beta, n_sim, n_free=1)


def _result(
    kw: float,
    meas: tuple[Measurement, ...],
    s: np.ndarray,
    beta: np.ndarray,
    n_sim: int,
    *,
    n_free: int,
    parameter: str | None = None,
    value: float | None = None,
) -> MultiCalibration:
    m = np.array([x.value for x in meas])
    resid = np.log(m / s)
    loo_kw, loo_err = [], []
    for i in range(len(meas)):
        keep = np.arange(len(meas)) != i
        if len(meas) - 1 < n_free or n_free > 1:
            loo_kw.append(math.nan)
            loo_err.append(math.nan)
            continue
        step = _fit_log(resid, beta, keep)
        loo_kw.append(kw * math.exp(step))
        loo_err.append(float(s[i] * math.exp(beta[i] * step) / m[i] - 1.0))
    return MultiCalibration(
        kw=kw,
        measurements=meas,
        simulated=tuple(float(v) for v in s),
        residuals=tuple(float(v) for v in s / m - 1.0),
        rms_log_misfit=float(np.sqrt(np.mean(resid**2))),
        loo_kw=tuple(loo_kw),
        loo_errors=tuple(loo_err),
        exponents=tuple(float(b) for b in beta),
        simulations=n_sim,
        parameter=parameter,
        parameter_value=value,
    )


def calibrate_kw_and_parameter(
    simulate: Callable[[float, float], xr.Dataset],
    measurements: list[Measurement] | tuple[Measurement, ...],
    *,
    parameter: str,
    bounds: tuple[float, float],
    kw0: float,
    xatol: float | None = None,
    max_evaluations: int = 12,
) -> MultiCalibration:
    """Fit kw together with one further parameter (e.g. ``mechanism.joint_offset``).

    For each trial value of the parameter (bounded Brent search, :func:`scipy.optimize.
    minimize_scalar`) the simulation is run once and kw is fitted to all snapshots in closed
    form with the local power law (exponents measured once, at the start); the parameter
    minimises the remaining log misfit. The optimum is re-simulated and its residuals reported.
    With as many snapshots as parameters (two) the fit can be exact and no leave-one-out check
    is possible ("not assessed"): compare the misfit with the one-parameter fit to see whether
    the second parameter helps.

    Parameters
    ----------
    simulate : callable
        ``f(kw, value) -> Dataset`` (e.g. ``resimulator(ds, parameter)``).
    measurements : sequence of Measurement
        Measured snapshots (at least two).
    parameter : str
        Name of the parameter (for the report).
    bounds : (float, float)
        Search interval of the parameter [its SI unit].
    kw0 : float
        Starting kw [m²/N].
    xatol : float, optional
        Absolute tolerance of the parameter (default 2 % of the interval).
    max_evaluations : int
        Maximum number of trial values.
    """
    from scipy.optimize import minimize_scalar

    meas = tuple(measurements)
    if len(meas) < 2:
        raise BadInputError("a two-parameter fit needs at least two measured snapshots")
    lo, hi = (float(b) for b in bounds)
    if not (np.isfinite(lo) and np.isfinite(hi) and lo < hi):
        raise BadInputError(f"bounds of {parameter} must be two numbers lo < hi, got {bounds!r}")
    m = np.array([x.value for x in meas])
    kw0 = _check_kw(kw0)
    mid = 0.5 * (lo + hi)
    s0 = _values(simulate(kw0, mid), meas)
    _check_sim(s0, meas)
    kw1 = _check_kw(kw0 * math.exp(_fit_log(np.log(m / s0), np.ones(len(meas)))))
    s1 = _values(simulate(kw1, mid), meas)
    beta = (
        np.clip(np.log(s1 / s0) / math.log(kw1 / kw0), 0.2, 2.0) if kw1 != kw0 else np.ones(len(m))
    )
    n_sim = [2]
    cache: dict[float, tuple[float, np.ndarray]] = {}

    def misfit(value: float) -> float:
        s = _values(simulate(kw1, value), meas)
        n_sim[0] += 1
        if not np.all(s > 0):
            return math.inf
        step = _fit_log(np.log(m / s), beta)
        pred = s * np.exp(beta * step)
        cache[value] = (kw1 * math.exp(step), pred)
        return float(np.sum(np.log(pred / m) ** 2))

    opt = minimize_scalar(
        misfit,
        bounds=(lo, hi),
        method="bounded",
        options={
            "xatol": xatol if xatol is not None else 0.02 * (hi - lo),
            "maxiter": max_evaluations,
        },
    )
    best = float(opt.x)
    kw_best = _check_kw(cache[best][0], name="calibrated kw") if best in cache else kw1
    s_best = _values(simulate(kw_best, best), meas)
    n_sim[0] += 1
    return _result(kw_best, meas, s_best, beta, n_sim[0], n_free=2, parameter=parameter, value=best)


def check_wear_run(sim: xr.Dataset, what: str = "the simulated file") -> None:
    """Refuse a dataset that is not a wear run of :func:`simulate_wear` (``sim wear --out``).

    Calibration reads the run's cycles and wear maps; a measured map or a file of
    another kind given in its place is named with what it lacks.
    """
    missing = [n for n in ("cycles", "wear_depth") if n not in sim.variables]
    if missing:
        raise BadInputError(
            f"{what} is not a wear run written by 'jointwear sim wear' (no "
            + ", ".join(missing)
            + "); give the file 'jointwear sim wear --out' wrote as SIMULATED and the measured "
            "map with --map"
        )


def calibration_report(
    sim: xr.Dataset,
    measurements: list[Measurement],
    *,
    measured_map: xr.Dataset | None = None,
    single: bool = False,
    cycles: float | None = None,
    vary: tuple[str, tuple[float, float]] | None = None,
    resimulate: bool = True,
    rtol: float = CALIBRATION_RTOL,
) -> list[str]:
    """Calibrate kw against measurements and describe the result, line by line.

    What ``jointwear sim calibrate-kw`` does. One measurement (``measured_map``, or the only
    scalar one with ``single``) goes through :func:`calibrate_kw` (tolerance ``rtol``);
    several snapshots through :func:`calibrate_kw_multi` and, with ``vary`` (a parameter name
    and its bounds), also :func:`calibrate_kw_and_parameter`, compared with kw alone.

    Parameters
    ----------
    sim : Dataset
        Simulated wear map (written by :func:`simulate_wear`).
    measurements : list of Measurement
        Scalar measurements.
    measured_map : Dataset, optional
        A measured wear map instead of ``measurements``.
    single : bool
        Calibrate the only measurement at ``cycles`` (default: the last snapshot).
    cycles : float, optional
        Cycle count of a single measurement.
    vary : (str, (float, float)), optional
        Also fit this simulator parameter within these bounds (SI).
    resimulate : bool
        Check the linear estimate by re-simulating.
    rtol : float
        Relative tolerance of the re-simulated match.

    Returns
    -------
    list of str
        The lines to print; the last one gives the calibrated kw.
    """
    check_wear_run(sim)
    resim = resimulator(sim) if resimulate else None
    if vary is None and (measured_map is not None or (single and len(measurements) == 1)):
        if measured_map is not None:
            quantity, measured, what = "map", measured_map, "measured map"
        else:
            m = measurements[0]
            quantity, measured, what = m.quantity, m.value, m.describe()
        cal = calibrate_kw(
            sim, measured, quantity=quantity, cycles=cycles, resimulate=resim, rtol=rtol
        )
        lines = [
            f"data used: {what} (at {cal.cycles:.6g} cycles)",
            f"kw (linear estimate): {cal.kw_linear:.4g} m²/N",
        ]
        if cal.linearity_error is not None:
            state = "converged" if cal.converged else "NOT converged"
            lines += [
                f"re-simulated with it: {100 * cal.linearity_error:+.1f} % off the measurement "
                "(wear is not exactly linear in kw)",
                f"kw (calibrated, {state} after {len(cal.iterations) - 1} re-simulations): "
                f"{cal.kw:.4g} m²/N",
                "residual of the last re-simulation: "
                f"{100 * (cal.iterations[-1][1] / cal.measured - 1):+.1f} %",
            ]
        return lines
    if vary is not None and not resimulate:
        raise BadInputError("--vary needs re-simulation; drop --linear")
    if vary is not None and len(measurements) < 2:
        raise BadInputError("--vary needs at least two measured snapshots")
    one = calibrate_kw_multi(sim, measurements, resimulate=resim, rtol=rtol / 4)
    lines = ["kw alone:", *(f"  {line}" for line in one.report())]
    if vary is not None:
        name, bounds = vary
        two = calibrate_kw_and_parameter(
            resimulator(sim, name), measurements, parameter=name, bounds=bounds, kw0=one.kw
        )
        better = two.rms_log_misfit < 0.5 * one.rms_log_misfit
        lines += [
            f"kw and {name}:",
            *(f"  {line}" for line in two.report()),
            f"two parameters {'fit clearly better than' if better else 'do not fit clearly better than'} "
            f"kw alone (RMS log misfit {100 * two.rms_log_misfit:.1f} % vs "
            f"{100 * one.rms_log_misfit:.1f} %)",
        ]
    return [*lines, f"kw (calibrated): {one.kw:.4g} m²/N"]
