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
from jointwear.sim._wear_settings import WearSettings
from jointwear.sim._wear_settings import check_kw as _check_kw
from jointwear.sim.wear import simulate_wear

__all__ = [
    "KwCalibration",
    "calibrate_kw",
    "resimulator",
]


def resimulator(ds: xr.Dataset) -> Callable[[float], xr.Dataset]:
    """A function ``f(kw) -> Dataset`` that repeats the run of the wear map ``ds`` with another kw.

    The contact model and wear settings are rebuilt from the provenance ``ds`` carries (as
    written by ``jointwear sim wear`` or :func:`jointwear.io.save` with
    ``parameters={"contact": model.describe(), "wear": settings}``); the re-run stores the same
    snapshots. Use it as ``calibrate_kw(..., resimulate=resimulator(ds))``.
    """
    from jointwear.io import parse_provenance
    from jointwear.params import from_mapping
    from jointwear.sim._wear_contact import contact_from_description

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

    return run


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
    rtol: float = 0.02,
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
