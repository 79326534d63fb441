"""Surface strain from a measured displacement field, by local least-squares fits.

For every point, the points of a square window of ``window x window`` grid points around it
(the point itself included) give a local linear fit of the *deformed* positions against the
*reference* positions expressed in a local tangent basis ``(t1, t2)`` of the reference surface:
``x_j = a + F (s_j, t_j)`` with ``F`` (d x 2) the surface deformation gradient (d = 2 for an
image-plane field, 3 for a stereo surface). Then ``C = F^T F`` and the Green-Lagrange strain
``E = (C - I) / 2`` in that basis; the engineering strains are ``sqrt(1 + 2 E_aa) - 1`` (normal)
and the change of the right angle ``asin(2 E_12 / sqrt((1 + 2 E_11)(1 + 2 E_22)))`` (shear).

The fit is the smoothing (VIC-3D's "strain filter", DICe's strain window): it averages the
displacement noise over the window; its length is ``(window - 1) * step`` subset spacings. For a
stereo surface the tangent basis comes from a plane fitted to the window's reference positions
(its normal pointing to +z of the output frame), ``t1`` is the frame's x axis projected onto
it, so on a flat specimen in the best-fit-plane frame ``E_11`` is ``E_xx``.

Uncertainty: the displacement uncertainties ``sigma_j`` of the window's points propagated
through the linear fit to first order in the strain, ``var(F_.b) = sum_jl w_bj w_bl rho_jl
sigma_j sigma_l`` with ``w`` the fit's slope weights and ``rho_jl`` the fraction of pixels the
two subsets share (overlapping subsets see the same image noise, so their errors correlate; the
independent-error formula under-states the slope noise about twofold at step = subset / 2).
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["window_neighbours", "tangent_frames", "surface_strain", "strain_variables"]


def window_neighbours(index: np.ndarray, window: int) -> tuple[np.ndarray, np.ndarray]:
    """CSR neighbour lists (pointer, indices) of the ``window x window`` grid square around
    each point (``index`` (N, 2) grid row/column of every point)."""
    n = len(index)
    r = window // 2
    lookup = {(int(a), int(b)): k for k, (a, b) in enumerate(index)}
    ptr = np.zeros(n + 1, np.int64)
    idx: list[int] = []
    for k, (a, b) in enumerate(index):
        for da in range(-r, r + 1):
            for db in range(-r, r + 1):
                j = lookup.get((int(a) + da, int(b) + db))
                if j is not None:
                    idx.append(j)
        ptr[k + 1] = len(idx)
    return ptr, np.asarray(idx, np.int64)


def tangent_frames(ref: np.ndarray, ptr: np.ndarray, idx: np.ndarray) -> np.ndarray:
    """Local tangent bases (N, 2, d) of the reference surface (see module docstring)."""
    n, d = ref.shape
    out = np.full((n, 2, d), np.nan)
    if d == 2:
        out[:, 0] = (1.0, 0.0)
        out[:, 1] = (0.0, 1.0)
        return out
    ex = np.array([1.0, 0.0, 0.0])
    for k in range(n):
        P = ref[idx[ptr[k] : ptr[k + 1]]]
        P = P[np.isfinite(P).all(axis=1)]
        if len(P) < 3:
            continue
        _, vec = np.linalg.eigh(np.cov((P - P.mean(0)).T))
        nrm = vec[:, 0] * (1.0 if vec[2, 0] >= 0 else -1.0)
        t1 = ex - nrm * (ex @ nrm)
        if np.linalg.norm(t1) < 1e-6:
            continue
        t1 /= np.linalg.norm(t1)
        out[k, 0] = t1
        out[k, 1] = np.cross(nrm, t1)
    return out


@njit(cache=True)
def _strain_kernel(ref, cur, sig, pix, subset, ptr, idx, frames, min_count, E, U):
    """E (T, N, 3): Green-Lagrange E11, E22, E12; U (T, N, 3) their standard uncertainty."""
    T, N, d = cur.shape
    for k in range(N):
        if not np.isfinite(frames[k, 0, 0]):
            continue
        cnt = ptr[k + 1] - ptr[k]
        sv = np.empty(cnt)  # local coordinates of the neighbours in the point's frame
        rv = np.empty(cnt)
        for q in range(ptr[k], ptr[k + 1]):
            j = idx[q]
            s = 0.0
            r = 0.0
            for c in range(d):
                s += (ref[j, c] - ref[k, c]) * frames[k, 0, c]
                r += (ref[j, c] - ref[k, c]) * frames[k, 1, c]
            sv[q - ptr[k]] = s
            rv[q - ptr[k]] = r
        used = np.zeros(cnt, np.bool_)
        w1 = np.zeros(cnt)
        w2 = np.zeros(cnt)
        for t in range(T):
            # normal equations of x_j = a + F (s_j, t_j), weights equal
            ata = np.zeros((3, 3))
            atx = np.zeros((3, d))
            m = 0
            for q in range(ptr[k], ptr[k + 1]):
                j = idx[q]
                ok = np.isfinite(sig[t, j])
                for c in range(d):
                    ok = ok and np.isfinite(cur[t, j, c]) and np.isfinite(ref[j, c])
                used[q - ptr[k]] = ok
                if not ok:
                    continue
                a = (1.0, sv[q - ptr[k]], rv[q - ptr[k]])
                for i1 in range(3):
                    for i2 in range(3):
                        ata[i1, i2] += a[i1] * a[i2]
                    for c in range(d):
                        atx[i1, c] += a[i1] * (cur[t, j, c] - ref[k, c])
                m += 1
            if m < min_count:
                continue
            if abs(np.linalg.det(ata)) < 1e-12 * (ata[1, 1] * ata[2, 2] + 1e-300) * m:
                continue
            inv = np.linalg.inv(ata)
            B = inv @ atx  # (3, d): rows a, dF/ds, dF/dt
            c11 = 0.0
            c22 = 0.0
            c12 = 0.0
            for c in range(d):
                c11 += B[1, c] * B[1, c]
                c22 += B[2, c] * B[2, c]
                c12 += B[1, c] * B[2, c]
            E[t, k, 0] = 0.5 * (c11 - 1.0)
            E[t, k, 1] = 0.5 * (c22 - 1.0)
            E[t, k, 2] = 0.5 * c12
            # slope noise with the correlation of overlapping subsets: errors of two points
            # correlate by the shared fraction of their subsets' pixels
            for a1 in range(cnt):
                w1[a1] = inv[1, 0] + inv[1, 1] * sv[a1] + inv[1, 2] * rv[a1]
                w2[a1] = inv[2, 0] + inv[2, 1] * sv[a1] + inv[2, 2] * rv[a1]
            v1 = 0.0
            v2 = 0.0
            v12 = 0.0
            for a1 in range(cnt):
                if not used[a1]:
                    continue
                ja = idx[ptr[k] + a1]
                for a2 in range(cnt):
                    if not used[a2]:
                        continue
                    jb = idx[ptr[k] + a2]
                    ox = 1.0 - abs(pix[ja, 0] - pix[jb, 0]) / subset
                    oy = 1.0 - abs(pix[ja, 1] - pix[jb, 1]) / subset
                    if ox <= 0.0 or oy <= 0.0:
                        continue
                    rho = ox * oy * sig[t, ja] * sig[t, jb]
                    v1 += w1[a1] * w1[a2] * rho
                    v2 += w2[a1] * w2[a2] * rho
                    v12 += 0.25 * (w1[a1] * w1[a2] + w2[a1] * w2[a2]) * rho
            U[t, k, 0] = np.sqrt(v1)
            U[t, k, 1] = np.sqrt(v2)
            U[t, k, 2] = np.sqrt(v12)


def surface_strain(
    ref: np.ndarray,
    cur: np.ndarray,
    sigma: np.ndarray,
    index: np.ndarray,
    window: int,
    pixels: np.ndarray,
    subset_size: int,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Green-Lagrange surface strain by local fits (see module docstring).

    Parameters
    ----------
    ref : ndarray (N, d)
        Reference positions (d = 2 image-plane [pixel], or 3 [m]); NaN where unknown.
    cur : ndarray (T, N, d)
        Deformed positions, same units; NaN where not measured.
    sigma : ndarray (T, N)
        Standard uncertainty of the displacement (RMS over components), same units; NaN
        where not measured.
    index : ndarray (N, 2) int
        Grid row/column of each point.
    window : int
        Odd window size in grid points (>= 3).
    pixels : ndarray (N, 2)
        Subset centres in the reference image [pixel]; with ``subset_size`` [pixel] they set
        how strongly the displacement errors of two points correlate (shared pixels).

    Returns
    -------
    E, E_u : ndarray (T, N, 3)
        ``E11, E22, E12`` (tensor shear) [1] and their standard uncertainties; NaN where
        fewer than 60 % of the window's points (and at least 4) were measured.
    frames : ndarray (N, 2, d)
        The tangent bases used.
    """
    ptr, idx = window_neighbours(index, window)
    frames = tangent_frames(ref, ptr, idx)
    T, N = cur.shape[:2]
    E = np.full((T, N, 3), np.nan)
    U = np.full((T, N, 3), np.nan)
    min_count = max(4, int(np.ceil(0.6 * window * window)))
    _strain_kernel(
        np.ascontiguousarray(ref, float),
        np.ascontiguousarray(cur, float),
        np.ascontiguousarray(sigma, float),
        np.ascontiguousarray(pixels, float),
        float(subset_size),
        ptr,
        idx,
        frames,
        min_count,
        E,
        U,
    )
    return E, U, frames


def engineering_strain(E: np.ndarray) -> np.ndarray:
    """Engineering strains (..., 3) from Green-Lagrange ``E11, E22, E12``: stretches minus one
    and the change of the right angle [rad]."""
    l1 = np.sqrt(1.0 + 2.0 * E[..., 0])
    l2 = np.sqrt(1.0 + 2.0 * E[..., 1])
    with np.errstate(invalid="ignore"):
        gamma = np.arcsin(np.clip(2.0 * E[..., 2] / (l1 * l2), -1.0, 1.0))
    return np.stack([l1 - 1.0, l2 - 1.0, gamma], axis=-1)


def strain_variables(ref, cur, disp_u, index, pixels, window, step, subset_size):
    """The field dataset's ``strain``, ``strain_u`` and ``strain_engineering`` variables and
    the ``component`` coordinate, from reference positions ``ref`` (N, d) (NaN where unknown),
    deformed positions ``cur`` (T, N, d) and the displacement uncertainty ``disp_u``
    (T, N, d); ``step`` and ``subset_size`` [pixel] describe the grid."""
    import xarray as xr

    data = {}
    inplane = np.sqrt(np.mean(disp_u[..., :2] ** 2, axis=-1))
    E, Eu, _ = surface_strain(ref, cur, inplane, index, window, pixels, subset_size)
    coords = {"component": ("component", ["xx", "yy", "xy"], {"long_name": "tensor component"})}
    span = (window - 1) * step
    note = (
        f"local linear fit of the deformed positions over {window}x"
        f"{window} grid points ({span} pixel in the left reference image), in "
        "the local tangent basis of the reference surface (t1 = frame x projected)"
    )
    data["strain"] = xr.DataArray(
        E,
        dims=("time", "point", "component"),
        attrs={
            "units": "1",
            "long_name": "Green-Lagrange surface strain (xy: tensor shear)",
            "strain_window": note,
            "ancillary_variables": "strain_u",
        },
    )
    data["strain_u"] = xr.DataArray(
        Eu,
        dims=("time", "point", "component"),
        attrs={
            "units": "1",
            "long_name": "standard uncertainty of strain (displacement noise through the fit)",
        },
    )
    data["strain_engineering"] = xr.DataArray(
        engineering_strain(E),
        dims=("time", "point", "component"),
        attrs={
            "units": "1",
            "long_name": "engineering strain: stretch - 1 (xx, yy), change of the right "
            "angle in rad (xy)",
        },
    )
    return data, coords
