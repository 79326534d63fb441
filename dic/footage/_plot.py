"""Plot of tracked body motion: follower centroid velocity and journal out-of-plane displacement."""

from __future__ import annotations

from pathlib import Path

import xarray as xr

from jointwear.errors import BadInputError

__all__ = ["plot_body_motion"]


def plot_body_motion(
    ds: xr.Dataset,
    *,
    reference: xr.Dataset | None = None,
    path: str | Path | None = None,
    title: str | None = None,
):
    """Follower centre-of-mass velocity (x, y, z) and journal out-of-plane displacement.

    Parameters
    ----------
    ds : Dataset
        Output of :func:`jointwear.dic.track_footage` (``follower_velocity`` [m/s] and/or
        ``journal_displacement`` [m]).
    reference : Dataset, optional
        Data to overlay as dashed lines (ground truth of the virtual rig, or a simulation with
        ``follower_velocity`` and ``journal_displacement``/``journal_offset``).
    path : path, optional
        Write the figure (PNG, SVG or PDF by extension, atomically).
    title : str, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib

    if path is not None:
        matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    has_v = "follower_velocity" in ds
    has_j = "journal_displacement" in ds
    if not (has_v or has_j):
        raise BadInputError(
            "nothing to plot: the dataset has neither 'follower_velocity' nor "
            "'journal_displacement' (track a body with role 'follower' or 'journal')"
        )
    n = int(has_v) + int(has_j)
    fig, axes = plt.subplots(n, 1, figsize=(7.5, 2.8 * n + 0.4), sharex=True, squeeze=False)
    axes = axes[:, 0]
    k = 0
    colors = {"x": "tab:blue", "y": "tab:orange", "z": "tab:green"}
    if has_v:
        ax = axes[k]
        k += 1
        v = ds["follower_velocity"]
        for a in v["axis"].values:
            ax.plot(ds["time"], v.sel(axis=a), color=colors.get(str(a)), label=f"v{a} (DIC)")
            if reference is not None and "follower_velocity" in reference:
                r = reference["follower_velocity"].sel(axis=a)
                ax.plot(
                    reference["time"],
                    r,
                    "--",
                    color=colors.get(str(a)),
                    lw=1,
                    label=f"v{a} (reference)",
                )
        ax.set_ylabel(f"follower velocity [{v.attrs.get('units', '')}]")
        ax.legend(ncol=3, fontsize=8, loc="upper right")
        ax.grid(alpha=0.3)
    if has_j:
        ax = axes[k]
        dz = ds["journal_displacement"].sel(axis="z") * 1e3
        ax.plot(ds["time"], dz, color="tab:green", label="journal z (DIC)")
        if "journal_displacement_u" in ds:
            u = ds["journal_displacement_u"].sel(axis="z") * 1e3
            ax.fill_between(
                ds["time"], dz - 2 * u, dz + 2 * u, color="tab:green", alpha=0.25, lw=0, label="±2u"
            )
        if reference is not None and "journal_displacement" in reference:
            r = reference["journal_displacement"].sel(axis="z") * 1e3
            ax.plot(reference["time"], r, "k--", lw=1, label="reference")
        ax.set_ylabel("journal out-of-plane\ndisplacement [mm]")
        ax.legend(fontsize=8, loc="upper right")
        ax.grid(alpha=0.3)
    axes[-1].set_xlabel("time [s]")
    fig.suptitle(
        title or "Rig footage: follower velocity and journal out-of-plane motion", fontsize=10
    )
    fig.tight_layout()
    if path is not None:
        from jointwear.io import save_figure

        save_figure(fig, path, dpi=110)
    return fig
