"""Figures of the validation report, rendered deterministically to inline SVG or PNG.

Line plots are SVG (text kept as text, ``svg.fonttype = "none"``), dense maps PNG. Output is
byte-identical for identical data: the SVG hash salt is fixed per figure (so ids differ between
figures of one page but not between runs), dates and software tags are left out of the
metadata, and the figures are drawn on :class:`matplotlib.figure.Figure` objects with no global
pyplot state.
"""

from __future__ import annotations

import base64
import io as _io
import re
from collections.abc import Sequence
from typing import Any

import numpy as np
import xarray as xr

__all__ = [
    "svg_markup",
    "png_data_uri",
    "wear_maps_figure",
    "polar_layers_figure",
    "motion_figure",
    "verification_figure",
]

_RC = {
    "svg.fonttype": "none",
    "font.family": "DejaVu Sans",
    "font.size": 8.5,
    "axes.titlesize": 9,
    "axes.labelsize": 8.5,
    "legend.fontsize": 7.5,
    "figure.dpi": 100,
    "savefig.dpi": 100,
    "path.simplify": False,
    "image.cmap": "magma_r",
}

SIM_COLOUR = "#1f5fa8"
MEAS_COLOUR = "#c0392b"


def _rc(key: str) -> dict[str, Any]:
    return {**_RC, "svg.hashsalt": f"jointwear-report-{key}"}


def svg_markup(fig: Any, key: str) -> str:
    """The figure as an ``<svg>`` element to inline in HTML (no XML prolog, no date)."""
    import matplotlib

    buf = _io.StringIO()
    with matplotlib.rc_context(_rc(key)):
        fig.savefig(buf, format="svg", metadata={"Date": None, "Creator": None})
    text = buf.getvalue()
    text = re.sub(r"<\?xml[^>]*\?>\s*", "", text)
    text = re.sub(r"<!DOCTYPE[^>]*>\s*", "", text)
    text = re.sub(r"\s*<metadata>.*?</metadata>", "", text, flags=re.S)  # RDF block
    # responsive width; keep the viewBox for the aspect ratio
    text = re.sub(r'<svg ([^>]*?)width="[^"]*" height="[^"]*"', r"<svg \1", text, count=1)
    text = text.replace("<svg ", f'<svg role="img" aria-label="{key}" class="figure" ', 1)
    return text.strip()


def png_data_uri(fig: Any, key: str, *, dpi: int = 110) -> str:
    """The figure as a ``data:image/png;base64,...`` URI (no software/date metadata)."""
    import matplotlib

    buf = _io.BytesIO()
    with matplotlib.rc_context(_rc(key)):
        fig.savefig(buf, format="png", dpi=dpi, metadata={"Software": None})
    return "data:image/png;base64," + base64.b64encode(buf.getvalue()).decode("ascii")


def _figure(width: float, height: float) -> Any:
    from matplotlib.figure import Figure

    with __import__("matplotlib").rc_context(_RC):
        return Figure(figsize=(width, height), layout="constrained")


def wear_maps_figure(wear: xr.Dataset) -> Any:
    """Simulated and measured wear maps side by side, plus their difference [µm].

    ``wear`` is the aligned dataset of :func:`jointwear.compare.align_wear_maps` (canonical
    theta [degree] by z [m]).
    """
    import matplotlib

    theta = np.asarray(wear["theta"].values, dtype=float)
    z_mm = np.asarray(wear["z"].values, dtype=float) * 1e3
    s = np.asarray(wear["wear_depth_sim"].values) * 1e6
    d = np.asarray(wear["wear_depth_meas"].values) * 1e6
    diff = s - d
    full = "wear_depth_sim_full" in wear
    if full:
        th_f = np.asarray(wear["theta_sim"].values, dtype=float)
        z_f = np.asarray(wear["z_sim"].values, dtype=float) * 1e3
        s = np.asarray(wear["wear_depth_sim_full"].values) * 1e6
    # one colour scale for both maps (a reader compares their colours), the difference on its
    # own diverging scale centred on zero
    vmax = float(np.nanmax([np.nanmax(s), np.nanmax(d)]))
    vmin = float(np.nanmin([np.nanmin(s), np.nanmin(d), 0.0]))
    dmax = float(np.nanmax(np.abs(diff))) or 1.0
    with matplotlib.rc_context(_RC):
        fig = _figure(10.5, 3.3)
        axes = fig.subplots(1, 3, sharey=True)
        panels = (
            (s, "simulation (whole width)" if full else "simulation", "magma_r", vmin, vmax),
            (d, "measurement", "magma_r", vmin, vmax),
            (diff, "simulation − measurement", "RdBu_r", -dmax, dmax),
        )
        meshes = []
        for k, (ax, (field, title, cmap, lo, hi)) in enumerate(zip(axes, panels, strict=True)):
            x, y = (th_f, z_f) if (full and k == 0) else (theta, z_mm)
            mesh = ax.pcolormesh(
                x, y, field, shading="nearest", cmap=cmap, vmin=lo, vmax=hi, rasterized=True
            )
            ax.set_title(title)
            if full:
                zlo, zhi = z_mm.min(), z_mm.max()
                for a, b in ((z_f.min(), zlo), (zhi, z_f.max())):
                    if b - a > 1e-9:
                        ax.axhspan(a, b, facecolor="none", edgecolor="0.35", hatch="///", lw=0)
                ax.axhline(zlo, color="0.2", lw=0.8, ls="--")
                ax.axhline(zhi, color="0.2", lw=0.8, ls="--")
                ax.set_ylim(z_f.min() - 0.5, z_f.max() + 0.5)
            ax.set_xlabel("θ [degree] (0 along −x, clockwise)")
            ax.set_xticks(np.arange(0, 361, 90))
            meshes.append(mesh)
        fig.colorbar(meshes[1], ax=list(axes[:2]), label="wear depth [µm] (both maps)")
        fig.colorbar(meshes[2], ax=axes[2], label="Δ [µm]")
        axes[0].set_ylabel("z [mm] (0 at mid-width)")
    return fig


def polar_layers_figure(wear: xr.Dataset, *, max_layers: int = 6) -> Any:
    """Per-layer polar plots of simulated and measured wear depth [µm], canonical orientation.

    Up to ``max_layers`` layers evenly spread over the common axial range (always the first and
    the last). Zero angle points left (−x), angles grow clockwise, as in the reference study.
    """
    import matplotlib
    from matplotlib.ticker import MaxNLocator

    z = np.asarray(wear["z"].values, dtype=float)
    theta = np.asarray(wear["theta"].values, dtype=float)
    n = min(max_layers, z.size)
    idx = np.unique(np.round(np.linspace(z.size - 1, 0, n)).astype(int))[::-1]
    s = np.asarray(wear["wear_depth_sim"].values) * 1e6
    d = np.asarray(wear["wear_depth_meas"].values) * 1e6
    ens = _band(wear, "wear_depth_sim_ensemble", 1e6)
    rmax = float(np.nanmax([np.nanmax(s), np.nanmax(d)])) * 1.05 or 1.0
    if ens is not None:
        rmax = max(rmax, float(np.nanmax(ens[1])) * 1.05)
    ncol = min(3, idx.size)
    nrow = int(np.ceil(idx.size / ncol))
    th = np.deg2rad(np.append(theta, theta[0] + 360.0))
    with matplotlib.rc_context(_RC):
        fig = _figure(3.2 * ncol, 3.0 * nrow)
        for k, i in enumerate(idx):
            ax = fig.add_subplot(nrow, ncol, k + 1, projection="polar")
            ax.set_theta_zero_location("W")
            ax.set_theta_direction(-1)
            if ens is not None:
                lo_b, hi_b = ens[0][i], ens[1][i]
                ax.fill_between(
                    th,
                    np.append(lo_b, lo_b[0]),
                    np.append(hi_b, hi_b[0]),
                    color=SIM_COLOUR,
                    alpha=0.2,
                    lw=0,
                    label="ensemble 5-95 %",
                )
            ax.plot(th, np.append(s[i], s[i][0]), color=SIM_COLOUR, lw=1.2, label="simulation")
            ax.plot(th, np.append(d[i], d[i][0]), color=MEAS_COLOUR, lw=1.0, label="measurement")
            # each layer on its own radial scale (a shared one leaves shallow layers empty)
            top = float(np.nanmax([np.nanmax(s[i]), np.nanmax(d[i])]))
            if ens is not None:
                top = max(top, float(np.nanmax(ens[1][i])))
            top = top * 1.05 if np.isfinite(top) and top > 0 else rmax
            ax.set_ylim(min(0.0, float(np.nanmin([s[i].min(), d[i].min()]))), top)
            ax.set_title(f"z = {z[i] * 1e3:+.2f} mm (max {top / 1.05:.3g} µm)", pad=10)
            ax.tick_params(labelsize=7)
            # three radial labels, between the 0 and 45 degree labels (none of them crowded)
            ax.yaxis.set_major_locator(MaxNLocator(3))
            ax.set_rlabel_position(22.5)
        handles, labels = fig.axes[0].get_legend_handles_labels()
        fig.legend(handles, labels, loc="outside lower center", ncol=len(labels), frameon=False)
        fig.suptitle("wear depth [µm] per layer", fontsize=9)
    return fig


def _band(ds: xr.Dataset, name: str, factor: float) -> tuple[np.ndarray, np.ndarray] | None:
    """5th and 95th percentile over ``run`` of an ensemble field (None when absent/empty)."""
    if name not in ds or "run" not in ds[name].dims:
        return None
    v = np.asarray(ds[name].transpose("run", ...).values, dtype=float) * factor
    ok = np.isfinite(v).reshape(v.shape[0], -1).any(axis=1)
    if ok.sum() < 2:
        return None
    return np.nanpercentile(v[ok], 5, axis=0), np.nanpercentile(v[ok], 95, axis=0)


def _components(motion: xr.Dataset) -> list[tuple[str, str | None]]:
    out = []
    for v in motion.data_vars:
        name = str(v)
        if not name.endswith("_sim") or name == "sim_time":
            continue
        base = name[: -len("_sim")]
        if "axis" in motion[name].dims:
            for c in motion["axis"].values:
                col = motion[f"{base}_meas"].sel(axis=c).values
                if np.isfinite(col).any():
                    out.append((base, str(c)))
        else:
            out.append((base, None))
    return out


def motion_figure(motion: xr.Dataset, *, k: float = 2.0) -> Any:
    """Aligned motion histories: measurement with its ``±k u`` band, simulation on top."""
    import matplotlib

    comps = _components(motion)
    t = np.asarray(motion["time"].values, dtype=float)
    with matplotlib.rc_context(_RC):
        fig = _figure(9.5, 1.9 * max(1, len(comps)) + 0.4)
        axes = np.atleast_1d(fig.subplots(max(1, len(comps)), 1, sharex=True))
        for ax, (base, c) in zip(axes, comps, strict=False):
            sel = {"axis": c} if c is not None else {}
            sim = motion[f"{base}_sim"].sel(sel)
            meas = motion[f"{base}_meas"].sel(sel)
            units = sim.attrs.get("units", "")
            m = np.asarray(meas.values, dtype=float)
            uname = f"{base}_meas_u"
            if uname in motion:
                u = np.asarray(motion[uname].sel(sel).values, dtype=float)
                ax.fill_between(
                    t,
                    m - k * u,
                    m + k * u,
                    color=MEAS_COLOUR,
                    alpha=0.22,
                    lw=0,
                    label=f"measurement ± {k:g}u",
                )
            band = _band(motion, f"{base}_sim_ensemble", 1.0)
            if band is not None:
                lo_b, hi_b = band
                if c is not None and "axis" in motion[f"{base}_sim_ensemble"].dims:
                    j = [str(a) for a in motion["axis"].values].index(c)
                    lo_b, hi_b = lo_b[:, j], hi_b[:, j]
                ax.fill_between(
                    t, lo_b, hi_b, color=SIM_COLOUR, alpha=0.2, lw=0, label="ensemble 5-95 %"
                )
            ax.plot(t, m, color=MEAS_COLOUR, lw=0.9, marker=".", ms=2.5, label="measurement")
            ax.plot(
                t, np.asarray(sim.values, dtype=float), color=SIM_COLOUR, lw=1.1, label="simulation"
            )
            label = base.replace("_", " ") + (f" {c}" if c else "")
            ax.set_ylabel(f"{label}\n[{units}]")
            ax.grid(True, lw=0.3, alpha=0.5)
        axes[0].legend(loc="upper right", ncol=3, frameon=False)
        axes[-1].set_xlabel("time of the measurement [s]")
    return fig


_DISPLAY = {"m": (1e6, "µm"), "m3": (1e9, "mm³")}


#: Quantities of a verification study shown in the report (when present).
STUDY_PLOTTED = ("max_wear_depth", "worn_volume", "cylindricity")


def _study_series(ds: xr.Dataset) -> list[tuple]:
    """Series of a ``jointwear sim verify`` study: level means over ΔN with their standard
    errors and the band value ± u_num (k = 1) of the finest level."""
    out = []
    names = [str(q) for q in ds["quantity"].values]
    for q in [*STUDY_PLOTTED, *(n for n in names if n.endswith("_in_band"))]:
        if q not in names:
            continue
        row = ds.sel(quantity=q)
        assessed = int(row["assessed"]) == 1
        attrs = {
            "units": str(row["quantity_units"].values),
            "long_name": f"{q}, band: value ± u_num" if assessed else f"{q}: u_num not assessed",
            "sem": np.asarray(row["level_sem"].values, dtype=float),
            "value": float(row["value"]),
            "u_num": float(row["u_num"]) if assessed else float("nan"),
        }
        x = np.asarray(ds["h"].values, dtype=float)
        out.append((q, "h", x, np.asarray(row["level_mean"].values, dtype=float), attrs, ds))
    return out


def _log_x(ax: Any, x: np.ndarray) -> None:
    """A logarithmic x axis whose labels do not run together: each level's value as a plain
    number when they span less than two decades and are few (ΔN = 12500 ... 100000), else
    powers of ten (solver tolerances 1e-4 ... 1e-12)."""
    from matplotlib.ticker import (
        LogFormatterSciNotation,
        LogLocator,
        NullFormatter,
        ScalarFormatter,
    )

    ax.set_xscale("log")
    levels = np.unique(x)
    if levels.max() / levels.min() < 100 and levels.size <= 5:
        ax.xaxis.set_major_formatter(ScalarFormatter())
        ax.set_xticks(levels)
    else:
        ax.xaxis.set_major_locator(LogLocator(base=10, numticks=6))
        ax.xaxis.set_major_formatter(LogFormatterSciNotation())
    ax.xaxis.set_minor_formatter(NullFormatter())


def verification_figure(datasets: Sequence[xr.Dataset]) -> Any | None:
    """Convergence plots of verification data: every 1-D variable against its dimension.

    A ``jointwear sim verify`` study shows the replicate means ± standard error of its wear
    quantities over ΔN and the finest level's value ± u_num (k = 1) as a band.
    Logarithmic x axis when the refinement parameter is positive (tolerances, grid steps), and
    a logarithmic y axis too when the values are positive and span more than a decade (then the
    slope is the observed order of convergence). Lengths in µm, volumes in mm³. Returns None
    when there is nothing to plot.
    """
    import matplotlib

    series = []
    for ds in datasets:
        if ds.attrs.get("jointwear_file") == "verification_study":
            series += _study_series(ds)
            continue
        for name, var in ds.data_vars.items():
            if var.ndim != 1 or var.size < 2 or var.dtype.kind not in "fiu":
                continue
            dim = var.dims[0]
            x = np.asarray(ds[dim].values if dim in ds.coords else np.arange(var.size), dtype=float)
            series.append((str(name), dim, x, np.asarray(var.values, dtype=float), var.attrs, ds))
    if not series:
        return None
    with matplotlib.rc_context(_RC):
        ncol = min(3, len(series))
        nrow = int(np.ceil(len(series) / ncol))
        fig = _figure(max(9.5, 3.4 * ncol), 2.9 * nrow)
        for k, (name, dim, x, y, attrs, ds) in enumerate(series):
            ax = fig.add_subplot(nrow, ncol, k + 1)
            factor, units = _DISPLAY.get(str(attrs.get("units", "")), (1.0, attrs.get("units", "")))
            ax.plot(x, y * factor, marker="o", color=SIM_COLOUR, lw=1.0, ms=3)
            if "sem" in attrs:  # a verification study: replicate means ± standard error, u_num
                ax.errorbar(
                    x, y * factor, yerr=attrs["sem"] * factor, fmt="none", ecolor=SIM_COLOUR
                )
                v, u = attrs["value"] * factor, attrs["u_num"] * factor
                if np.isfinite(u):
                    ax.axhspan(v - u, v + u, color=SIM_COLOUR, alpha=0.12, lw=0)
            if np.all(x > 0):
                _log_x(ax, x)
            if np.all(y > 0) and y.max() / y.min() > 10:
                ax.set_yscale("log")
            else:
                ax.ticklabel_format(axis="y", useOffset=False, style="plain")
            xu = ds[dim].attrs.get("units", "") if dim in ds.coords else ""
            ax.set_xlabel(f"{dim}" + (f" [{xu}]" if xu and xu != "1" else ""))
            ax.set_ylabel(f"{name} [{units}]")
            ax.set_title(str(attrs.get("long_name", name))[:60])
            ax.grid(True, which="both", lw=0.3, alpha=0.5)
    return fig
