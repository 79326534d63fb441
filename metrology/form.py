"""Roundness and cylindricity: reference circles/cylinders and form parameters (ISO 12181/12180).

All four references (least squares LS, minimum zone MZ, maximum inscribed MI, minimum
circumscribed MC) are evaluated on the *limaçon* model used by roundness instruments: a radius
profile r(theta) measured about the spindle axis is compared with a reference whose centre is
offset by (x0, y0) (and, for a cylinder, tilted by (tx, ty) per metre of z),

    e_i = r_i - (x0 + tx z_i) cos(theta_i) - (y0 + ty z_i) sin(theta_i).

The model is linear in the centre parameters, so the LS reference is an exact linear least
squares fit and MZ/MI/MC are linear programmes. They are solved with HiGHS
(:func:`scipy.optimize.linprog`) by *constraint generation*: the LP is solved on a small set of
candidate points, every point is checked against the solution, the violators are added and the
LP is solved again. The solution of the final small LP is feasible for all points, so it is the
true optimum of the full LP (to the solver's tolerance, far below 1 nm), while each LP has only a
few hundred rows. The limaçon neglects a second-harmonic term of amplitude e^2/(4R) (e the
eccentricity, R the radius); :func:`limacon_error` gives it and :func:`assess` warns when it
exceeds a tolerance. Exact (geometric, non-linearised) least-squares fits are in
:mod:`jointwear.metrology.fit`.

Angles are taken in the data's own convention: form values do not depend on where theta = 0
is or which way it turns; centres are reported as (eccentricity, direction in that convention).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import xarray as xr
from scipy.optimize import linprog

from jointwear.errors import BadInputError
from jointwear.metrology.choices import REFERENCES

__all__ = [
    "REFERENCES",
    "ZoneResult",
    "normalise_reference",
    "circle_zone",
    "circle_zones",
    "cylinder_zone",
    "roundness",
    "cylindricity",
    "limacon_error",
]

_ALIASES = {
    **{k: k for k in REFERENCES},
    **{v[0]: k for k, v in REFERENCES.items()},
    **{v[1]: k for k, v in REFERENCES.items()},
    "LSQ": "LS",
    "LEASTSQUARES": "LS",
    "MINIMUMZONE": "MZ",
    "MRS": "MZ",
    "MIC": "MI",
    "MCC": "MC",
}

# internal unit for the LPs: micrometres (keeps the solver's absolute tolerances << 1 nm)
_SCALE = 1e6
# acceptance tolerance of constraint generation [m]
_TOL = 1e-13


def normalise_reference(reference: str) -> str:
    """``"MZ"``, ``"mzci"``, ``"MZCY"`` ... -> ``"MZ"``; a clear error for anything else."""
    key = str(reference).strip().upper().replace("_", "").replace("-", "").replace(" ", "")
    if key not in _ALIASES:
        raise BadInputError(
            f"reference {reference!r} is not known; use one of LS (least squares), MZ (minimum "
            "zone), MI (maximum inscribed), MC (minimum circumscribed)"
        )
    return _ALIASES[key]


@dataclass(frozen=True)
class ZoneResult:
    """Form deviation of a profile (circle) or surface (cylinder) from one reference.

    Attributes
    ----------
    reference : str
        ``"LS"``, ``"MZ"``, ``"MI"`` or ``"MC"``.
    total : float
        Peak-to-valley deviation from the reference (RONt / CYLt) [m].
    peak, valley : float
        Largest deviation outward / inward of the reference (RONp / RONv) [m], both >= 0.
    rms : float
        Root-mean-square deviation from the reference (RONq / CYLq) [m].
    centre : tuple of float
        Reference centre (x0, y0) relative to the measurement axis at z = z_ref [m], in the data's
        angle frame (x along theta = 0, y along theta = 90 degree).
    tilt : tuple of float
        Axis tilt (dx/dz, dy/dz) [1]; (0, 0) for circles.
    z_ref : float
        Axial position the centre refers to [m].
    radius : float
        Reference radius (mean of the two zone circles for MZ) in the units of the input [m].
    residual : ndarray
        Deviation of each input point from the reference [m], NaN where the input was NaN.
    active : int
        Number of candidate points in the final LP (0 for LS).
    """

    reference: str
    total: float
    peak: float
    valley: float
    rms: float
    centre: tuple[float, float]
    tilt: tuple[float, float]
    z_ref: float
    radius: float
    residual: np.ndarray = field(repr=False)
    active: int = 0

    @property
    def eccentricity(self) -> float:
        """Distance of the reference centre from the measurement axis at z_ref [m]."""
        return float(np.hypot(*self.centre))

    @property
    def eccentricity_angle_deg(self) -> float:
        """Direction of the centre offset, in the data's theta convention [degree]."""
        return float(np.degrees(np.arctan2(self.centre[1], self.centre[0])) % 360.0)


def limacon_error(eccentricity: float, radius: float) -> float:
    """Amplitude of the second harmonic the limaçon model neglects, e^2 / (4 R) [m].

    The exact radius seen from an axis offset by e is e cos(phi) + sqrt(R^2 - e^2 sin^2 phi)
    = R + e cos(phi) - e^2 / (4 R) (1 - cos 2 phi) + O(e^4/R^3), so the neglected form term has
    peak-to-valley e^2 / (2 R) and amplitude e^2 / (4 R).
    """
    if radius <= 0 or not np.isfinite(radius):
        return float("nan")
    return float(eccentricity**2 / (4.0 * radius))


# --------------------------------------------------------------------------------------------
# core solvers on flat arrays
# --------------------------------------------------------------------------------------------


class _Basis:
    """Design columns (cos, sin[, z cos, z sin]) stored row-wise; fast G @ p and G[idx]."""

    def __init__(self, theta_rad: np.ndarray, z: np.ndarray | None):
        c, s = np.cos(theta_rad), np.sin(theta_rad)
        self.cols = np.stack([c, s] if z is None else [c, s, z * c, z * s])
        self.shape = (c.size, self.cols.shape[0])

    def dot(self, p: np.ndarray) -> np.ndarray:
        out = self.cols[0] * p[0]
        for k in range(1, self.cols.shape[0]):
            out += self.cols[k] * p[k]
        return out

    def rows(self, idx: np.ndarray) -> np.ndarray:
        return self.cols[:, idx].T


def _design(theta_rad: np.ndarray, z: np.ndarray | None) -> _Basis:
    return _Basis(theta_rad, z)


def _ls(G: _Basis, r: np.ndarray) -> tuple[np.ndarray, float]:
    A = np.vstack([G.cols, np.ones((1, r.size))])
    # normal equations: the basis (cos, sin, z cos, z sin, 1) with centred z is well conditioned
    # einsum, not BLAS: threaded BLAS on tall-skinny products is slow on a busy machine
    sol = np.linalg.solve(np.einsum("jn,kn->jk", A, A), np.einsum("jn,n->j", A, r))
    return sol[:-1], float(sol[-1])


class _Sectors:
    """Points grouped by (layer, angular sector), for picking one extreme per sector."""

    def __init__(self, theta_rad: np.ndarray, groups: np.ndarray | None, n_sectors: int):
        sec = np.floor(np.mod(theta_rad, 2 * np.pi) / (2 * np.pi) * n_sectors).astype(np.int64)
        sec = np.clip(sec, 0, n_sectors - 1)
        key = sec if groups is None else groups.astype(np.int64) * n_sectors + sec
        if key.size and np.all(key[1:] >= key[:-1]):
            self.order = np.arange(key.size)  # grid data, layer-major with ascending angles
        else:
            self.order = np.argsort(key, kind="stable")
        ks = key[self.order]
        self.starts = np.flatnonzero(np.concatenate([[True], ks[1:] != ks[:-1]]))
        self.sector_of_sorted = np.repeat(
            np.arange(self.starts.size), np.diff(np.append(self.starts, ks.size))
        )

    def argmax(self, values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Index of the largest value in each sector, and that value."""
        vs = values[self.order]
        mx = np.maximum.reduceat(vs, self.starts)
        hit = np.flatnonzero(vs == mx[self.sector_of_sorted])
        _, first = np.unique(self.sector_of_sorted[hit], return_index=True)
        return self.order[hit[first]], mx


def _initial_candidates(sectors: _Sectors, e0: np.ndarray, kind: str) -> np.ndarray:
    """The points the zone LP starts from: per sector the largest residual (MZ, MC) and the
    smallest (MZ, MI) of the LS solution."""
    parts = []
    if kind in ("MZ", "MC"):
        parts.append(sectors.argmax(e0)[0])
    if kind in ("MZ", "MI"):
        parts.append(sectors.argmax(-e0)[0])
    return np.unique(np.concatenate(parts))


def _grown_candidates(res, cand: np.ndarray, n: int, what: str, why: str) -> np.ndarray | None:
    """After the zone LP on the candidate points: None when it is solved; more candidates when
    the subset does not surround the axis yet (unbounded) and points are left; else refused."""
    if res.status == 3 and cand.size < n:
        more = np.linspace(0, n - 1, min(n, 4 * cand.size), dtype=np.int64)
        return np.union1d(cand, more)
    if res.status != 0:
        raise BadInputError(f"{what} could not be computed ({res.message.strip()}); {why}")
    return None


def _zone_lp(
    G: np.ndarray,
    r: np.ndarray,
    kind: str,
    sectors: _Sectors,
    what: str = "profile",
) -> tuple[np.ndarray, float, float, int]:
    """Solve the MZ / MI / MC LP by constraint generation.

    Candidates start as the extremes of the least-squares residual in each angular sector of
    each layer; each round adds, per sector, the point that violates the current solution most.
    Returns (centre parameters p, min residual, max residual, number of candidates);
    inputs in micrometres.
    """
    m = G.shape[1]
    p0, _ = _ls(G, r)
    e0 = r - G.dot(p0)
    cand = _initial_candidates(sectors, e0, kind)
    tol = _TOL * _SCALE
    for _ in range(200):
        Gs, rs = G.rows(cand), r[cand]
        ns = len(cand)
        if kind == "MZ":
            # vars [p (m), a, t]; min t; G p + a <= r ; -G p - a - t <= -r
            c = np.zeros(m + 2)
            c[-1] = 1.0
            A = np.block(
                [
                    [Gs, np.ones((ns, 1)), np.zeros((ns, 1))],
                    [-Gs, -np.ones((ns, 1)), -np.ones((ns, 1))],
                ]
            )
            b = np.concatenate([rs, -rs])
            bounds = [(None, None)] * (m + 1) + [(0, None)]
        elif kind == "MI":
            # vars [p, a]; max a; G p + a <= r
            c = np.zeros(m + 1)
            c[-1] = -1.0
            A = np.column_stack([Gs, np.ones(ns)])
            b = rs
            bounds = [(None, None)] * (m + 1)
        else:  # MC: vars [p, bb]; min bb; -G p - bb <= -r
            c = np.zeros(m + 1)
            c[-1] = 1.0
            A = np.column_stack([-Gs, -np.ones(ns)])
            b = -rs
            bounds = [(None, None)] * (m + 1)
        res = linprog(c, A_ub=A, b_ub=b, bounds=bounds, method="highs")
        grown = _grown_candidates(
            res,
            cand,
            len(r),
            f"{what}: the {kind} reference",
            "the points probably do not surround the axis (a closed profile needs angles "
            "spread over more than half a turn, a cylinder at least two layers)",
        )
        if grown is not None:
            cand = grown
            continue
        x = res.x
        p = x[:m]
        e = r - G.dot(p)
        if kind == "MZ":
            viol = np.maximum(x[m] - e, e - (x[m] + x[m + 1]))
        elif kind == "MI":
            viol = x[m] - e
        else:
            viol = e - x[m]
        idx, worst = sectors.argmax(viol)
        new = idx[worst > tol]
        if new.size == 0:
            return p, float(np.min(e)), float(np.max(e)), len(cand)
        cand = np.union1d(cand, new)
    raise BadInputError(f"{what}: {kind} constraint generation did not converge in 200 rounds")


def _zone(
    theta_rad: np.ndarray,
    r: np.ndarray,
    z: np.ndarray | None,
    reference: str,
    groups: np.ndarray | None,
    n_groups: int,
    what: str,
) -> ZoneResult:
    kind = normalise_reference(reference)
    theta_rad = np.asarray(theta_rad, dtype=float).ravel()
    r = np.asarray(r, dtype=float).ravel()
    ok = np.isfinite(r) & np.isfinite(theta_rad)
    if z is not None:
        z = np.asarray(z, dtype=float).ravel()
        ok &= np.isfinite(z)
    n_ok = int(ok.sum())
    need = 3 if z is None else 5
    if n_ok < need + 1:
        raise BadInputError(
            f"{what}: only {n_ok} finite points; a form assessment needs at least {need + 1}"
        )
    th, rr = theta_rad[ok], r[ok]
    z_ref = 0.0
    zz = None
    if z is not None:
        z_ref = float(0.5 * (np.min(z[ok]) + np.max(z[ok])))
        zz = z[ok] - z_ref
        if np.ptp(zz) == 0:
            raise BadInputError(
                f"{what}: all points lie in one layer; cylindricity needs at least two layers"
            )
    grp = groups[ok] if groups is not None else None
    offset = float(np.mean(rr))
    G = _design(th, zz)
    rs = (rr - offset) * _SCALE
    active = 0
    if kind == "LS":
        p, a = _ls(G, rs)
        e = rs - G.dot(p)
        ref = a
    else:
        n_sec = 64 if grp is None else 32
        sectors = _Sectors(th, grp, n_sec)
        p, lo, hi, active = _zone_lp(G, rs, kind, sectors, what)
        e = rs - G.dot(p)
        ref = {"MZ": 0.5 * (lo + hi), "MI": lo, "MC": hi}[kind]
    dev = (e - ref) / _SCALE
    peak = float(max(np.max(dev), 0.0))
    valley = float(max(-np.min(dev), 0.0))
    p = p / _SCALE
    resid = np.full(r.shape, np.nan)
    resid[ok] = dev
    return ZoneResult(
        reference=kind,
        total=float(np.max(dev) - np.min(dev)),
        peak=peak,
        valley=valley,
        rms=float(np.sqrt(np.mean(dev**2))),
        centre=(float(p[0]), float(p[1])),
        tilt=(float(p[2]), float(p[3])) if z is not None else (0.0, 0.0),
        z_ref=z_ref,
        radius=float(offset + ref / _SCALE),
        residual=resid,
        active=active,
    )


def circle_zone(
    theta_deg: np.ndarray, r: np.ndarray, *, reference: str = "MZ", what: str = "profile"
) -> ZoneResult:
    """Roundness of one closed profile against a reference circle (limaçon model).

    Parameters
    ----------
    theta_deg : array_like
        Angles of the points [degree] (any convention, any order).
    r : array_like
        Radius, or radial deviation from any constant, at those angles [m]. NaN points are
        ignored.
    reference : {"LS", "MZ", "MI", "MC"}
        Reference circle (also accepts the ISO names LSCI, MZCI, MICI, MCCI).
    what : str
        Name used in error messages.

    Returns
    -------
    ZoneResult
        ``total`` is RONt, ``peak`` RONp, ``valley`` RONv and ``rms`` RONq [m].
    """
    return _zone(np.radians(theta_deg), r, None, reference, None, 1, what)


def circle_zones(
    theta_deg: np.ndarray, r: np.ndarray, *, reference: str = "MZ", what: str = "scan"
) -> list[ZoneResult]:
    """Roundness of every layer of a (layers, points) array against a reference circle.

    Same results as :func:`circle_zone` per layer, but the MZ/MI/MC problems of all layers are
    solved together as one block-separable LP per constraint-generation round (the objective is
    the sum of the per-layer objectives, so each block reaches its own optimum), which needs far
    fewer solver calls.

    Parameters
    ----------
    theta_deg : array_like (n,) or (layers, n)
        Angles [degree].
    r : array_like (layers, n)
        Radius or radial deviation [m]; NaN points are ignored.
    reference : {"LS", "MZ", "MI", "MC"}
        Reference circle.

    Returns
    -------
    list of ZoneResult
        One per layer.
    """
    from scipy.sparse import coo_matrix

    kind = normalise_reference(reference)
    r = np.atleast_2d(np.asarray(r, dtype=float))
    nl, n = r.shape
    th = np.broadcast_to(np.radians(np.asarray(theta_deg, dtype=float)), r.shape)
    if kind == "LS" or nl == 1:
        return [
            circle_zone(np.degrees(th[i]), r[i], reference=kind, what=f"{what} layer {i + 1}")
            for i in range(nl)
        ]
    ok = np.isfinite(r) & np.isfinite(th)
    counts = ok.sum(axis=1)
    if np.any(counts < 4):
        i = int(np.argmin(counts))
        raise BadInputError(
            f"{what} layer {i + 1}: only {int(counts[i])} finite points; a form assessment "
            "needs at least 4"
        )
    g = np.broadcast_to(np.arange(nl)[:, None], r.shape)[ok]
    t = th[ok]
    offsets = np.array([np.mean(r[i][ok[i]]) for i in range(nl)])
    rs = (r[ok] - offsets[g]) * _SCALE
    c, sn = np.cos(t), np.sin(t)
    # LS start per layer
    p = np.zeros((nl, 2))
    for i in range(nl):
        sel = g == i
        A = np.column_stack([c[sel], sn[sel], np.ones(sel.sum())])
        sol = np.linalg.solve(np.einsum("nj,nk->jk", A, A), np.einsum("nj,n->j", A, rs[sel]))
        p[i] = sol[:2]
    e0 = rs - c * p[g, 0] - sn * p[g, 1]
    sectors = _Sectors(t, g, 64)
    cand = _initial_candidates(sectors, e0, kind)
    nv = 4 if kind == "MZ" else 3  # per layer: x, y, a [, t]
    tol = _TOL * _SCALE
    for _ in range(200):
        gi, ci, si, ri = g[cand], c[cand], sn[cand], rs[cand]
        m = cand.size
        base = gi * nv
        if kind == "MZ":
            rows = np.concatenate([np.repeat(np.arange(m), 3), np.repeat(np.arange(m, 2 * m), 4)])
            cols = np.concatenate(
                [
                    np.stack([base, base + 1, base + 2], axis=1).ravel(),
                    np.stack([base, base + 1, base + 2, base + 3], axis=1).ravel(),
                ]
            )
            vals = np.concatenate(
                [
                    np.stack([ci, si, np.ones(m)], axis=1).ravel(),
                    np.stack([-ci, -si, -np.ones(m), -np.ones(m)], axis=1).ravel(),
                ]
            )
            b = np.concatenate([ri, -ri])
            cost = np.tile([0.0, 0.0, 0.0, 1.0], nl)
            bounds = [(None, None), (None, None), (None, None), (0, None)] * nl
            nrows = 2 * m
        else:
            sign = 1.0 if kind == "MI" else -1.0
            rows = np.repeat(np.arange(m), 3)
            cols = np.stack([base, base + 1, base + 2], axis=1).ravel()
            vals = sign * np.stack([ci, si, np.ones(m)], axis=1).ravel()
            b = sign * ri
            cost = np.tile([0.0, 0.0, -1.0 if kind == "MI" else 1.0], nl)
            bounds = [(None, None)] * (nv * nl)
            nrows = m
        A = coo_matrix((vals, (rows, cols)), shape=(nrows, nv * nl)).tocsr()
        res = linprog(cost, A_ub=A, b_ub=b, bounds=bounds, method="highs")
        grown = _grown_candidates(
            res,
            cand,
            rs.size,
            f"{what}: the {kind} reference",
            "the points of some layer probably do not surround the axis",
        )
        if grown is not None:
            cand = grown
            continue
        x = res.x.reshape(nl, nv)
        e = rs - c * x[g, 0] - sn * x[g, 1]
        if kind == "MZ":
            viol = np.maximum(x[g, 2] - e, e - (x[g, 2] + x[g, 3]))
        elif kind == "MI":
            viol = x[g, 2] - e
        else:
            viol = e - x[g, 2]
        idx, worst = sectors.argmax(viol)
        new = idx[worst > tol]
        if new.size == 0:
            break
        cand = np.union1d(cand, new)
    else:
        raise BadInputError(f"{what}: {kind} constraint generation did not converge")
    out = []
    for i in range(nl):
        sel = g == i
        ei = e[sel]
        lo, hi = float(np.min(ei)), float(np.max(ei))
        ref = {"MZ": 0.5 * (lo + hi), "MI": lo, "MC": hi}[kind]
        dev = (ei - ref) / _SCALE
        resid = np.full(n, np.nan)
        resid[ok[i]] = dev
        out.append(
            ZoneResult(
                reference=kind,
                total=float(np.max(dev) - np.min(dev)),
                peak=float(max(np.max(dev), 0.0)),
                valley=float(max(-np.min(dev), 0.0)),
                rms=float(np.sqrt(np.mean(dev**2))),
                centre=(float(x[i, 0] / _SCALE), float(x[i, 1] / _SCALE)),
                tilt=(0.0, 0.0),
                z_ref=0.0,
                radius=float(offsets[i] + ref / _SCALE),
                residual=resid,
                active=int(np.sum(g[cand] == i)),
            )
        )
    return out


def cylinder_zone(
    z: np.ndarray,
    theta_deg: np.ndarray,
    r: np.ndarray,
    *,
    reference: str = "MZ",
    what: str = "surface",
) -> ZoneResult:
    """Cylindricity of points (z, theta, r) against a reference cylinder (limaçon model).

    Parameters
    ----------
    z : array_like
        Axial position of each point [m].
    theta_deg : array_like
        Angle of each point [degree].
    r : array_like
        Radius or radial deviation [m]; NaN points are ignored.
    reference : {"LS", "MZ", "MI", "MC"}
        Reference cylinder (also LSCY, MZCY, MICY, MCCY).

    Returns
    -------
    ZoneResult
        ``total`` is CYLt, ``peak`` CYLp, ``valley`` CYLv, ``rms`` CYLq [m]; ``centre`` is the
        axis position at ``z_ref`` (mid of the measured z range) and ``tilt`` its slope.
    """
    z = np.asarray(z, dtype=float).ravel()
    if z.size and np.all(z[1:] >= z[:-1]):  # sorted (layer-major grid): cheap layer ids
        inv = np.concatenate([[0], np.cumsum(z[1:] != z[:-1])])
    else:
        _, inv = np.unique(z, return_inverse=True)
    return _zone(
        np.radians(np.asarray(theta_deg, dtype=float)),
        r,
        z,
        reference,
        inv,
        int(inv.max()) + 1,
        what,
    )


#: The variables a scan dataset may hold its values in, the first found is taken.
SCAN_VARIABLES = ("radius", "radial_deviation")


def scan_variable(scan: xr.Dataset, what: str) -> tuple[xr.DataArray, str]:
    """The values of a scan dataset: its ``radius`` or else its ``radial_deviation`` variable,
    and that variable's name (``what`` names the caller in the refusal)."""
    for name in SCAN_VARIABLES:
        if name in scan:
            return scan[name], name
    source = scan.encoding.get("source")  # the file it was read from, if any
    where = f"{what} '{source}'" if source else what
    raise BadInputError(
        f"{where}: the dataset has neither 'radius' nor 'radial_deviation' "
        f"(variables: {', '.join(map(str, scan.data_vars)) or 'none'}); give a scan "
        "(jointwear metrology import)"
    )


def _as_grid(data: xr.DataArray | xr.Dataset, what: str) -> xr.DataArray:
    if isinstance(data, xr.Dataset):
        data, _ = scan_variable(data, what)
    if "theta" not in data.dims:
        raise BadInputError(f"{what}: expected a 'theta' dimension, found dims {data.dims}")
    return data


def roundness(profile: xr.DataArray | xr.Dataset, *, reference: str = "MZ") -> float | xr.DataArray:
    """RONt of a profile over ``theta`` [m], or of each layer of a (z, theta) scan.

    Parameters
    ----------
    profile : DataArray or Dataset
        ``radius`` or ``radial_deviation`` [m] over ``theta`` [degree] (and optionally ``z``).
    reference : {"LS", "MZ", "MI", "MC"}
        Reference circle.

    Returns
    -------
    float or DataArray
        RONt [m]; a DataArray over ``z`` for a multi-layer scan.
    """
    da = _as_grid(profile, "roundness")
    th = np.asarray(da["theta"].values, dtype=float)
    if da.ndim == 1:
        return circle_zone(th, da.values, reference=reference).total
    if "z" not in da.dims or da.ndim != 2:
        raise BadInputError(f"roundness: expected dims (theta,) or (z, theta), got {da.dims}")
    da = da.transpose("z", "theta")
    vals = [res.total for res in circle_zones(th, da.values, reference=reference)]
    return xr.DataArray(
        np.asarray(vals),
        dims="z",
        coords={"z": da["z"]},
        attrs={"units": "m", "long_name": f"roundness RONt ({normalise_reference(reference)}CI)"},
    )


def cylindricity(radius: xr.DataArray | xr.Dataset, *, reference: str = "MZ") -> float:
    """Cylindricity CYLt of a bore or shaft scanned over (z, theta) [m].

    Parameters
    ----------
    radius : DataArray or Dataset
        ``radius`` (or ``radial_deviation``) [m] over dims ``z`` [m] and ``theta`` [degree];
        a Dataset is searched for either variable. NaN points are ignored.
    reference : {"MZ", "LS", "MI", "MC"}
        Reference cylinder: minimum zone (default), least squares, maximum inscribed, minimum
        circumscribed (limaçon model; see the module docstring).

    Returns
    -------
    float
        Peak-to-valley radial deviation from the reference cylinder [m].

    Examples
    --------
    >>> import numpy as np, xarray as xr
    >>> th = np.arange(0, 360, 1.0)
    >>> z = np.array([-1e-3, 0.0, 1e-3])
    >>> r = 8e-3 + 1e-6 * np.cos(np.radians(2 * th)) + 0 * z[:, None]
    >>> da = xr.DataArray(r, dims=("z", "theta"), coords={"z": z, "theta": th})
    >>> round(cylindricity(da) * 1e6, 6)
    2.0
    """
    da = _as_grid(radius, "cylindricity")
    if "z" not in da.dims or da.ndim != 2:
        raise BadInputError(f"cylindricity: expected dims (z, theta), got {da.dims}")
    da = da.transpose("z", "theta")
    z = np.asarray(da["z"].values, dtype=float)
    th = np.asarray(da["theta"].values, dtype=float)
    zz = np.broadcast_to(z[:, None], da.shape)
    tt = np.broadcast_to(th[None, :], da.shape)
    return cylinder_zone(zz, tt, da.values, reference=reference, what="cylindricity").total
