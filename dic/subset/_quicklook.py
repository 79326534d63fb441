"""Quick-look figure of a 2D DIC result: colour maps of u and v, arrows, invalid points masked.

``plot_displacement(ds, *, time=-1, background=None, arrows=True, title=None) -> Figure``
    ``ds`` as returned by :func:`jointwear.dic.correlate` (grid ``(y, x)`` or ``point``) or
    :func:`jointwear.dic.correlate_sequence` (``time`` selects the frame). Invalid points (flag
    not ``ok``) are left blank on the maps and marked with grey crosses.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import xarray as xr

__all__ = ["plot_displacement", "save_quicklook"]


def plot_displacement(
    ds: xr.Dataset,
    *,
    time: int | None = -1,
    background: np.ndarray | None = None,
    arrows: bool = True,
    title: str | None = None,
):
    """Figure with the u and v displacement [pixel] as colour maps (matplotlib ``Figure``)."""
    from matplotlib.figure import Figure

    if "time" in ds.dims and time is not None:
        ds = ds.isel(time=time)
    ok = ds["flag"].values == 0
    fig = Figure(figsize=(10.5, 4.4), layout="constrained")
    axes = fig.subplots(1, 2, sharex=True, sharey=True)
    grid = "point" not in ds.dims
    x = ds["x"].values
    y = ds["y"].values
    u = ds["u"].values
    v = ds["v"].values
    for ax, comp, name in ((axes[0], u, "u"), (axes[1], v, "v")):
        if background is not None:
            ax.imshow(background, cmap="gray", alpha=0.45, origin="upper")
        vals = np.ma.masked_invalid(np.where(ok, comp, np.nan))
        if grid:
            dx = x[1] - x[0] if x.size > 1 else 1.0
            dy = y[1] - y[0] if y.size > 1 else 1.0
            extent = (x[0] - dx / 2, x[-1] + dx / 2, y[-1] + dy / 2, y[0] - dy / 2)
            im = ax.imshow(vals, extent=extent, cmap="viridis", origin="upper", alpha=0.85)
            X, Y = np.meshgrid(x, y)
        else:
            X, Y = x, y
            im = ax.scatter(X[ok], Y[ok], c=comp[ok], cmap="viridis", s=18)
        bad = ~ok
        if bad.any():
            ax.plot(
                np.asarray(X)[bad],
                np.asarray(Y)[bad],
                "x",
                color="0.45",
                ms=4,
                label=f"invalid ({int(bad.sum())})",
            )
            ax.legend(loc="lower right", fontsize=8, framealpha=0.8)
        if arrows and ok.any():
            sel = ok
            n = int(sel.sum())
            stride = max(1, int(np.sqrt(n / 400)))
            Xs, Ys, Us, Vs = (
                (np.asarray(a)[::stride, ::stride] if grid else np.asarray(a))
                for a in (X, Y, np.where(ok, u, np.nan), np.where(ok, v, np.nan))
            )
            ax.quiver(Xs, Ys, Us, Vs, angles="xy", color="k", alpha=0.6, width=0.003)
        cb = fig.colorbar(im, ax=ax, shrink=0.85)
        cb.set_label(f"{name} [pixel]")
        ax.set_title(f"{name} (x right, y down)")
        ax.set_xlabel("x [pixel]")
        ax.set_aspect("equal")
        if not grid or background is None:
            ax.invert_yaxis() if not ax.yaxis_inverted() else None
    axes[0].set_ylabel("y [pixel]")
    zn = ds["zncc"].values[ok]
    summary = (
        f"{int(ok.sum())}/{ok.size} points ok"
        + (f", median ZNCC {np.median(zn):.4f}" if zn.size else "")
        + (
            f", t = {float(ds['time']):.4g} s"
            if "time" in ds.coords and ds["time"].ndim == 0
            else ""
        )
    )
    fig.suptitle(f"{title + ': ' if title else ''}{summary}", fontsize=10)
    return fig


def save_quicklook(ds: xr.Dataset, path: str | Path, **kwargs) -> Path:
    """Write :func:`plot_displacement` to ``path`` (png/pdf/svg), atomically."""
    from jointwear.io import save_figure

    return save_figure(plot_displacement(ds, **kwargs), path, dpi=90)
