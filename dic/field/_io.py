"""Export and display of full-field DIC results (:func:`jointwear.dic.measure_field`).

``write_field_csv(ds, path, *, time=None)``: one CSV per image, VIC-3D-like columns (one row per
point, flagged points kept with empty values): ``x``, ``y`` [pixel] (left reference image),
``X``, ``Y``, ``Z``, ``U``, ``V``, ``W`` and their standard uncertainties ``sigma_U`` ...
in millimetres as VIC-3D exports them (stereo; the header says ``[mm]``), or ``u``, ``v``
[pixel] (2D); ``exx``, ``eyy``, ``exy`` (Green-Lagrange, tensor shear) and ``sigma_exx`` ...
[1]; ``zncc``; ``flag`` (the flag's name).

``plot_field(ds, *, time=-1)``: filled contour maps of the displacement components (and the
strain components) over the surface (stereo: the position's x, y in mm; 2D: the left image in
pixels, y down), flagged points left blank.
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import xarray as xr

__all__ = ["write_field_csv", "plot_field"]


def _columns(ds: xr.Dataset, k: int) -> dict[str, np.ndarray]:
    stereo = "position" in ds
    cols: dict[str, np.ndarray] = {"x": ds.x.values, "y": ds.y.values}
    d = ds.displacement.isel(time=k).values
    du = ds.displacement_u.isel(time=k).values
    if stereo:
        P = ds.position.values
        for i, a in enumerate("XYZ"):
            cols[f"{a} [mm]"] = P[:, i] * 1e3
        for i, a in enumerate("UVW"):
            cols[f"{a} [mm]"] = d[:, i] * 1e3
        for i, a in enumerate("UVW"):
            cols[f"sigma_{a} [mm]"] = du[:, i] * 1e3
    else:
        for i, a in enumerate("uv"):
            cols[f"{a} [pixel]"] = d[:, i]
        for i, a in enumerate("uv"):
            cols[f"sigma_{a} [pixel]"] = du[:, i]
    if "strain" in ds:
        E = ds.strain.isel(time=k).values
        Eu = ds.strain_u.isel(time=k).values
        for i, a in enumerate(("exx", "eyy", "exy")):
            cols[a] = E[:, i]
        for i, a in enumerate(("exx", "eyy", "exy")):
            cols[f"sigma_{a}"] = Eu[:, i]
    cols["zncc"] = ds.zncc.isel(time=k).values
    names = str(ds.flag.attrs.get("flag_meanings", "")).split()
    fl = ds.flag.isel(time=k).values.astype(int)
    cols["flag"] = np.array([names[f] if 0 <= f < len(names) else str(f) for f in fl])
    return cols


def write_field_csv(ds: xr.Dataset, path: str | Path, *, time: int | None = None) -> list[Path]:
    """Write the field as CSV (see module docstring); returns the files written.

    With several images and ``time=None``, one file per image: ``<stem>_<image>.csv``
    (image 0 = reference). ``time`` selects one image (index).
    """
    from jointwear.io import atomic_path

    path = Path(path)
    n_t = ds.sizes["time"]
    ks = [time % n_t] if time is not None else list(range(n_t))
    out = []
    for k in ks:
        p = path if len(ks) == 1 else path.with_name(f"{path.stem}_{k:04d}{path.suffix or '.csv'}")
        cols = _columns(ds, k)
        with atomic_path(p) as tmp, open(tmp, "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(list(cols))
            for row in zip(*cols.values(), strict=True):
                w.writerow(
                    [
                        v
                        if isinstance(v, str)
                        else ("" if not np.isfinite(v) else f"{float(v):.9g}")
                        for v in row
                    ]
                )
        out.append(p)
    return out


def plot_field(ds: xr.Dataset, *, time: int = -1, title: str | None = None):
    """Contour maps of the field at image ``time`` (matplotlib ``Figure``)."""
    from matplotlib.figure import Figure
    from matplotlib.tri import Triangulation

    stereo = "position" in ds
    k = time % ds.sizes["time"]
    if stereo:
        xs, ys = ds.position.values[:, 0] * 1e3, ds.position.values[:, 1] * 1e3
        scale, unit, names = 1e3, "mm", ("U", "V", "W")
    else:
        xs, ys = ds.x.values.astype(float), ds.y.values.astype(float)
        scale, unit, names = 1.0, "pixel", ("u", "v")
    panels = [
        (f"{n} [{unit}]", ds.displacement.isel(time=k).values[:, i] * scale)
        for i, n in enumerate(names)
    ]
    if "strain" in ds:
        E = ds.strain.isel(time=k).values
        panels += [("exx [1e-6]", E[:, 0] * 1e6), ("eyy [1e-6]", E[:, 1] * 1e6)]
    fig = Figure(figsize=(4.2 * min(len(panels), 3), 3.6 * ((len(panels) + 2) // 3)))
    ok = np.isfinite(xs) & np.isfinite(ys)
    for i, (label, val) in enumerate(panels):
        ax = fig.add_subplot((len(panels) + 2) // 3, min(len(panels), 3), i + 1)
        good = ok & np.isfinite(val)
        if good.sum() >= 3 and np.ptp(xs[good]) > 0 and np.ptp(ys[good]) > 0:
            tri = Triangulation(xs[good], ys[good])
            vmin, vmax = np.percentile(val[good], [1, 99])
            if vmin == vmax:
                vmin, vmax = vmin - 1e-12, vmax + 1e-12
            levels = np.linspace(vmin, vmax, 16)
            cs = ax.tricontourf(tri, np.clip(val[good], vmin, vmax), levels=levels, cmap="viridis")
            fig.colorbar(cs, ax=ax, shrink=0.85)
        else:
            ax.text(0.5, 0.5, "no valid points", ha="center", transform=ax.transAxes)
        ax.set_title(label, fontsize=9)
        ax.set_aspect("equal")
        if not stereo:
            ax.invert_yaxis()
        ax.set_xlabel(f"x [{unit}]")
        ax.set_ylabel(f"y [{unit}]")
    n_ok = int((ds.flag.isel(time=k).values == 0).sum())
    head = title or ds.attrs.get("title", "DIC field")
    fig.suptitle(f"{head}: image {k}, {n_ok}/{ds.sizes['point']} points ok", fontsize=10)
    fig.tight_layout()
    return fig


def save_field_plot(ds: xr.Dataset, path: str | Path, **kwargs) -> Path:
    """Write :func:`plot_field` to ``path`` (png/pdf/svg), atomically."""
    from jointwear.io import save_figure

    return save_figure(plot_field(ds, **kwargs), path, dpi=90)
