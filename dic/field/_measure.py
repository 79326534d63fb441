"""Full-field DIC: displacement and shape of a surface over a ROI (2D or stereo).

``measure_field(left, right=None, *, calibration=None, roi=None, ...)`` is what VIC-3D and
DICe report for a specimen: subsets on a grid over the ROI of the left reference image, each
matched (affine IC-GN, :mod:`jointwear.dic.subset._correlator`) in every image,

* 2D (one camera): in every later left image (absolute reference, guess from the previous
  image); displacement in pixels;
* stereo (two cameras and a :class:`~jointwear.dic.StereoCalibration`): the same left reference
  subsets in the right reference image (initial guess: the affine map that a plane through the
  cameras' convergence point induces between the two images, then reliability-guided search if
  that fails), and in every later left and right image; the matched pairs are triangulated into
  ``position`` (reference shape) and ``displacement`` [m] in the calibration's world frame or in
  the best-fit-plane frame of the reference surface.

Uncertainty (``displacement_u``): every match carries its standard uncertainty from the IC-GN
residual (:mod:`jointwear.dic.icgn._match`; in 2D within 0.75-1.3 of the scatter). For the
displacement, each camera's current match is taken relative to that camera's reference image
and its uncertainty recomputed from the residual between the two
(:mod:`jointwear.dic.field._mismatch`) with the heteroscedasticity-consistent (sandwich)
covariance: it counts the *sub-pixel pattern mismatch* of a moved image (re-sampled at another
sub-pixel phase, the speckle aliases and interpolates differently; the mismatch sits on the
steep speckle edges and moves the match more than white noise of its variance would), which the
white-noise ``s^2 H^-1`` misses. Left: the residual of the match itself (left reference and
current noise: the left reference's noise shifts the current left match but not the grid centre
of the reference position, so it does not cancel). Right: the residual between the right
reference and current images at their matches (the two images' noise; their common mismatch
with the left reference cancels in ``P_k - P_0``), half its variance to each. Both propagate
through the unweighted triangulation, ``cov = G diag(s^2) G^T``, ``G = (J^T J)^-1 J^T`` (J the
projection Jacobians). On the virtual rig (4-pixel speckle) the moved image's Z error is 3.9 um
RMS against 3.7 um reported (2.7 before), coverage of ``|error| <= 2u`` 95 % (85 %).
``position_u`` propagates the full match uncertainty of the reference pair.

Flags (``flag``): the 2D engine's, plus ``epipolar_mismatch`` (the left and right rays miss
each other by more than ``epipolar_max_px`` RMS reprojection: the right match is on the wrong
feature, or the calibration does not fit the images), ``subset_crosses_roi_edge`` (the
subset is not wholly inside a polygon/mask ROI: it mixes the specimen with what lies beyond)
and ``left_right_inconsistent`` (matched back from the right reference image into the left,
the subset lands more than ``consistency_max_px`` from where it started: it straddles a depth
step or another surface, whose parts shift differently between the views).
A flagged point keeps its row with NaN values.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
import xarray as xr

from jointwear.dic import icgn as _flags
from jointwear.dic.field._params import FieldParams
from jointwear.dic.subset import check_image_origin
from jointwear.errors import BadInputError, ParameterError

__all__ = ["FieldParams", "measure_field", "FIELD_FLAG_MEANINGS"]

FLAG_EPIPOLAR = 8
FLAG_ROI_EDGE = 9
FLAG_LEFT_RIGHT = 10
FIELD_FLAG_MEANINGS = (
    _flags.FLAG_MEANINGS + " epipolar_mismatch subset_crosses_roi_edge left_right_inconsistent"
    " uncertainty_outlier failed_in_source neighbour_outlier"
)  # failed_in_source (12): imported fields only (dic.field._import), the value kept for them
assert FIELD_FLAG_MEANINGS.split().index("uncertainty_outlier") == _flags.FLAG_U_OUTLIER
assert FIELD_FLAG_MEANINGS.split().index("neighbour_outlier") == _flags.FLAG_NEIGHBOUR_OUTLIER


def _frames(source, what: str) -> tuple[list[np.ndarray], list[str]]:
    """Images of one camera (first = reference) and their names."""
    from pathlib import Path

    from jointwear.dic.subset import check_image, read_frames, read_image

    if isinstance(source, np.ndarray) and source.ndim == 2:
        return [check_image(source, f"{what} image 0")], ["0"]
    if isinstance(source, (str, Path)):
        from jointwear.dic.footage import is_image_sequence, list_image_sequence

        if is_image_sequence(source):
            files, _ = list_image_sequence(source, what=f"{what} images")
            frames, _ = read_frames(source)
            return frames, [f.name for f in files]
        return [read_image(source)], [Path(source).name]
    if isinstance(source, (list, tuple)):
        out, names = [], []
        for k, item in enumerate(source):
            if isinstance(item, (str, Path)):
                out.append(read_image(item))
                names.append(Path(item).name)
            else:
                out.append(check_image(item, f"{what} image {k}"))
                names.append(str(k))
        return out, names
    frames, _ = read_frames(source)
    return frames, [str(k) for k in range(len(frames))]


def _median_or(values: np.ndarray, default: float) -> float:
    """Median of the latest frame's finite ``values`` (T, N) that has any, else ``default``."""
    for row in values[::-1]:
        finite = row[np.isfinite(row)]
        if finite.size:
            return float(np.median(finite))
    return default


def _track(corr, img, guess, search_centre=(0.0, 0.0)):
    """Match ``img`` from per-point guesses; where points fail (a region moved or lies at a
    depth the guesses do not reach), search afresh from seeds and keep, point by point, the
    match that succeeded."""
    res = corr.match(img, initial_guess=guess)
    structural = np.isin(
        res.flag, (_flags.FLAG_OUTSIDE, _flags.FLAG_NO_TEXTURE, _flags.FLAG_INVALID_PIXELS)
    )
    failed = ~res.ok & ~structural
    if failed.any():
        res2 = corr.match(img, search_centre=search_centre)
        take = failed & res2.ok if res.ok.any() else np.ones(corr.n_points, bool)
        if res.ok.mean() < 0.5 and res2.ok.sum() > res.ok.sum():
            take = np.ones(corr.n_points, bool)  # the guesses were poor overall
        for a, b in (
            (res.params, res2.params),
            (res.zncc, res2.zncc),
            (res.iterations, res2.iterations),
            (res.flag, res2.flag),
            (res.sigma, res2.sigma),
        ):
            a[take] = b[take]
    return res


def left_right_deviation(corr_params, right_img, left_img, centres, rx, ry, subset_size):
    """Left-right consistency: match the right image's subsets (centred where the left ones
    were found) back into the left image; the distance [pixel] from where they land to the
    left centres (NaN where not matched). A subset that straddles a depth step or a second
    surface sees different things in the two views: its forward and backward matches disagree
    by tenths of a pixel while the ZNCC can stay above 0.8. Also returns the backward match's
    standard uncertainty (RMS over x and y times sqrt(2)) [pixel]."""
    from jointwear.dic.subset import SubsetCorrelator

    rc = np.column_stack([rx, ry])
    dev = np.full(len(centres), np.nan)
    sig = np.full(len(centres), np.nan)
    h, w = right_img.shape
    fin = np.isfinite(rc).all(axis=1)
    fin &= (rc[:, 0] >= 0) & (rc[:, 0] <= w - 1) & (rc[:, 1] >= 0) & (rc[:, 1] <= h - 1)
    if not fin.any():
        return dev, sig
    back = SubsetCorrelator(right_img, points=rc[fin], params=corr_params)
    res = back.match(left_img, initial_guess=centres[fin] - rc[fin])
    landed = rc[fin] + res.params[:, [0, 6]]
    d = np.hypot(*(landed - centres[fin]).T)
    dev[fin] = np.where(res.ok, d, np.inf)
    sig[fin] = np.sqrt(np.sum(res.sigma**2, axis=1))
    return dev, sig


def _match_images(corr, L, Rr, calibration, centres, epipolar_max_px=1.0, index=None):
    """Match the left reference subsets in every left image and (stereo) every right image.

    Returns shape parameters ``PL``, ``PR`` (T, N, 12), their (u, v) uncertainties ``SL``,
    ``SR`` (T, N, 2) [pixel] (NaN where the match failed), ZNCC ``Z``, flags ``F``
    (T, cameras, N) and (stereo) the reference pair's fit to the calibration
    (:func:`~jointwear.dic.field._stereo.check_calibration_fits`: refused before the later
    images are matched when it does not fit). ``index`` (N, 2): the points' grid (row, column)
    for the neighbour outlier test (-1 or None: points off a grid, tested on their u only).
    """
    from jointwear.dic.field._stereo import check_calibration_fits, plane_guess

    stereo = len(Rr) > 0
    n_t, n = len(L), corr.n_points
    cams = 2 if stereo else 1
    fit: dict = {}
    PL = np.full((n_t, n, 12), np.nan)
    PR = np.full((n_t, n, 12), np.nan)
    SL = np.full((n_t, n, 2), np.nan)
    SR = np.full((n_t, n, 2), np.nan)
    Z = np.full((n_t, cams, n), np.nan)
    F = np.full((n_t, cams, n), _flags.FLAG_NOT_REACHED, np.int8)
    PL[0] = 0.0
    SL[0] = 0.0
    Z[0, 0] = 1.0
    F[0, 0] = np.where(corr._texture_and_usable()[1], _flags.FLAG_OK, _flags.FLAG_NO_TEXTURE)
    for k in range(1 if not stereo else 0, n_t):
        if k > 0:
            g = np.where(np.isfinite(PL[k - 1]).all(axis=1)[:, None], PL[k - 1], np.nan)
            res = _track(corr, L[k], g)
            PL[k], SL[k], Z[k, 0], F[k, 0] = res.params, res.sigma, res.zncc, res.flag
        if stereo:
            if k == 0:
                G = plane_guess(calibration, centres)
                centre = (float(np.median(G[:, 0])), float(np.median(G[:, 3])))
                res = _track(corr, Rr[0], G, centre)
                fit = check_calibration_fits(
                    calibration, centres, centres + res.params[:, [0, 6]],
                    (F[0, 0] == _flags.FLAG_OK) & res.ok, epipolar_max_px,
                )  # fmt: skip
            else:
                g = np.where(np.isfinite(PR[k - 1]).all(axis=1)[:, None], PR[k - 1], np.nan)
                centre = (_median_or(PR[:k, :, 0], 0.0), _median_or(PR[:k, :, 6], 0.0))
                res = _track(corr, Rr[k], g, centre)
            PR[k], SR[k], Z[k, 1], F[k, 1] = res.params, res.sigma, res.zncc, res.flag
    cp = corr.params
    test = dict(
        centres=centres, index=index, neighbour_factor=cp.neighbour_outlier_factor,
        reach=_flags.neighbour_reach(cp.subset_size, cp.step),
    )  # fmt: skip
    F[1:, 0] = _flags.flag_uncertainty_outliers(
        F[1:, 0], SL[1:], cp.u_outlier_factor, P=PL[1:], **test
    )
    if stereo:
        F[:, 1] = _flags.flag_uncertainty_outliers(F[:, 1], SR, cp.u_outlier_factor, P=PR, **test)
    ok_img = F == _flags.FLAG_OK
    PL[~ok_img[:, 0]] = np.nan
    SL[~ok_img[:, 0]] = np.nan
    if stereo:
        PR[~ok_img[:, 1]] = np.nan
        SR[~ok_img[:, 1]] = np.nan
    return PL, PR, SL, SR, Z, F, fit


def _relative_sigma(L, Rr, PL, PR, centres, cp, kappa):
    """Standard uncertainties ``DL``, ``DR`` (T, N, 2) [pixel] of every image's match relative
    to its camera's reference image (left: the match itself; right: against the right
    reference's match), from the residual between the two images, pattern mismatch included
    (:mod:`jointwear.dic.field._mismatch`), times the engine's ``kappa``; 0 at the reference
    image, NaN where a match is missing."""
    from jointwear.dic.field._mismatch import relative_sigma, spline_coefficients

    n_t, n = PL.shape[:2]
    DL = np.zeros((n_t, n, 2))
    DR = np.zeros((n_t, n, 2))
    if n_t < 2:
        return DL, DR
    c0 = spline_coefficients(L[0], cp.interpolation)
    r0 = spline_coefficients(Rr[0], cp.interpolation) if len(Rr) else None
    for k in range(1, n_t):  # both cameras in one call: the reference Jacobian is shared
        pairs = [(c0, PL[0], spline_coefficients(L[k], cp.interpolation), PL[k])]
        if r0 is not None:
            pairs.append((r0, PR[0], spline_coefficients(Rr[k], cp.interpolation), PR[k]))
        out = relative_sigma(c0, centres, cp.subset_size, pairs, cp.interpolation)
        DL[k] = out[0]
        if r0 is not None:
            DR[k] = out[1]
    return DL * kappa[None, :, None], DR * kappa[None, :, None]


def _point_grid(points, roi, prm: FieldParams):
    """The given subset centres as a :class:`RoiGrid` (no grid index: no strain)."""
    from jointwear.dic.field._roi import RoiGrid

    if roi is not None:
        raise ParameterError("give either points= or roi=, not both (points are the subsets)")
    if prm.strain_window:
        raise ParameterError(
            f"strain_window={prm.strain_window}: scattered points= have no grid to fit strain "
            "over; give strain_window=0, or a roi= grid for strain"
        )
    pts = np.asarray(points, float)
    if pts.ndim != 2 or pts.shape[1] != 2 or len(pts) == 0 or not np.isfinite(pts).all():
        raise BadInputError(
            f"points: expected an (N, 2) array of finite x, y [pixel], got {pts.shape}"
        )
    n = len(pts)
    return (
        RoiGrid(pts, np.full((n, 2), -1, np.int64), np.ones(n, bool), f"{n} points given"),
        f"{n} points given",
    )


def measure_field(
    left,
    right=None,
    *,
    calibration=None,
    roi=None,
    points=None,
    times=None,
    frame_rate: float | None = None,
    data_origin: str = "measured",
    params: FieldParams | None = None,
    **options,
) -> xr.Dataset:
    """Displacement (and shape) of a surface over a ROI, 2D or stereo (see module docstring).

    Parameters
    ----------
    left : image, list of images/paths, folder, pattern or 3D array
        The (left) camera's images; the first is the reference.
    right : same as ``left``, optional
        The right camera's images, one per left image (stereo).
    calibration : StereoCalibration or path, optional
        Required with ``right``: the cameras' calibration (a jointwear calibration file or a
        :class:`~jointwear.dic.StereoCalibration`).
    roi : optional
        Rectangle ``(x0, y0, x1, y1)`` [pixel], polygon TOML, mask image or array (see
        :func:`jointwear.dic.field._roi.read_roi`); default the whole image.
    points : array (N, 2), optional
        Subset centres ``(x, y)`` [pixel, left reference image] instead of a grid over
        ``roi`` (not both). Scattered points have no strain window: with points,
        ``strain_window`` must be 0.
    times : sequence of float, optional
        Time of every image [s]; or ``frame_rate`` [1/s]. Without either (still images), the
        ``time`` dimension has no time coordinate, only the image index.
    data_origin : {"measured", "synthetic"}
        What the images are.
    params : FieldParams, optional
        Options; keyword arguments override its fields.

    Returns
    -------
    Dataset
        Over ``point`` (and ``time``, ``axis``): ``displacement`` [m, or pixel in 2D] with
        ``displacement_u``; stereo ``position`` [m] with ``position_u`` and ``reprojection``
        [pixel]; ``subset_x``/``subset_y`` [pixel] the subset centre in every image
        (``camera``); ``zncc`` (lowest of the point's matches), ``flag``; ``strain`` and
        ``strain_engineering`` [1] (``component`` xx, yy, xy) with ``strain_u``; coordinates
        ``x``, ``y`` [pixel] (left reference image) and the grid ``row``/``col``.

    Examples
    --------
    2D (one camera): the second image's displacement of every subset, image-plane pixels:

    >>> from jointwear.datasets.speckle import RigidField, speckle_pair
    >>> pair = speckle_pair((128, 128), RigidField(translation=(1.3, -0.7)))  # exact shift [pixel]
    >>> from jointwear.dic import measure_field
    >>> ds = measure_field(
    ...     [pair.reference, pair.deformed], subset_size=31, step=16, data_origin="synthetic"
    ... )
    >>> d = ds["displacement"].isel(time=1).mean("point")
    >>> print(f"{float(d.sel(axis='x')):.3f}, {float(d.sel(axis='y')):.3f} pixel")
    1.300, -0.700 pixel
    """
    from jointwear.dic.field._roi import grid_points, read_roi
    from jointwear.dic.subset import SubsetCorrelator

    prm = _field_params(params, options)
    check_image_origin(data_origin)
    calibration, L, lnames, Rr, rnames = _read_images(left, right, calibration)
    t = _time_base(times, frame_rate, len(L))
    cp = prm.correlation()
    if points is not None:
        grid, roi_text = _point_grid(points, roi, prm)
    else:
        mask, roi_text = read_roi(roi, L[0].shape)
        grid = grid_points(mask, cp.subset_size, cp.step, cp.border)
    corr = SubsetCorrelator(L[0], points=grid.centres, params=cp)
    PL, PR, SL, SR, Z, F, fit = _match_images(
        corr, L, Rr, calibration, grid.centres, prm.epipolar_max_px, grid.index
    )
    DL, DR = _relative_sigma(L, Rr, PL, PR, grid.centres, cp, corr._sigma_scale())
    m = _Matches(L, Rr, lnames, rnames, t, grid, PL, PR, SR, DL, DR, Z, F)
    flag, lr = _point_flags(m, cp, prm)
    ds = _field_dataset(m, flag, lr, calibration, prm, cp, with_grid=points is None)
    ds.attrs.update(
        {
            "title": ("stereo" if m.stereo else "2D") + " DIC displacement field",
            "data_origin": data_origin,
            "dic_roi": roi_text,
            "dic_subset_size_pixel": int(cp.subset_size),
            "dic_step_pixel": int(cp.step) if points is None else "points given",
            "dic_zncc_min": float(cp.zncc_min),
            "dic_max_iterations": int(cp.max_iterations),
            "dic_u_outlier_factor": float(cp.u_outlier_factor),
            "dic_neighbour_outlier_factor": float(cp.neighbour_outlier_factor),
            "dic_outlier_floor_pixel": float(_flags.U_OUTLIER_FLOOR_PX),
            "dic_shape_function": "affine",
            "dic_interpolation": f"{cp.interpolation} B-spline (prefiltered)",
            "dic_criterion": "ZNSSD (IC-GN), image gradients by central differences",
            "dic_reference": "absolute (image 0), guesses from the previous image",
            "displacement_convention": "Lagrangian: the point at position moved by displacement",
        }
    )
    if t is None:
        ds.attrs["time_note"] = "still images: no time base; 'image' indexes the time dimension"
    if m.stereo:
        ds.attrs["calibration_source"] = calibration.source
        ds.attrs["dic_epipolar_max_pixel"] = float(prm.epipolar_max_px)
        ds.attrs.update(fit)
    return ds


def _field_params(params: FieldParams | None, options: dict) -> FieldParams:
    """``params`` (default :class:`FieldParams`) with the keyword ``options`` applied."""
    base = params or FieldParams()
    if options:
        unknown = sorted(set(options) - set(asdict(base)))
        if unknown:
            raise ParameterError(
                f"unknown field option(s) {', '.join(unknown)}; known: "
                f"{', '.join(sorted(asdict(base)))}"
            )
        base = FieldParams(**{**asdict(base), **options})
    return base


def _read_images(left, right, calibration):
    """The calibration (read if a path) and the checked images of both cameras with their
    names: ``calibration, L, lnames, Rr, rnames`` (``Rr`` empty in 2D)."""
    from jointwear.dic.subset import check_pair

    stereo = right is not None
    if stereo and calibration is None:
        raise BadInputError(
            "stereo field: right images given without a calibration; pass calibration= "
            "(--calibration FILE)"
        )
    if calibration is not None and not stereo:
        raise BadInputError(
            "a calibration was given but no right images: give the right camera's images "
            "(--right) for a stereo field, or drop the calibration for a 2D field"
        )
    if stereo and not hasattr(calibration, "left"):
        from jointwear.dic.calibration import read_calibration

        calibration = read_calibration(calibration)
    L, lnames = _frames(left, "left" if stereo else "")
    Rr, rnames = _frames(right, "right") if stereo else ([], [])
    n_t = len(L)
    if stereo and len(Rr) != n_t:
        raise BadInputError(
            f"stereo field: {n_t} left images but {len(Rr)} right images; give one right image "
            "per left image (same order)"
        )
    if not stereo and n_t < 2:
        raise BadInputError("2D field: need a reference and at least one deformed image")
    for k in range(1, n_t):
        check_pair(L[0], L[k], what=f"left image {k} ('{lnames[k]}')")
    for k in range(n_t if stereo else 0):
        check_pair(L[0], Rr[k], what=f"right image {k} ('{rnames[k]}')")
    if stereo:
        w, h = calibration.left.image_size
        if (w, h) != (L[0].shape[1], L[0].shape[0]):
            raise BadInputError(
                f"calibration: the left camera was calibrated for {w}x{h} images, the images "
                f"are {L[0].shape[1]}x{L[0].shape[0]}; use the calibration of these cameras"
            )
    return calibration, L, lnames, Rr, rnames


def _time_base(times, frame_rate, n_t: int) -> np.ndarray | None:
    """Time of every image [s] from ``times`` or ``frame_rate`` (None: still images)."""
    if times is not None:
        t = np.asarray(times, float)
        if t.shape != (n_t,) or not np.isfinite(t).all() or np.any(np.diff(t) <= 0):
            raise BadInputError(f"times: expected {n_t} finite, increasing values [s]")
        return t
    if frame_rate is not None:
        if not frame_rate > 0:
            raise ParameterError(f"frame_rate={frame_rate!r}: expected > 0 frames per second")
        return np.arange(n_t) / float(frame_rate)
    return None


@dataclass(frozen=True)
class _Matches:
    """The images and their matches (:func:`_match_images`, :func:`_relative_sigma`)."""

    L: list
    Rr: list
    lnames: list
    rnames: list
    t: np.ndarray | None
    grid: object
    PL: np.ndarray
    PR: np.ndarray
    SR: np.ndarray
    DL: np.ndarray
    DR: np.ndarray
    Z: np.ndarray
    F: np.ndarray

    @property
    def stereo(self) -> bool:
        return len(self.Rr) > 0

    def subset_centres(self) -> tuple[np.ndarray, np.ndarray]:
        """Subset centres ``sub_x``, ``sub_y`` (T, cameras, N) [pixel] in every image."""
        c, PL, PR = self.grid.centres, self.PL, self.PR
        sub_x = np.stack(
            [c[:, 0] + PL[..., 0]] + ([c[:, 0] + PR[..., 0]] if self.stereo else []), axis=1
        )
        sub_y = np.stack(
            [c[:, 1] + PL[..., 6]] + ([c[:, 1] + PR[..., 6]] if self.stereo else []), axis=1
        )
        return sub_x, sub_y


def _point_flags(m: _Matches, cp, prm: FieldParams):
    """One flag per (time, point): the first failing match, else the field's own checks
    (stereo left-right consistency, ROI edge); and (stereo) the left-right deviation
    [pixel]."""
    F = m.F
    n_t, n = F.shape[0], F.shape[2]
    flag = np.full((n_t, n), _flags.FLAG_OK, np.int8)
    for j in range(F.shape[1]):
        bad = (flag == _flags.FLAG_OK) & (F[:, j] != _flags.FLAG_OK)
        flag[bad] = F[:, j][bad]
    lr = None
    if m.stereo:
        bad0 = F[0, 1] != _flags.FLAG_OK  # no right reference match: no position
        flag[:, bad0 & (flag[0] == _flags.FLAG_OK)] = F[0, 1][bad0 & (flag[0] == _flags.FLAG_OK)]
        sub_x, sub_y = m.subset_centres()
        lr, lr_sig = left_right_deviation(
            cp, m.Rr[0], m.L[0], m.grid.centres, sub_x[0, 1], sub_y[0, 1], cp.subset_size
        )
        # the forward and backward matches' typical noise (a median: a straddling subset's
        # own residual-based sigma is inflated by the very mismatch to be caught)
        noise = np.sqrt(lr_sig**2 + np.sum(m.SR[0] ** 2, axis=1))
        typical = float(np.nanmedian(noise)) if np.isfinite(noise).any() else 0.0
        limit = max(prm.consistency_max_px, 5.0 * typical)
        bad = (lr > limit) & (flag[0] == _flags.FLAG_OK)
        flag[:, bad] = np.where(flag[:, bad] == _flags.FLAG_OK, FLAG_LEFT_RIGHT, flag[:, bad])
    edge = ~m.grid.complete
    flag[:, edge] = np.where(flag[:, edge] == _flags.FLAG_OK, FLAG_ROI_EDGE, flag[:, edge])
    return flag, lr


def variable(values, dims, units: str, long_name: str, **attrs) -> xr.DataArray:
    """A data variable with its ``units`` and ``long_name`` (and further ``attrs``)."""
    return xr.DataArray(values, dims=dims, attrs={"units": units, "long_name": long_name, **attrs})


def _coordinates(m: _Matches, with_grid: bool) -> dict:
    """Coordinates of the field over point, camera and time."""
    c = m.grid.centres
    cams = ["left", "right"] if m.stereo else ["left"]
    coords = {
        "point": ("point", np.arange(len(c)), {"long_name": "measurement point (subset)"}),
        "x": (
            "point",
            c[:, 0],
            {"units": "pixel", "long_name": "subset centre column, left reference image"},
        ),
        "y": (
            "point",
            c[:, 1],
            {"units": "pixel", "long_name": "subset centre row, left reference image"},
        ),
        "camera": ("camera", cams, {"long_name": "camera"}),
        "image": ("time", np.arange(len(m.L)), {"long_name": "image index (0 = reference)"}),
        "image_left": ("time", m.lnames, {"long_name": "left (or only) camera image"}),
    }
    if m.stereo:
        coords["image_right"] = ("time", m.rnames, {"long_name": "right camera image"})
    if with_grid:
        coords["row"] = ("point", m.grid.index[:, 0], {"long_name": "grid row of the point"})
        coords["col"] = ("point", m.grid.index[:, 1], {"long_name": "grid column of the point"})
    if m.t is not None:
        coords["time"] = ("time", m.t, {"units": "s", "long_name": "time of the image"})
    return coords


def _field_dataset(m: _Matches, flag, lr, calibration, prm: FieldParams, cp, with_grid: bool):
    """The field's Dataset (displacement, uncertainty, subset centres, ZNCC, flags, strain)."""
    from jointwear.dic.field._stereo import stereo_geometry

    c = m.grid.centres
    sub_x, sub_y = m.subset_centres()
    Z = m.Z
    zncc = np.fmin.reduce(np.where(np.isfinite(Z), Z, np.nan), axis=1) if m.stereo else Z[:, 0]
    coords = _coordinates(m, with_grid)
    data: dict[str, xr.DataArray] = {}
    attrs: dict = {}
    if not m.stereo:
        axes = ["x", "y"]
        disp = np.stack([m.PL[..., 0], m.PL[..., 6]], axis=-1)
        disp_u = m.DL
        ref_pos = c.copy()
        unit = "pixel"
        attrs["field_frame"] = "left image: x to the right (columns), y down (rows), pixel"
    else:
        axes = ["x", "y", "z"]
        ref_pos, disp, disp_u, extra, extra_coords, extra_attrs = stereo_geometry(
            calibration, sub_x, sub_y, m.DL, m.SR, m.DR, flag, prm
        )
        unit = "m"
        data.update(extra)
        coords.update(extra_coords)
        attrs.update(extra_attrs)
    ok = flag == _flags.FLAG_OK
    disp = np.where(ok[..., None], disp, np.nan)
    disp_u = np.where(ok[..., None], disp_u, np.nan)
    coords["axis"] = ("axis", axes, {"long_name": "vector component"})
    tpa = ("time", "point", "axis")
    data["displacement"] = variable(
        disp, tpa, unit, "displacement of the point from the reference image",
        ancillary_variables="displacement_u zncc flag",
    )  # fmt: skip
    data["displacement_u"] = variable(
        disp_u, tpa, unit,
        "standard uncertainty of displacement (image noise and sub-pixel pattern mismatch "
        "through the matches and the triangulation; excludes calibration error)",
    )  # fmt: skip
    tcp = ("time", "camera", "point")
    data["subset_x"] = variable(
        np.where(ok[:, None, :], sub_x, np.nan), tcp, "pixel", "subset centre column in the image"
    )
    data["subset_y"] = variable(
        np.where(ok[:, None, :], sub_y, np.nan), tcp, "pixel", "subset centre row in the image"
    )
    data["zncc"] = variable(zncc, ("time", "point"), "1", "lowest ZNCC of the point's matches")
    data["flag"] = variable(
        flag, ("time", "point"), "1", "field quality flag",
        flag_values=np.arange(len(FIELD_FLAG_MEANINGS.split()), dtype=np.int8),
        flag_meanings=FIELD_FLAG_MEANINGS,
    )  # fmt: skip
    if m.stereo:
        data["left_right_deviation"] = variable(
            np.where(np.isfinite(lr), lr, np.nan), "point", "pixel",
            "distance from the left subset centre to where its right match lands when matched "
            "back into the left reference image",
        )  # fmt: skip
    if prm.strain_window:
        from jointwear.dic.field._strain import strain_variables

        strain, comp = strain_variables(
            np.where(ok[0][:, None], ref_pos, np.nan), ref_pos[None] + disp, disp_u,
            m.grid.index, c, prm.strain_window, cp.step, cp.subset_size,
        )  # fmt: skip
        data.update(strain)
        coords.update(comp)
    ds = xr.Dataset(data, coords=coords)
    ds.attrs.update(attrs)
    return ds
