"""Wear maps of the bearing bore: the discrete grid, the contract Dataset, volume, cylindricity, plots.

The bearing's inner surface is discretised as in the reference study (eq. 2 of Zhang et al. 2023):
``Nl`` layers over the bearing width ``wb`` (layer ``n = 0`` at ``z = +wb/2`` ... layer ``Nl - 1``
at ``z = -wb/2``; equally spaced as in the study, or crowded towards both edges with
``axial_grading``, :func:`layer_positions`) times ``Nd`` points per layer at ``phi_m = m * 360 / Nd`` degrees
in the canonical angle convention (0 along -x of the bearing frame, clockwise seen from +z).
Simulator arrays are indexed ``[n, m]`` (layer, point). The :mod:`jointwear.conventions` Dataset
instead has ``z`` *ascending*, so the layer axis is reversed when a map is written.

Each point stands for a patch of the bore: ``Rb * dphi`` around the circumference times the
trapezoidal share of the width (half of each neighbouring layer spacing), so the patch
areas add up to the bore area ``2 pi Rb wb`` for any grid.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import xarray as xr

from jointwear import conventions
from jointwear.errors import BadInputError, ParameterError

__all__ = [
    "BearingGrid",
    "layer_positions",
    "wear_map_dataset",
    "worn_volume",
    "edge_volume_share",
    "bore_radius",
    "bore_cylindricity",
    "plot_wear_map",
    "plot_wear_history",
]


def layer_positions(
    n_layers: int, width: float, grading: float = 0.0
) -> tuple[np.ndarray, np.ndarray]:
    """Axial position of each layer [m] and its trapezoidal share of the width (sums to 1).

    Layer order (``+wb/2`` first). ``grading`` in [0, 1) blends the uniform spacing with
    Chebyshev-Gauss-Lobatto points, ``z = wb/2 ((1 - g) s + g sin(pi s / 2))`` with ``s``
    uniform in [1, -1]: the layers crowd towards both bearing edges (the spacing there is
    about ``(1 - g)`` times the uniform one, and ``1 + 0.57 g`` times it at mid-width), where
    a tilted journal's contacts and their wear are shorter than a uniform layer spacing.
    ``grading = 0`` is the study's equal spacing (eq. 2).
    """
    n = int(n_layers)
    g = float(grading)
    if g == 0.0:  # the study's spacing, written as eq. 2 (bit for bit as before the grading)
        share = np.full(n, 1.0 / (n - 1))
        share[[0, -1]] = 0.5 / (n - 1)
        return width / 2 - np.arange(n) * width / (n - 1), share
    s = 1.0 - 2.0 * np.arange(n) / (n - 1)
    z = 0.5 * width * ((1.0 - g) * s + g * np.sin(0.5 * np.pi * s))
    z[0], z[-1] = 0.5 * width, -0.5 * width
    dz = -np.diff(z)
    share = np.zeros(n)
    share[:-1] += 0.5 * dz
    share[1:] += 0.5 * dz
    return z, share / width


@dataclass(frozen=True)
class BearingGrid:
    """Discretisation of the bearing bore (reference study eq. 2).

    Parameters
    ----------
    n_layers : int
        Number of layers ``Nl`` over the width (>= 2; the first and last lie on the edges).
    n_points : int
        Number of points ``Nd`` per layer, equally spaced in angle (>= 8).
    radius : float
        Unworn bore radius ``Rb`` [m].
    width : float
        Bearing width ``wb`` [m].
    axial_grading : float
        Crowding of the layers towards the bearing edges, in [0, 1) (0: equal spacing, the
        study's eq. 2); see :func:`layer_positions`.
    """

    n_layers: int = 20
    n_points: int = 200
    radius: float = 8.0e-3
    width: float = 15.0e-3
    axial_grading: float = 0.0

    def __post_init__(self) -> None:
        if int(self.n_layers) != self.n_layers or self.n_layers < 2:
            raise ParameterError(
                f"n_layers must be an integer >= 2 (layers on both bearing edges), got {self.n_layers!r}"
            )
        if int(self.n_points) != self.n_points or self.n_points < 8:
            raise ParameterError(
                f"n_points must be an integer >= 8 points per layer, got {self.n_points!r}"
            )
        for name in ("radius", "width"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value > 0):
                raise ParameterError(f"bearing {name} must be a positive length [m], got {value!r}")
        if not (np.isfinite(self.axial_grading) and 0.0 <= self.axial_grading < 1.0):
            raise ParameterError(
                f"axial_grading must lie in [0, 1) (0: equal layer spacing), got {self.axial_grading!r}"
            )

    @classmethod
    def from_params(cls, params: Any) -> BearingGrid:
        """The grid of a :class:`jointwear.sim.SimParameters` (``params.joint``)."""
        joint = params.joint
        return cls(
            n_layers=int(joint.n_layers),
            n_points=int(joint.n_points),
            radius=float(joint.bearing_radius),
            width=float(joint.bearing_width),
            axial_grading=float(joint.axial_grading),
        )

    @property
    def shape(self) -> tuple[int, int]:
        """``(Nl, Nd)``: the shape of every per-point array, index ``[layer, point]``."""
        return (self.n_layers, self.n_points)

    @property
    def z(self) -> np.ndarray:
        """Axial position of each layer [m], layer order (``+wb/2`` first)."""
        return layer_positions(self.n_layers, self.width, self.axial_grading)[0]

    @property
    def theta_deg(self) -> np.ndarray:
        """Angle of each point [degree], canonical convention."""
        return np.arange(self.n_points) * 360.0 / self.n_points

    @property
    def point_area(self) -> np.ndarray:
        """Bore area each point stands for, shape ``(Nl, Nd)`` [m²] (trapezoid in z)."""
        dz = self.width * layer_positions(self.n_layers, self.width, self.axial_grading)[1]
        dphi = 2 * math.pi / self.n_points
        return np.repeat((self.radius * dphi * dz)[:, None], self.n_points, axis=1)

    def check(self, array: np.ndarray, name: str) -> np.ndarray:
        """Return ``array`` as float64 of shape :attr:`shape`, or raise naming ``name``."""
        arr = np.asarray(array, dtype=float)
        if arr.shape != self.shape:
            raise BadInputError(
                f"{name} has shape {arr.shape}, expected (n_layers, n_points) = {self.shape}; "
                "use an array on the simulator's bearing grid"
            )
        if not np.all(np.isfinite(arr)):
            raise BadInputError(f"{name} contains NaN or infinite values")
        return arr


def worn_volume(wear_depth: np.ndarray, grid: BearingGrid) -> float:
    """Volume of material removed from the bore [m³].

    Parameters
    ----------
    wear_depth : ndarray, shape (Nl, Nd)
        Wear depth per point [m].
    grid : BearingGrid
        The discretisation.

    Notes
    -----
    ``sum(h * A)`` with the patch areas of :attr:`BearingGrid.point_area`: the first-order term of
    the exact annulus volume ``((Rb + h)^2 - Rb^2) / 2 dphi dz`` (relative error ``h / 2Rb``, i.e.
    0.3 % for 50 µm in an 8 mm bore).
    """
    return float(np.sum(grid.check(wear_depth, "wear_depth") * grid.point_area))


def edge_volume_share(wear_depth: xr.DataArray, inner_half_width: float = 6e-3) -> xr.DataArray:
    """Share of the worn volume that lies outside ``|z| <= inner_half_width`` [1].

    The profile is integrated exactly as the piecewise-linear function of z that the map's
    layers define (patch widths in theta are equal, so the angle sum stands for the area), so
    the share does not depend on where the layers lie. Uniform wear along the width gives
    ``1 - 2 inner_half_width / wb`` (0.2 for the study's 15-mm bearing and 6 mm); wear that
    sits at the bearing edges gives values near 1.

    Parameters
    ----------
    wear_depth : DataArray
        Wear depth [m] over ``z`` [m] and ``theta`` (and optionally ``cycles``).
    inner_half_width : float
        Half-width of the central band [m].

    Returns
    -------
    DataArray
        The share (over ``cycles`` if the map has it); NaN where nothing has worn.

    Raises
    ------
    BadInputError
        The map does not extend beyond the central band on both sides (e.g. a measured map of a
        narrower band), or lacks ``z``/``theta``.
    """
    if "z" not in wear_depth.dims or "theta" not in wear_depth.dims:
        raise BadInputError(f"wear_depth has dims {wear_depth.dims}, expected z and theta")
    prof = wear_depth.sum("theta").sortby("z")
    z = prof["z"].values
    if not (z[0] < -inner_half_width and z[-1] > inner_half_width):
        raise BadInputError(
            f"the wear map covers z = {z[0] * 1e3:.3g} ... {z[-1] * 1e3:.3g} mm, which does not "
            f"reach beyond the central band |z| <= {inner_half_width * 1e3:g} mm on both sides: "
            "the share outside it would mean nothing; give a smaller inner_half_width"
        )
    edges = np.unique(
        np.clip(np.concatenate([z, [-inner_half_width, inner_half_width]]), z[0], z[-1])
    )
    fine = prof.interp(z=edges)  # exact: the profile is linear between layers
    seg = 0.5 * (fine.isel(z=slice(1, None)).values + fine.isel(z=slice(None, -1)).values)
    seg = np.moveaxis(seg, fine.get_axis_num("z"), -1) * np.diff(edges)
    mid = 0.5 * (edges[1:] + edges[:-1])
    total = seg.sum(axis=-1)
    outside = seg[..., np.abs(mid) > inner_half_width].sum(axis=-1)
    with np.errstate(invalid="ignore", divide="ignore"):
        share = np.where(total > 0, outside / np.where(total > 0, total, 1.0), np.nan)
    dims = [d for d in fine.dims if d != "z"]
    return xr.DataArray(
        share,
        dims=dims,
        coords={d: fine[d] for d in dims},
        attrs={
            "units": "1",
            "long_name": f"share of the worn volume outside |z| <= {inner_half_width * 1e3:g} mm",
        },
    )


def bore_radius(wear_depth: xr.DataArray, radius: float) -> xr.DataArray:
    """Radius of the worn bore over ``(z, theta)`` [m]: ``Rb + h`` (wear removes material)."""
    out = radius + wear_depth
    out.attrs = conventions.variable_attrs("radius", comment="simulated worn bore: Rb + wear_depth")
    out.name = "radius"
    return out


def bore_cylindricity(radius: xr.DataArray) -> float:
    """Cylindricity of a bore [m], by the metrology module's own definition.

    Calls ``jointwear.metrology.cylindricity(radius, reference="MZ")`` (minimum-zone), so a
    simulated bore and a measured one are assessed identically. Returns NaN when that function
    is not available in this installation.

    Parameters
    ----------
    radius : DataArray over (z, theta)
        Bore radius [m], theta in degrees with its convention attributes.
    """
    try:
        from jointwear.metrology import cylindricity
    except ImportError:
        return float("nan")
    return float(cylindricity(radius, reference="MZ"))


def wear_map_dataset(
    snapshots: np.ndarray,
    cycles: np.ndarray,
    grid: BearingGrid,
    *,
    cylindricity: bool = True,
    extra: dict[str, xr.DataArray] | None = None,
    attrs: dict[str, Any] | None = None,
) -> xr.Dataset:
    """Build the contract wear-map Dataset from simulator snapshots.

    Parameters
    ----------
    snapshots : ndarray, shape (K, Nl, Nd)
        Wear depth per point at each snapshot [m], simulator index ``[k, layer, point]``.
    cycles : ndarray, shape (K,)
        Crank revolutions completed at each snapshot (strictly increasing).
    grid : BearingGrid
        The discretisation.
    cylindricity : bool
        Also compute the cylindricity of the worn bore per snapshot (metrology definition).
    extra : dict, optional
        Further variables to include.
    attrs : dict, optional
        Global attributes.

    Returns
    -------
    Dataset
        ``wear_depth(cycles, z, theta)`` [m] with z ascending and theta canonical, plus
        ``worn_volume(cycles)`` [m³], ``max_wear_depth(cycles)`` [m] and
        ``cylindricity(cycles)`` [m].
    """
    snaps = np.asarray(snapshots, dtype=float)
    if snaps.ndim != 3 or snaps.shape[1:] != grid.shape:
        raise BadInputError(
            f"wear snapshots have shape {snaps.shape}, expected (K, {grid.n_layers}, {grid.n_points})"
        )
    cyc = np.asarray(cycles, dtype=float)
    depth = snaps[:, ::-1, :]  # layer order (+wb/2 first) -> z ascending
    z = conventions.z_coord(
        grid.z[::-1], note=f"layers of the simulated bearing, layer 1 at z = +{grid.width / 2:g} m"
    )
    theta = conventions.theta_coord(
        grid.theta_deg, note="canonical: theta = 0 along -x of the bearing frame, clockwise from +z"
    )
    cyc_coord = xr.DataArray(
        cyc,
        dims="cycles",
        attrs={"units": "1", "long_name": conventions.COORDINATES["cycles"][1]},
    )
    ds = xr.Dataset(coords={"cycles": cyc_coord, "z": z, "theta": theta})
    ds["wear_depth"] = (("cycles", "z", "theta"), depth, conventions.variable_attrs("wear_depth"))
    ds["worn_volume"] = (
        "cycles",
        np.array([worn_volume(s, grid) for s in snaps]),
        {"units": "m3", "long_name": "volume of bearing material removed by wear"},
    )
    ds["max_wear_depth"] = (
        "cycles",
        depth.reshape(len(cyc), -1).max(axis=1) if len(cyc) else np.zeros(0),
        {"units": "m", "long_name": "largest wear depth over the bore"},
    )
    cyl = np.full(len(cyc), np.nan)
    if cylindricity:
        for k in range(len(cyc)):
            cyl[k] = bore_cylindricity(bore_radius(ds["wear_depth"].isel(cycles=k), grid.radius))
    ds["cylindricity"] = (
        "cycles",
        cyl,
        {
            "units": "m",
            "long_name": "cylindricity of the worn bore (minimum zone)",
            "comment": "jointwear.metrology.cylindricity of radius = Rb + wear_depth; NaN if "
            "the metrology module is not available",
        },
    )
    for name, value in (extra or {}).items():
        ds[name] = value
    ds.attrs.update(
        {
            "title": "simulated wear map of the bearing bore",
            "data_origin": "simulated",
            "bearing_radius_m": grid.radius,
            "bearing_width_m": grid.width,
            "n_layers": grid.n_layers,
            "n_points": grid.n_points,
            "axial_grading": grid.axial_grading,
        }
    )
    ds.attrs.update(attrs or {})
    return ds


def plot_wear_map(
    ds: xr.Dataset | xr.DataArray,
    *,
    cycles: float | None = None,
    kind: str = "unrolled",
    layers: list[int] | None = None,
    ax: Any = None,
    title: str | None = None,
):
    """Plot a wear map: unrolled (angle x axial position) or polar (depth vs angle per layer).

    Parameters
    ----------
    ds : Dataset or DataArray
        A wear map with ``wear_depth`` over ``(cycles,) z, theta`` [m]; theta in any stated
        convention (converted to canonical for the plot).
    cycles : float, optional
        Snapshot to show (nearest); default the last one.
    kind : {"unrolled", "polar", "both"}
        ``"unrolled"``: colour map of depth [µm] over theta [degree] x z [mm]. ``"polar"``:
        depth [µm] versus angle for selected layers (polar axes). ``"both"``: side by side.
    layers : list of int, optional
        Layer numbers (1 = z = +wb/2, as in the study) for the polar plot; default first,
        middle and last.
    ax : matplotlib Axes, optional
        Axes to draw into (``kind`` "unrolled" or "polar"; a polar plot needs polar axes).
    title : str, optional
        Figure title.

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt

    da = ds["wear_depth"] if isinstance(ds, xr.Dataset) else ds
    da = conventions.to_canonical(da)
    if "cycles" in da.dims:
        n = float(da["cycles"].values[-1]) if cycles is None else float(cycles)
        da = da.sel(cycles=n, method="nearest")
        n_shown = float(da["cycles"].values)
    else:
        n_shown = None
    if kind not in ("unrolled", "polar", "both"):
        raise BadInputError(f"kind must be 'unrolled', 'polar' or 'both', got {kind!r}")
    z = np.asarray(da["z"].values)
    theta = np.asarray(da["theta"].values)
    depth_um = np.asarray(da.transpose("z", "theta").values) * 1e6
    order = np.argsort(-z)  # layer 1 = largest z
    if layers is None:
        layers = sorted({1, (len(z) + 1) // 2, len(z)})
    for layer in layers:
        if not 1 <= layer <= len(z):
            raise BadInputError(f"layer {layer} does not exist; layers are 1 .. {len(z)}")

    if ax is not None:
        fig = ax.figure
        axes = {kind: ax}
    elif kind == "both":
        fig = plt.figure(figsize=(11, 4.2))
        axes = {
            "unrolled": fig.add_subplot(1, 2, 1),
            "polar": fig.add_subplot(1, 2, 2, projection="polar"),
        }
    else:
        fig = plt.figure(figsize=(6.2, 4.2))
        axes = {kind: fig.add_subplot(1, 1, 1, projection="polar" if kind == "polar" else None)}

    if "unrolled" in axes:
        a = axes["unrolled"]
        mesh = a.pcolormesh(theta, z * 1e3, depth_um, shading="nearest", cmap="magma_r")
        fig.colorbar(mesh, ax=a, label="wear depth [µm]")
        a.set_xlabel("theta [degree] (0 along -x, clockwise from +z)")
        a.set_ylabel("z [mm] (0 at mid-width)")
        a.set_xlim(0, 360)
        a.set_xticks(np.arange(0, 361, 60))
    if "polar" in axes:
        a = axes["polar"]
        a.set_theta_zero_location("W")  # theta = 0 along -x
        a.set_theta_direction(-1)  # clockwise
        th = np.deg2rad(np.append(theta, theta[0] + 360.0))
        for layer in layers:
            row = depth_um[order[layer - 1]]
            a.plot(
                th,
                np.append(row, row[0]),
                label=f"layer {layer} (z = {z[order[layer - 1]] * 1e3:+.1f} mm)",
            )
        a.set_title("wear depth [µm]", fontsize=9)
        a.legend(loc="lower left", bbox_to_anchor=(0.75, -0.15), fontsize=7)
    if title is None and n_shown is not None:
        title = f"simulated wear after {n_shown:.3g} cycles"
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    return fig


def plot_wear_history(
    ds: xr.Dataset,
    *,
    measured_cylindricity: dict[float, float] | None = None,
    title: str | None = None,
):
    """Plot wear growth over the cycles and the update intervals used.

    Parameters
    ----------
    ds : Dataset
        A wear map from :func:`jointwear.sim.simulate_wear` (snapshots and ``update_*``).
    measured_cylindricity : dict, optional
        Measured growth of the bore's cylindricity [m] by cycle count, drawn as markers.
    title : str, optional
        Figure title.

    Returns
    -------
    matplotlib.figure.Figure
        Left: maximum depth and cylindricity [µm] versus cycles; right: dN per update.
    """
    import matplotlib.pyplot as plt

    fig, (a, b) = plt.subplots(1, 2, figsize=(10, 3.8))
    cyc = np.asarray(ds["cycles"].values, dtype=float)
    a.plot(cyc, ds["max_wear_depth"].values * 1e6, "o-", label="max wear depth")
    if "cylindricity" in ds and np.any(np.isfinite(ds["cylindricity"].values)):
        a.plot(cyc, ds["cylindricity"].values * 1e6, "s--", label="cylindricity of the bore")
    if measured_cylindricity:
        mc = sorted(measured_cylindricity.items())
        a.plot(
            [c for c, _ in mc],
            [v * 1e6 for _, v in mc],
            "k*",
            markersize=11,
            label="measured cylindricity growth",
        )
    a.set_xlabel("cycles")
    a.set_ylabel("µm")
    a.set_xlim(left=0)
    a.set_ylim(bottom=0)
    a.legend(fontsize=8)
    a.grid(alpha=0.3)
    if "update_dn" in ds:
        acc = np.asarray(ds["update_accepted"].values) == 1
        start = np.asarray(ds["update_start"].values, dtype=float)
        dn = np.asarray(ds["update_dn"].values, dtype=float)
        b.step(start[acc], dn[acc], where="post", label="accepted")
        if np.any(~acc):
            b.plot(start[~acc], dn[~acc], "rx", label="rejected")
        b.set_yscale("log")
        b.set_xlabel("cycles")
        b.set_ylabel("cycles per update dN")
        b.legend(fontsize=8)
        b.grid(alpha=0.3)
    fig.suptitle(title or "wear growth and update intervals")
    fig.tight_layout()
    return fig
