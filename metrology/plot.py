"""Wear-map figures: unrolled map (angle x z) and per-layer polar plots."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import xarray as xr

from jointwear.errors import BadInputError

__all__ = ["plot_wear_map"]


def plot_wear_map(
    wear: xr.Dataset | xr.DataArray,
    *,
    layers: list[int] | None = None,
    path: str | Path | None = None,
    title: str | None = None,
    dpi: int = 110,
):
    """Plot a wear map: unrolled (theta x z) colour map and polar plots of chosen layers.

    Parameters
    ----------
    wear : Dataset or DataArray
        ``wear_depth`` [m] over (``z`` [m], ``theta`` [degree]) (a Dataset from
        :func:`~jointwear.metrology.wearmap.wear_map`, or a simulated wear map; a ``cycles``
        dimension, if present, is reduced to its last entry).
    layers : list of int, optional
        Layer indices for the polar plot (default: first, middle and last).
    path : path, optional
        Save the figure there (PNG/PDF/SVG; written atomically).
    title : str, optional
        Figure title.
    dpi : int
        Resolution of a saved raster figure.

    Returns
    -------
    matplotlib.figure.Figure
        Left: wear depth [µm] over theta [degree, convention stated in the axis label] and z
        [mm]; right: wear depth [µm] against theta for the chosen layers (polar axes, theta
        drawn in the map's own convention: zero and direction as stated).
    """
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    da = wear["wear_depth"] if isinstance(wear, xr.Dataset) else wear
    if "cycles" in da.dims:
        da = da.isel(cycles=-1)
    if set(da.dims) != {"z", "theta"}:
        raise BadInputError(f"plot_wear_map: expected wear_depth over (z, theta), got {da.dims}")
    da = da.transpose("z", "theta")
    th = np.asarray(da["theta"].values, dtype=float)
    z = np.asarray(da["z"].values, dtype=float)
    w = np.asarray(da.values, dtype=float) * 1e6
    zero = da["theta"].attrs.get("angle_zero", "?")
    direction = da["theta"].attrs.get("angle_direction", "?")
    nz = z.size
    if layers is None:
        layers = sorted({0, nz // 2, nz - 1})
    bad = [i for i in layers if not -nz <= i < nz]
    if bad:
        raise BadInputError(f"plot_wear_map: layer index {bad} out of range (0..{nz - 1})")

    fig = plt.figure(figsize=(11, 4.2), layout="constrained")
    gs = fig.add_gridspec(1, 2, width_ratios=[1.7, 1])
    ax = fig.add_subplot(gs[0])
    lim = np.nanmax(np.abs(w)) or 1.0
    vmin = min(np.nanmin(w), 0.0)
    mesh = ax.pcolormesh(th, z * 1e3, w, shading="nearest", cmap="viridis", vmin=vmin, vmax=lim)
    ax.set_xlabel(f"theta [degree] (0 along {zero}, {direction})")
    ax.set_ylabel("z [mm] (0 = mid-width)")
    ax.set_xlim(0, 360)
    ax.set_xticks(np.arange(0, 361, 45))
    fig.colorbar(mesh, ax=ax, label="wear depth [µm]")
    ax.set_title("unrolled wear map")

    pax = fig.add_subplot(gs[1], projection="polar")
    # draw theta in the map's own convention: zero direction and sense as stated
    from jointwear.conventions import AngleConvention

    try:
        conv = AngleConvention(zero, direction)
        offset = np.radians(conv.zero_angle_deg)
        pax.set_theta_offset(offset)
        pax.set_theta_direction(-1 if conv.direction == "clockwise" else 1)
    except Exception:  # noqa: BLE001 - convention missing: plot plainly
        pass
    tt = np.radians(np.append(th, th[0] + 360.0))
    for i in layers:
        row = np.append(w[i], w[i][0])
        pax.plot(tt, row, lw=1.2, label=f"z = {z[i] * 1e3:+.1f} mm")
    from matplotlib.ticker import MaxNLocator

    sel = w[layers]
    pax.set_rlim(min(0.0, float(np.nanmin(sel))), float(np.nanmax(sel)) or 1.0)
    pax.yaxis.set_major_locator(MaxNLocator(4))
    pax.set_rlabel_position(112.5)
    pax.tick_params(axis="y", labelsize=7)
    pax.set_title("wear depth per layer [µm]\n(bearing frame: +x right, +y up)", fontsize=9)
    pax.legend(loc="lower left", bbox_to_anchor=(-0.25, -0.2), fontsize=8)
    if title:
        fig.suptitle(title)
    if path is not None:
        from jointwear.io import save_figure

        save_figure(fig, path, dpi=dpi)
    return fig
