"""Synthetic wear maps and motion records with known truth (shared by the compare/report tests)."""

from __future__ import annotations

import numpy as np
import xarray as xr

from jointwear import conventions
from jointwear.conventions import CANONICAL, AngleConvention

PERIOD = 0.5  # s, 120 rev/min
OMEGA = 2 * np.pi / PERIOD
RADIUS = 8.0e-3


def wear_field(z, theta_canon_deg, *, scale=1.0, rotate_deg=0.0):
    """Two worn regions (near 90 deg at z=+5 mm and 300 deg at z=-5 mm), canonical angles [m]."""
    z = np.asarray(z, dtype=float)[:, None]
    th = np.asarray(theta_canon_deg, dtype=float)[None, :] - rotate_deg

    def bump(amp, th0, z0, sth, sz):
        d = (th - th0 + 180.0) % 360.0 - 180.0
        return amp * np.exp(-0.5 * (d / sth) ** 2 - 0.5 * ((z - z0) / sz) ** 2)

    h = bump(30e-6, 90.0, 5e-3, 25.0, 3e-3) + bump(18e-6, 300.0, -5e-3, 30.0, 3e-3) + 2e-6
    return scale * h


def sim_wear(*, n_layers=20, n_points=200, width=15e-3, cycles=(0.0, 2e5, 4e5), rotate_deg=0.0):
    """Simulator-style map: (cycles, z, theta), canonical convention, linear growth in cycles."""
    z = np.linspace(-width / 2, width / 2, n_layers)
    theta = np.arange(n_points) * 360.0 / n_points
    base = wear_field(z, theta, rotate_deg=rotate_deg)
    depth = np.stack([base * c / cycles[-1] for c in cycles])
    ds = wear_history(depth, cycles, z, theta)
    ds.attrs.update({"title": "synthetic simulated wear", "bearing_radius_m": RADIUS})
    return ds


def wear_history(depth, cycles, z, theta):
    """A simulator-style wear map ``depth`` [m] over (cycles, z [m], theta [degree, canonical])."""
    ds = xr.Dataset(
        coords={
            "cycles": ("cycles", np.asarray(cycles, float), {"units": "1", "long_name": "cycles"}),
            "z": conventions.z_coord(z),
            "theta": conventions.theta_coord(theta),
        }
    )
    ds["wear_depth"] = (("cycles", "z", "theta"), depth, conventions.variable_attrs("wear_depth"))
    return ds


def meas_wear(
    *,
    n_layers=13,
    n_points=3600,
    spacing=1e-3,
    convention=AngleConvention("+y", "counterclockwise"),
    rotate_deg=0.0,
    scale=1.0,
    cycles=4e5,
    u=None,
    state_convention=True,
    units="m",
):
    """Instrument-style map: 13 layers 1 mm apart, dense points, in another angle convention.

    The field is the same physical field as :func:`sim_wear` (at 4e5 cycles) unless rotated or
    scaled; each sample is evaluated at its canonical angle, then labelled in ``convention``.
    """
    z = (np.arange(n_layers) - (n_layers - 1) / 2) * spacing
    theta_own = np.arange(n_points) * 360.0 / n_points
    theta_canon = CANONICAL.from_physical(convention.to_physical(theta_own))
    depth = wear_field(z, theta_canon, scale=scale * cycles / 4e5, rotate_deg=rotate_deg)
    factor = {"m": 1.0, "um": 1e6}[units]
    ds = xr.Dataset(
        coords={
            "z": conventions.z_coord(z),
            "theta": conventions.theta_coord(theta_own, convention),
        }
    )
    ds["wear_depth"] = (
        ("z", "theta"),
        depth * factor,
        {**conventions.variable_attrs("wear_depth"), "units": units},
    )
    if u is not None:
        ds["wear_depth_u"] = (
            ("z", "theta"),
            np.full_like(depth, u * factor),
            {"units": units, "long_name": "standard uncertainty of wear_depth"},
        )
        ds["wear_depth"].attrs["ancillary_variables"] = "wear_depth_u"
    if not state_convention:
        for key in ("angle_zero", "angle_direction", "angle_note"):
            ds["theta"].attrs.pop(key, None)
    ds.attrs.update({"title": "synthetic measured wear", "cycles": cycles})
    return ds


def velocity(phi):
    """Follower velocity as a function of the crank angle [m/s], components x, y, z."""
    return np.stack(
        [
            0.3 * np.sin(phi) + 0.05 * np.sin(2 * phi + 0.4),
            0.2 * np.cos(phi) - 0.04 * np.cos(3 * phi),
            0.01 * np.sin(phi + 1.0),
        ],
        axis=-1,
    )


def follower_motion(t, v):
    """A motion record: follower velocity ``v`` [m/s] over time ``t`` [s] and axis x, y, z."""
    ds = xr.Dataset(
        coords={
            "time": ("time", t, {"units": "s", "long_name": "time"}),
            "axis": ("axis", np.array(["x", "y", "z"])),
        }
    )
    ds["follower_velocity"] = (("time", "axis"), v, conventions.variable_attrs("follower_velocity"))
    return ds


def sim_motion(*, theta0=0.3, duration=1.2, seed=1):
    """Variable-step simulated motion with crank angle."""
    rng = np.random.default_rng(seed)
    steps = rng.uniform(2e-4, 1.2e-3, size=int(duration / 4e-4) + 10)
    t = np.concatenate([[0.0], np.cumsum(steps)])
    t = t[t <= duration]
    phi = theta0 + OMEGA * t
    ds = follower_motion(t, velocity(phi))
    ds["crank_angle"] = ("time", phi, conventions.variable_attrs("crank_angle"))
    ds.attrs["title"] = "synthetic simulated motion"
    return ds


def meas_motion(*, phi0=1.7, duration=2.1, fps=50.0, with_crank=True, scale=1.0, u=None):
    """50 fps measured motion, crank angle phi0 at t = 0."""
    t = np.arange(int(duration * fps)) / fps
    phi = phi0 + OMEGA * t
    ds = follower_motion(t, scale * velocity(phi))
    if u is not None:
        ds["follower_velocity_u"] = (
            ("time", "axis"),
            np.full((t.size, 3), u),
            {"units": "m s-1", "long_name": "standard uncertainty of follower_velocity"},
        )
    if with_crank:
        ds["crank_angle"] = (
            "time",
            np.mod(phi, 2 * np.pi),
            conventions.variable_attrs("crank_angle"),
        )
    ds.attrs["title"] = "synthetic measured motion"
    return ds
