"""The calibration data: measured wear maps and stated values, reduced to scalar quantities.

A measured map (``jointwear metrology wearmap``, or any wear map of the data contract) gives
the quantities of :data:`~jointwear.sim.calibrate._spec.MAP_QUANTITIES` *within its band*: the
simulated map is interpolated onto the measured (z, theta) grid (periodic in theta, both in the
canonical angle convention) and both maps are reduced by the same functions
(:func:`band_quantities`): the largest depth, the worn volume ``R ∬ h dθ dz`` and the MZ
cylindricity of the wear (:func:`jointwear.metrology.form.cylinder_zone`, the metrology
module's own definition). The measured value's standard uncertainty u_D is the map's own
``<name>_u`` (metrology states it per quantity); without it, it is derived from the per-point
``wear_depth_u`` (at the maximum; integrated as fully correlated for the volume, an upper bound;
√2 × its RMS for the cylindricity); a map stating neither is refused (unknown is not zero).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import xarray as xr

from jointwear.errors import BadInputError

__all__ = ["Datum", "Band", "read_band", "band_quantities", "on_band", "file_record"]

#: the metrology wearmap names of the map quantities (its cylindricity of the wear map)
_STATED = {
    "max_wear_depth": "max_wear_depth",
    "worn_volume": "worn_volume",
    "cylindricity": "wear_cylindricity",
}


@dataclass(frozen=True)
class Datum:
    """One calibration datum: measured ``value ± u_d`` of ``quantity`` at ``cycles``.

    Attributes
    ----------
    quantity : str
        Quantity name (SI value: m, m³).
    cycles : float
        Crank cycles of the measurement.
    value, u_d : float
        Measured value and its standard uncertainty (k = 1).
    source : str
        The file (or statement) it comes from.
    band : int
        Index of the measured map it belongs to (-1: a stated value).
    u_d_basis : str
        Where u_d comes from.
    """

    quantity: str
    cycles: float
    value: float
    u_d: float
    source: str
    band: int = -1
    u_d_basis: str = ""

    @property
    def label(self) -> str:
        """``"max_wear_depth of wear-2e5.nc at 200000 cycles"`` (a stated value: its source)."""
        if self.band < 0:
            return f"{self.quantity} ({self.source})"
        return f"{self.quantity} of {Path(self.source).name} at {self.cycles:.6g} cycles"


@dataclass(frozen=True)
class Band:
    """A measured map's grid (canonical convention) and depth: where the simulation is reduced.

    Attributes
    ----------
    z : ndarray
        Axial positions of the layers [m].
    theta : ndarray
        Angles [degree], canonical convention.
    depth, u : ndarray (z, theta)
        Measured wear depth and its per-point standard uncertainty (NaN: not stated) [m].
    radius : float or None
        Bore radius stated by the map [m].
    """

    z: np.ndarray
    theta: np.ndarray
    depth: np.ndarray
    u: np.ndarray
    radius: float | None


def file_record(path: str | Path) -> dict[str, object]:
    """Path, sha256 and the sha256 of its own provenance inputs (the snapshot it was made from)."""
    from jointwear import io

    digest, inputs = io.file_snapshot(path)
    return {"path": str(path), "sha256": digest, "inputs_sha256": list(inputs)}


def read_band(ds: xr.Dataset, where: str) -> Band:
    """The measured map of ``ds`` on its own grid, in the canonical angle convention."""
    from jointwear import conventions

    if "wear_depth" not in ds:
        raise BadInputError(
            f"{where}: no 'wear_depth' variable; a calibration map is a measured wear map "
            "(jointwear metrology wearmap --out)"
        )
    da = ds["wear_depth"]
    if "cycles" in da.dims:
        if da.sizes["cycles"] != 1:
            raise BadInputError(f"{where}: {da.sizes['cycles']} snapshots; give one map per file")
        da = da.isel(cycles=0)
    if set(da.dims) != {"z", "theta"}:
        raise BadInputError(f"{where}: wear_depth has dims {da.dims}, expected (z, theta)")
    da = conventions.to_canonical(da).transpose("z", "theta").sortby("theta")
    u = np.full(da.shape, np.nan)
    if "wear_depth_u" in ds:
        uda = ds["wear_depth_u"]
        uda = uda.isel(cycles=0) if "cycles" in uda.dims else uda
        uda = conventions.to_canonical(uda).transpose("z", "theta").sortby("theta")
        u = np.asarray(uda.values, dtype=float)
    radius = ds.attrs.get("bearing_radius_m")
    return Band(
        np.asarray(da["z"].values, dtype=float),
        np.asarray(da["theta"].values, dtype=float),
        np.asarray(da.values, dtype=float),
        u,
        float(radius) if radius is not None else None,
    )


def on_band(sim: xr.DataArray, band: Band) -> np.ndarray:
    """A simulated map ``wear_depth(z, theta)`` interpolated onto the band's grid [m]."""
    from jointwear import conventions

    sim = conventions.to_canonical(sim).transpose("z", "theta").sortby("theta")
    th = np.asarray(sim["theta"].values, dtype=float)
    padded = xr.concat(
        [
            sim.isel(theta=[-1]).assign_coords(theta=[th[-1] - 360.0]),
            sim,
            sim.isel(theta=[0]).assign_coords(theta=[th[0] + 360.0]),
        ],
        dim="theta",
    )
    zs = np.asarray(sim["z"].values, dtype=float)
    if band.z.min() < zs.min() - 1e-9 or band.z.max() > zs.max() + 1e-9:
        raise BadInputError(
            f"the measured map spans z = {band.z.min() * 1e3:+.3g} .. {band.z.max() * 1e3:+.3g} "
            f"mm, beyond the simulated bearing ({zs.min() * 1e3:+.3g} .. {zs.max() * 1e3:+.3g} "
            "mm); check the axial origin (z = 0 at mid-width) or the bearing width"
        )
    z = np.clip(band.z, zs.min(), zs.max())
    out = padded.interp(z=xr.DataArray(z, dims="z"), theta=xr.DataArray(band.theta, dims="theta"))
    return np.asarray(out.transpose("z", "theta").values, dtype=float)


def band_quantities(
    depth: np.ndarray, z: np.ndarray, theta: np.ndarray, radius: float
) -> dict[str, float]:
    """Largest depth [m], worn volume ``R ∬ h dθ dz`` [m³] and MZ cylindricity of a wear map [m].

    The volume integrates by the trapezoid rule in z and the periodic rectangle rule in theta
    (uniform grid over the whole circle); a single layer has no volume or cylindricity (NaN).
    """
    from jointwear.metrology.form import cylinder_zone

    h = np.asarray(depth, dtype=float)
    out = {"max_wear_depth": float(np.nanmax(h))}
    if len(z) < 2:
        return {**out, "worn_volume": math.nan, "cylindricity": math.nan}
    per_layer = np.nansum(h, axis=1) * (2 * math.pi / len(theta)) * radius
    out["worn_volume"] = float(np.trapezoid(per_layer, z))
    zz, tt = np.meshgrid(z, theta, indexing="ij")
    out["cylindricity"] = float(cylinder_zone(zz, tt, h, reference="MZ").total)
    return out


def _u_from_points(band: Band, radius: float) -> dict[str, tuple[float, str]]:
    u = band.u
    if not np.isfinite(u).any():
        return {}
    i, j = np.unravel_index(np.nanargmax(band.depth), band.depth.shape)
    vol = band_quantities(np.nan_to_num(u), band.z, band.theta, radius)["worn_volume"]
    return {
        "max_wear_depth": (float(u[i, j]), "per-point wear_depth_u at the maximum"),
        "worn_volume": (vol, "per-point wear_depth_u integrated as fully correlated (upper bound)"),
        "cylindricity": (
            math.sqrt(2) * float(np.sqrt(np.nanmean(u**2))),
            "√2 × RMS of the per-point wear_depth_u (peak-to-valley of two points)",
        ),
    }


def map_data(
    ds: xr.Dataset,
    path: Path,
    index: int,
    cycles: float,
    quantities: tuple[str, ...],
    radius: float,
) -> tuple[Band, list[Datum]]:
    """The band of a measured map and its data (one :class:`Datum` per quantity)."""
    band = read_band(ds, str(path))
    r = band.radius or radius
    values = band_quantities(band.depth, band.z, band.theta, r)
    from_points = _u_from_points(band, r)
    data = []
    for q in quantities:
        stated = _STATED[q]
        if f"{stated}_u" in ds and np.isfinite(float(ds[f"{stated}_u"])):
            u = float(ds[f"{stated}_u"])
            basis = f"the map's {stated}_u ({ds[f'{stated}_u'].attrs.get('comment', '')})"
        elif q in from_points and np.isfinite(from_points[q][0]):
            u, basis = from_points[q]
        else:
            raise BadInputError(
                f"{path}: the map states no uncertainty of {q} ({stated}_u) nor a per-point "
                "wear_depth_u; the likelihood needs u_D: use the map 'jointwear metrology "
                "wearmap' writes, or state the value with its u in [[calibrate.values]]"
            )
        if not (np.isfinite(values[q]) and u > 0):
            raise BadInputError(
                f"{path}: {q} = {values[q]!r} ± {u!r} cannot be calibrated on (a single layer "
                "has no volume or cylindricity: drop it from [calibrate] quantities)"
            )
        data.append(Datum(q, cycles, values[q], u, str(path), index, basis))
    return band, data
