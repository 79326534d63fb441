"""Stereo part of the full-field measurement: the plane-induced initial guess of the right
image's matches, triangulation with per-point covariance, the left-right consistency flag, and
the best-fit-plane output frame (see :mod:`jointwear.dic.field._measure`)."""

from __future__ import annotations

import numpy as np
import xarray as xr

from jointwear.dic import icgn as _flags
from jointwear.errors import BadInputError

__all__ = ["plane_guess", "best_fit_plane", "stereo_geometry"]

FLAG_EPIPOLAR = 8


def plane_guess(calibration, centres: np.ndarray) -> np.ndarray:
    """Affine guesses (N, 6) of the left-to-right image map that a plane through the cameras'
    convergence point (normal: the mean viewing direction) induces, at each left centre."""
    L, R = calibration.left, calibration.right
    cl, cr = L.centre, R.centre
    dl, dr = L.rotation[2], R.rotation[2]  # optical axes in the world frame
    # closest points of the two optical axes
    w0 = cl - cr
    a, b, c = dl @ dl, dl @ dr, dr @ dr
    d, e = dl @ w0, dr @ w0
    den = a * c - b * b
    s = (b * e - c * d) / den if abs(den) > 1e-12 else 1.0
    t = (a * e - b * d) / den if abs(den) > 1e-12 else 1.0
    p0 = 0.5 * (cl + s * dl + cr + t * dr)
    nrm = dl + dr
    nrm /= np.linalg.norm(nrm)

    def to_right(uv):
        ray = L.rays(uv)
        lam = ((p0 - cl) @ nrm) / (ray @ nrm)
        return R.project(cl + lam[:, None] * ray)

    h = 1.0
    x0 = to_right(centres)
    gx = (to_right(centres + [h, 0.0]) - to_right(centres - [h, 0.0])) / (2 * h)
    gy = (to_right(centres + [0.0, h]) - to_right(centres - [0.0, h])) / (2 * h)
    G = np.empty((len(centres), 6))
    G[:, 0] = x0[:, 0] - centres[:, 0]
    G[:, 1] = gx[:, 0] - 1.0
    G[:, 2] = gy[:, 0]
    G[:, 3] = x0[:, 1] - centres[:, 1]
    G[:, 4] = gx[:, 1]
    G[:, 5] = gy[:, 1] - 1.0
    return G


def _point_cov(calibration, X, sl, sr):
    """Covariance (N, 3, 3) of triangulated points X (N, 3) from per-image standard
    uncertainties ``sl``, ``sr`` (N, 2) [pixel] (undistorted-pixel Jacobians ``J``).

    The triangulation minimises the unweighted reprojection error of the four image
    coordinates, so a point moves by ``G d``, ``G = (J^T J)^-1 J^T``, for image errors ``d``:
    ``cov = G diag(s^2) G^T`` (not the inverse-variance-weighted ``(J^T diag(s^-2) J)^-1``,
    which is the covariance of a weighted triangulation and under-states Y, the coordinate
    both cameras' rows fix, when the images' uncertainties differ)."""
    from jointwear.dic.calibration import project_undistorted as _project_undistorted

    out = np.full((len(X), 3, 3), np.nan)
    ok = np.isfinite(X).all(axis=1) & np.isfinite(sl).all(axis=1) & np.isfinite(sr).all(axis=1)
    if not ok.any():
        return out
    _, Jl = _project_undistorted(calibration.left, X[ok])
    _, Jr = _project_undistorted(calibration.right, X[ok])
    J = np.concatenate([Jl, Jr], axis=1)  # (n, 4, 3)
    G = np.linalg.solve(np.einsum("nki,nkj->nij", J, J), np.transpose(J, (0, 2, 1)))
    v = np.concatenate([sl[ok], sr[ok]], axis=1) ** 2
    out[ok] = np.einsum("nik,nk,njk->nij", G, v, G)
    return out


#: a calibration whose reference pair misses by more than this many times the epipolar gate
#: (median RMS reprojection residual) is refused before the sequence is matched
MISFIT_FACTOR = 2.0


#: the gate a refusal suggests keeps this share [%] of the reference pair's points
RECOVER_PERCENTILE = 95


def _round_up(value: float) -> float:
    """``value`` rounded up to two significant digits (a gate that keeps what it measured)."""
    digits = 1 - int(np.floor(np.log10(value)))
    return float(np.ceil(value * 10.0**digits) / 10.0**digits)


def check_calibration_fits(calibration, uv_left, uv_right, ok, epipolar_max_px) -> dict:
    """Measure how well the calibration fits the reference pair's matches, once, up front.

    ``uv_left``, ``uv_right`` (N, 2) [pixel] the matched subset centres, ``ok`` the points
    matched in both images. Returns the medians as dataset attributes
    (``dic_median_epipolar_error_pixel``: distance of the right match from the left point's
    epipolar line; ``dic_median_reprojection_pixel``: RMS reprojection residual of the
    triangulated pair, what ``epipolar_max_px`` gates). Raises :class:`BadInputError` when
    the median reprojection residual exceeds ``MISFIT_FACTOR`` times the gate: most points
    would be flagged ``epipolar_mismatch`` and the positions of the rest carry the misfit.
    """
    from jointwear.dic.calibration import epipolar_distance, triangulate

    if not ok.any():
        return {}
    epi = epipolar_distance(calibration, uv_left[ok], uv_right[ok])
    _, _, rep = triangulate(calibration, uv_left[ok], uv_right[ok])
    med_epi, med_rep = float(np.nanmedian(np.abs(epi))), float(np.nanmedian(rep))
    if med_rep > MISFIT_FACTOR * epipolar_max_px:
        share = float(np.mean(rep > epipolar_max_px))
        keeps = _round_up(float(np.nanpercentile(rep, RECOVER_PERCENTILE)))
        raise BadInputError(
            f"the calibration ({calibration.source}) does not fit these images: over the "
            f"{int(ok.sum())} points matched in the reference pair, median epipolar error "
            f"{med_epi:.2f} pixel (median RMS reprojection residual {med_rep:.2f} pixel), "
            f"against epipolar_max_px={epipolar_max_px:g} (CLI --epipolar-max, pixel, RMS "
            f"reprojection): {share:.0%} of the points would be flagged epipolar_mismatch. "
            "Use the calibration of these cameras and check which images are the left and "
            "which the right camera's; only for a calibration known to be coarse, "
            f"--epipolar-max {keeps:g} keeps {RECOVER_PERCENTILE}% of these points (the "
            f"{RECOVER_PERCENTILE}th percentile of their residual; the positions then carry "
            "that misfit)"
        )
    return {"dic_median_epipolar_error_pixel": med_epi, "dic_median_reprojection_pixel": med_rep}


def best_fit_plane(P: np.ndarray, towards: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rotation (3, 3) (rows: plane x, y, z in world coordinates) and origin (3,) [m] of the
    least-squares plane of the points P (N, 3); z points to the side of ``towards``."""
    Q = P[np.isfinite(P).all(axis=1)]
    if len(Q) < 3:
        raise BadInputError(
            "best-fit-plane frame: fewer than 3 points were measured in the reference pair"
        )
    o = Q.mean(axis=0)
    _, _, vt = np.linalg.svd(Q - o, full_matrices=False)
    z = vt[2] * (1.0 if vt[2] @ (towards - o) > 0 else -1.0)
    ref = np.array([1.0, 0, 0]) if abs(z[0]) < 0.9 else np.array([0, 1.0, 0])
    x = ref - z * (ref @ z)
    x /= np.linalg.norm(x)
    return np.stack([x, np.cross(z, x), z]), o


def stereo_geometry(calibration, sub_x, sub_y, DL, SR, DR, flag, prm):
    """Triangulate every image's matched pairs (see :mod:`jointwear.dic.field._measure`).

    ``sub_x``, ``sub_y`` (T, 2, N) [pixel] subset centres in the left and right images, ``DL``,
    ``DR`` (T, N, 2) the standard uncertainties [pixel] of every image's left and right match
    relative to the camera's reference image (:mod:`jointwear.dic.field._mismatch`), ``SR``
    (T, N, 2) the right matches' own (for ``position_u``), ``flag`` (T, N) updated in place
    (``epipolar_mismatch``; a point without a reference position is flagged at every time).
    Returns ``(ref_pos, disp, disp_u, data, coords, attrs)``: reference positions (N, 3) and
    displacements (T, N, 3) [m] in the output frame, their standard uncertainties, and the
    dataset's stereo variables, coordinates and attributes.
    """
    from jointwear.dic.calibration import triangulate
    from jointwear.dic.field._measure import variable

    n_t, _, n = sub_x.shape
    data: dict[str, xr.DataArray] = {}
    attrs: dict = {}
    coords: dict = {}

    X = np.full((n_t, n, 3), np.nan)
    rep = np.full((n_t, n), np.nan)
    for k in range(n_t):
        uvl = np.stack([sub_x[k, 0], sub_y[k, 0]], axis=1)
        uvr = np.stack([sub_x[k, 1], sub_y[k, 1]], axis=1)
        X[k], _, rep[k] = triangulate(calibration, uvl, uvr)
    far = (rep > prm.epipolar_max_px) & (flag == _flags.FLAG_OK)
    flag[far] = FLAG_EPIPOLAR
    flag[:, flag[0] != _flags.FLAG_OK] = np.where(
        flag[:, flag[0] != _flags.FLAG_OK] == _flags.FLAG_OK,
        flag[0][flag[0] != _flags.FLAG_OK],
        flag[:, flag[0] != _flags.FLAG_OK],
    )
    ref_pos = X[0]
    zero = np.zeros((n, 2))
    cov_pos = _point_cov(calibration, X[0], SR[0], SR[0])
    disp = X - X[0][None]
    cov_d = np.full((n_t, n, 3, 3), np.nan)
    cov_d[0] = 0.0
    for k in range(1, n_t):
        # relative-match uncertainties (jointwear.dic.field._mismatch): the left one whole at
        # X_k (the reference position has the unmatched grid centre), the right one half at
        # X_0 (right reference image) and half at X_k (current right image)
        sr = DR[k] / np.sqrt(2)
        cov_d[k] = _point_cov(calibration, X[k], DL[k], sr) + _point_cov(
            calibration, X[0], zero, sr
        )
    Rf, of = np.eye(3), np.zeros(3)
    if prm.frame == "plane":
        Rf, of = best_fit_plane(X[0][flag[0] == _flags.FLAG_OK], calibration.left.centre)
        attrs["field_frame"] = (
            "best-fit plane of the reference surface: origin at the centroid of the "
            "measured points, z its normal towards the cameras, x the world x axis "
            "projected onto it; world = frame_rotation^T (p) + frame_origin"
        )
    else:
        attrs["field_frame"] = f"calibration world frame: {calibration.world_frame}"
    ref_pos = (ref_pos - of) @ Rf.T
    disp = disp @ Rf.T
    cov_d = Rf @ cov_d @ Rf.T
    cov_pos = Rf @ cov_pos @ Rf.T
    disp_u = np.sqrt(np.maximum(np.diagonal(cov_d, axis1=-2, axis2=-1), 0.0))
    pos_u = np.sqrt(np.maximum(np.diagonal(cov_pos, axis1=-2, axis2=-1), 0.0))
    okp = flag[0] == _flags.FLAG_OK
    data["position"] = variable(
        np.where(okp[:, None], ref_pos, np.nan), ("point", "axis"), "m",
        "reference position of the point (surface shape)", ancillary_variables="position_u",
    )  # fmt: skip
    data["position_u"] = variable(
        np.where(okp[:, None], pos_u, np.nan), ("point", "axis"), "m",
        "standard uncertainty of position (image noise)",
    )  # fmt: skip
    data["reprojection"] = variable(
        rep, ("time", "point"), "pixel", "RMS reprojection residual of the triangulated pair"
    )
    data["frame_rotation"] = variable(
        Rf, ("axis", "axis_world"), "1", "rows: output frame axes in world coordinates"
    )
    data["frame_origin"] = variable(of, "axis_world", "m", "output frame origin (world)")
    coords["axis_world"] = ("axis_world", ["x", "y", "z"], {"long_name": "world axis"})
    return ref_pos, disp, disp_u, data, coords, attrs
