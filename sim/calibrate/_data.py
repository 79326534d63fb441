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
from jointwear.sim.calibrate._spec import FIELD_QUANTITY

__all__ = ["Datum", "Band", "read_band", "band_quantities", "on_band", "file_record"]

#: the whole-band wear field: one datum per bin, ``wear_field_<k>`` (jointwear.wear_field)
FIELD = FIELD_QUANTITY

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
    u_random : ndarray (z, theta)
        The part of ``u`` independent from point to point (``wear_depth_u_random``; NaN: not
        stated, the whole u then counts as correlated over the map) [m].
    win : int
        Samples in theta the maximum and the cylindricity are averaged over (1: none), as
        ``metrology wearmap`` states its ``max_wear_depth`` (about 1 degree).
    field : tuple
        The wear field's bins (row and column indices, :func:`jointwear.wear_field.field_bins`)
        when it is calibrated on, else empty.
    cylindricity_reference : str
        Reference cylinder of the cylindricity: ``"MZ"`` (a measured map, metrology's) or
        ``"LS"`` (a reported value stated so).
    """

    z: np.ndarray
    theta: np.ndarray
    depth: np.ndarray
    u: np.ndarray
    radius: float | None
    u_random: np.ndarray | None = None
    win: int = 1
    cylindricity_reference: str = "MZ"
    field: tuple = ()

    def quantities(self, h: np.ndarray, radius: float) -> dict[str, float]:
        """:func:`band_quantities` of a map ``h`` on this band's grid, as the band defines them,
        and the wear field's bin means ``wear_field_<k>`` when the band has bins (``field``)."""
        r = self.radius or radius
        out = band_quantities(h, self.z, self.theta, r, self.win, self.cylindricity_reference)
        if self.field:
            from jointwear.wear_field import field_means

            out.update({f"{FIELD}_{k}": v for k, v in enumerate(field_means(h, list(self.field)))})
        return out


def file_record(path: str | Path) -> dict[str, object]:
    """Path, sha256 and the sha256 of its own provenance inputs (the snapshot it was made from)."""
    from jointwear import io

    digest, inputs = io.file_snapshot(path)
    return {"path": str(path), "sha256": digest, "inputs_sha256": list(inputs)}


def read_band(ds: xr.Dataset, where: str) -> Band:
    """The measured map of ``ds`` on its own grid, in the canonical angle convention."""
    from jointwear import conventions
    from jointwear.wear_field import random_part

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
    u, u_random = (_per_point(ds, n, da.shape) for n in ("wear_depth_u", "wear_depth_u_random"))
    radius = ds.attrs.get("bearing_radius_m")
    n_t = da.sizes["theta"]
    # a map stating its max_wear_depth (metrology wearmap) averaged it over about 1 degree
    win = max(1, int(round(n_t / 360.0)) | 1) if "max_wear_depth" in ds else 1
    return Band(
        np.asarray(da["z"].values, dtype=float),
        np.asarray(da["theta"].values, dtype=float),
        np.asarray(da.values, dtype=float),
        u,
        float(radius) if radius is not None else None,
        random_part(u, u_random, where),
        win,
    )


def _per_point(ds: xr.Dataset, name: str, shape: tuple[int, ...]) -> np.ndarray:
    """A per-point variable of the map in the canonical convention (NaN where not stated)."""
    from jointwear import conventions

    if name not in ds:
        return np.full(shape, np.nan)
    uda = ds[name]
    uda = uda.isel(cycles=0) if "cycles" in uda.dims else uda
    uda = conventions.to_canonical(uda).transpose("z", "theta").sortby("theta")
    return np.asarray(uda.values, dtype=float)


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


def volume_weights(z: np.ndarray, theta: np.ndarray, radius: float) -> np.ndarray:
    """Weights ``w`` (z, theta) [m²] of the worn volume ``V = Σ w h = R ∬ h dθ dz``: the
    trapezoid rule in z, the periodic rectangle rule in theta (a uniform grid over the circle)."""
    tz = np.zeros(len(z))
    if len(z) > 1:
        dz = np.diff(z)
        tz[:-1] += dz / 2
        tz[1:] += dz / 2
    return np.outer(tz, np.full(len(theta), 2 * math.pi / len(theta) * radius))


def band_quantities(
    depth: np.ndarray,
    z: np.ndarray,
    theta: np.ndarray,
    radius: float,
    win: int = 1,
    reference: str = "MZ",
) -> dict[str, float]:
    """Largest depth [m], worn volume ``R ∬ h dθ dz`` [m³] and cylindricity of a wear map [m]
    (against the ``reference`` cylinder, metrology's :func:`~jointwear.metrology.form.cylinder_zone`).

    The volume integrates by :func:`volume_weights`; the largest depth and the cylindricity are
    of the map averaged over ``win`` samples in theta (periodic; 1: the map itself), as
    ``metrology wearmap`` states them. A single layer has no volume or cylindricity (NaN).
    """
    from scipy.ndimage import uniform_filter1d

    from jointwear.metrology.form import cylinder_zone

    h = np.asarray(depth, dtype=float)
    sm = h if win <= 1 else uniform_filter1d(np.nan_to_num(h), win, axis=1, mode="wrap")
    out = {"max_wear_depth": float(np.nanmax(sm))}
    if len(z) < 2:
        return {**out, "worn_volume": math.nan, "cylindricity": math.nan}
    out["worn_volume"] = float(np.nansum(volume_weights(z, theta, radius) * h))
    zz, tt = np.meshgrid(z, theta, indexing="ij")
    out["cylindricity"] = float(cylinder_zone(zz, tt, sm, reference=reference).total)
    return out


def _u_from_points(band: Band, radius: float) -> dict[str, tuple[float, str]]:
    from jointwear.wear_field import split_u

    u = band.u
    if not np.isfinite(u).any():
        return {}
    i, j = np.unravel_index(np.nanargmax(band.depth), band.depth.shape)
    w = volume_weights(band.z, band.theta, radius)
    sys_part, rnd = split_u(u, band.u_random)
    sys_part = np.nan_to_num(sys_part)  # a point whose u is not stated adds none
    vol = math.sqrt(float(np.sum(w * sys_part)) ** 2 + float(np.sum((w * rnd) ** 2)))
    vol_basis = (
        "per-point wear_depth_u: its independent part (wear_depth_u_random) summed in "
        "quadrature, the rest integrated as fully correlated"
        if rnd.any()
        else "per-point wear_depth_u integrated as fully correlated (upper bound)"
    )
    return {
        "max_wear_depth": (float(u[i, j]), "per-point wear_depth_u at the maximum"),
        "worn_volume": (vol, vol_basis),
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
    bins: tuple[int, int] = (4, 12),
) -> tuple[Band, list[Datum]]:
    """The band of a measured map and its data (one :class:`Datum` per quantity; the wear
    field one per bin of ``bins`` = (z, theta) bins)."""
    import dataclasses

    band = read_band(ds, str(path))
    r = band.radius or radius
    values = band_quantities(band.depth, band.z, band.theta, r, band.win)
    if "max_wear_depth" in ds and np.isfinite(float(ds["max_wear_depth"])):
        # metrology's maximum, less its extreme-value bias (the noise lifts the largest of
        # many noisy values near the top; the simulated map has no such noise)
        values["max_wear_depth"] = float(ds["max_wear_depth"])
    from_points = _u_from_points(band, r)
    data = []
    for q in quantities:
        if q == FIELD:
            band = dataclasses.replace(band, field=_field_bins(band, bins))
            data += _field_data(band, path, index, cycles)
            continue
        stated = _STATED[q]
        if f"{stated}_u" in ds and np.isfinite(float(ds[f"{stated}_u"])):
            u = float(ds[f"{stated}_u"])
            basis = f"the map's {stated}_u ({ds[f'{stated}_u'].attrs.get('comment', '')})"
        elif q in from_points and np.isfinite(from_points[q][0]):
            u, basis = from_points[q]
        else:
            raise _no_u(path, f"{q} ({stated}_u)")
        if not (np.isfinite(values[q]) and u > 0):
            raise BadInputError(
                f"{path}: {q} = {values[q]!r} ± {u!r} cannot be calibrated on (a single layer "
                "has no volume or cylindricity: drop it from [calibrate] quantities)"
            )
        data.append(Datum(q, cycles, values[q], u, str(path), index, basis))
    return band, data


def _no_u(path: Path, what: str) -> BadInputError:
    return BadInputError(
        f"{path}: the map states no uncertainty of {what} nor a per-point wear_depth_u; the "
        "likelihood needs u_D: use the map 'jointwear metrology wearmap' writes, or state the "
        "value with its u in [[calibrate.values]]"
    )


def _field_bins(band: Band, bins: tuple[int, int]) -> tuple:
    """The wear field's bins of the band that hold a measured cell (a gap's bins dropped)."""
    from jointwear.wear_field import field_bins, field_means

    groups = field_bins(len(band.z), len(band.theta), *bins)
    seen = np.isfinite(field_means(band.depth, groups))
    return tuple(g for g, ok in zip(groups, seen, strict=True) if ok)


def _field_data(band: Band, path: Path, index: int, cycles: float) -> list[Datum]:
    """One datum per bin of the wear field: the bin's mean depth and its u (wear_field.field_u)."""
    from jointwear.wear_field import field_means, field_u

    groups = list(band.field)
    values = field_means(band.depth, groups)
    u = field_u(band.u, band.u_random, groups)
    if not np.all(np.isfinite(u) & (u > 0)):
        raise _no_u(path, "the wear field's bins")
    basis = (
        "per-point wear_depth_u over the bin: its independent part averaged, the rest as fully "
        "correlated within the bin (jointwear.wear_field.field_u)"
    )
    return [
        Datum(f"{FIELD}_{k}", cycles, float(values[k]), float(u[k]), str(path), index, basis)
        for k in range(len(groups))
    ]
