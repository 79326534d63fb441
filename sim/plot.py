"""Figure of a simulated cycle record: journal orbit, contact force, follower velocity."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from jointwear.errors import BadInputError

__all__ = ["plot_cycle"]


def plot_cycle(ds: xr.Dataset, path: str | Path | None = None, *, clearance: float | None = None):
    """Plot a record of :func:`jointwear.sim.run_cycles` (or a ``jointwear sim cycle`` file).

    Three panels: the journal centre's orbit in the bearing (x-y of the bearing frame, um, with
    the clearance circle), the contact force magnitude against the crank angle (coloured by
    contact mode), and the follower's centre-of-mass velocity components (the slider's velocity
    for a slider-crank record).

    Parameters
    ----------
    ds : Dataset
        Record with ``journal_offset``, ``contact_force``, ``contact_mode``, ``crank_angle``,
        ``follower_velocity`` (or ``slider_velocity``) over ``time``.
    path : path, optional
        Write the figure there (PNG/PDF/SVG by suffix, atomically).
    clearance : float, optional
        Radial clearance [m] for the circle; read from the record's parameters if omitted.

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib

    if path is not None:
        matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    body, body_name = (
        ("slider_velocity", "slider")
        if "slider_velocity" in ds and "follower_velocity" not in ds
        else ("follower_velocity", "follower centre of mass")
    )
    needed = ["journal_offset", "contact_force", "contact_mode", "crank_angle", body]
    missing = [n for n in needed if n not in ds]
    if missing:
        raise BadInputError(
            f"plot_cycle: the dataset lacks {', '.join(missing)}; pass a record of "
            "jointwear.sim.run_cycles or a 'jointwear sim cycle' file"
        )
    if clearance is None:
        clearance = _clearance_from(ds)
    off = ds.journal_offset.values * 1e6
    fig, axes = plt.subplots(1, 3, figsize=(13, 4.0), constrained_layout=True)
    ax = axes[0]
    if clearance:
        a = np.linspace(0, 2 * np.pi, 361)
        ax.plot(clearance * 1e6 * np.cos(a), clearance * 1e6 * np.sin(a), "k--", lw=0.8)
    ax.plot(off[:, 0], off[:, 1], lw=0.7)
    ax.set_aspect("equal")
    ax.set_xlabel("journal centre x, bearing frame [um]")
    ax.set_ylabel("journal centre y [um]")
    ax.set_title("journal orbit (dashed: radial clearance)")
    ax = axes[1]
    crank = np.degrees(np.unwrap(ds.crank_angle.values))
    mode = ds.contact_mode.values
    meanings = ds.contact_mode.attrs.get("flag_meanings", "").split()
    values = list(np.atleast_1d(ds.contact_mode.attrs.get("flag_values", [])))
    ax.plot(crank, ds.contact_force.values, color="0.6", lw=0.6)
    for v, name in zip(values, meanings, strict=False):
        sel = mode == v
        if sel.any() and v != 0:
            ax.plot(crank[sel], ds.contact_force.values[sel], ".", ms=1.5, label=name)
    ax.set_xlabel("crank angle [deg]")
    ax.set_ylabel("contact force [N]")
    ax.set_yscale("symlog", linthresh=10.0)
    ax.set_title("contact force in the clearance joint")
    ax.legend(markerscale=6, fontsize=8)
    ax = axes[2]
    fv = ds[body].values
    for i, comp in enumerate(("x", "y", "z")):
        ax.plot(crank, fv[:, i], lw=0.8, label=f"v{comp}")
    ax.set_xlabel("crank angle [deg]")
    ax.set_ylabel(f"{body_name} velocity [m/s]")
    ax.set_title(body_name)
    ax.legend(fontsize=8)
    if path is not None:
        from jointwear.io import save_figure

        save_figure(fig, path, dpi=110)
    return fig


def _clearance_from(ds: xr.Dataset) -> float | None:
    import json

    text: Any = ds.attrs.get("parameters_json")
    try:
        joint = json.loads(text)["joint"]
        return float(joint["bearing_radius"]) - float(joint["journal_radius"])
    except (TypeError, ValueError, KeyError):
        return None
