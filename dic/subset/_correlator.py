"""Subset correlation of a reference image against deformed images (the 2D engine's core).

``SubsetCorrelator(reference, *, points=None, roi=None, subset_size=31, step=10,
shape="affine", interpolation="cubic", ...)`` validates the reference once, computes its B-spline
coefficients and node gradients, lays out the points of interest (a grid over ``roi`` with
``step``, or the given ``(N, 2)`` array of ``(x, y)`` positions [pixel]) and their neighbour
graph. Then, for each deformed image:

``SubsetCorrelator.correlate(deformed, *, initial_guess=None, seed_points=None) -> Dataset``

* ``initial_guess`` ``(N, 2)`` displacements ``(u, v)`` [pixel], or ``(N, 6)`` affine
  ``(u, du/dx, du/dy, v, dv/dx, dv/dy)``, or ``(N, 12)`` full shape parameters (layout of
  :mod:`jointwear.dic.icgn._match`): every point is refined from its guess in parallel, and points
  that fail are retried by reliability-guided propagation from their converged neighbours.
* otherwise seeds are found by OpenCV template matching (``search_radius``; rotated templates
  when the plain search fails) and the solution propagates from the best-correlated points to
  their neighbours (reliability-guided DIC), in parallel bands.

``SubsetCorrelator.match(deformed, ...)`` returns the raw arrays (``MatchResult``) instead of a
Dataset, and ``to_record`` packages them as the Dataset's arrays without xarray (what the command
line writes). Points that cannot be correlated are kept and flagged (``flag``, CF
``flag_values``/``flag_meanings``), with NaN displacements.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from typing import TYPE_CHECKING

import numpy as np

from jointwear.dic import icgn as _flags
from jointwear.dic.subset._output import result_dataset, result_record
from jointwear.dic.subset._params import (
    CorrelationParams,
    _integral_invalid,
    check_image,
    check_pair,
    set_threads,
)
from jointwear.errors import BadInputError, ParameterError

if TYPE_CHECKING:
    import xarray as xr

    from jointwear._netcdf import Record
    from jointwear.dic.icgn import SplineImage

__all__ = [
    "CorrelationParams",
    "SubsetCorrelator",
    "MatchResult",
    "FLAG_MEANINGS",
    "check_image",
    "check_pair",
    "result_dataset",
    "set_threads",
]

FLAG_MEANINGS = _flags.FLAG_MEANINGS

#: extra margin [pixel] of the default grid beyond the border (see SubsetCorrelator)
_GRID_SLACK = 2


@dataclass
class MatchResult:
    """Raw per-point output of :meth:`SubsetCorrelator.match`.

    ``params`` (N, 12) shape parameters (layout of :mod:`jointwear.dic.icgn._match`), ``zncc`` (N,),
    ``iterations`` (N,), ``flag`` (N,) int8, ``sigma`` (N, 2) standard uncertainty of (u, v)
    [pixel] from the match residual (NaN unless ok).
    """

    params: np.ndarray
    zncc: np.ndarray
    iterations: np.ndarray
    flag: np.ndarray
    sigma: np.ndarray | None = None

    def __post_init__(self) -> None:
        if self.sigma is None:
            self.sigma = np.full((len(self.zncc), 2), np.nan)

    @property
    def ok(self) -> np.ndarray:
        return self.flag == _flags.FLAG_OK


class SubsetCorrelator:
    """Reference image prepared once for correlating many deformed images.

    Parameters
    ----------
    reference : ndarray (H, W)
        Reference image (any numeric type; NaN marks invalid pixels).
    points : ndarray (N, 2), optional
        Subset centres ``(x, y)`` [pixel] (x = column, y = row). Non-integer centres are
        sampled on the reference interpolant.
    roi : (x_min, y_min, x_max, y_max), optional
        Region [pixel, inclusive] that grid subsets must lie in (default: the whole image).
    params : CorrelationParams, optional
        All options; keyword arguments (``subset_size=...``) override its fields.
    """

    #: points per propagation group that measure the IC-GN's contraction before the others
    #: may assume it (None: ``CONTRACTION_PROBES``; 0: the classic convergence test only; see
    #: :func:`jointwear.dic.icgn._drive.rg_propagate`)
    _contraction_probes: int | None = None

    def __init__(
        self,
        reference: np.ndarray,
        *,
        points: np.ndarray | None = None,
        roi: Sequence[float] | None = None,
        params: CorrelationParams | None = None,
        _graph: tuple[np.ndarray, np.ndarray] | None = None,
        **options,
    ) -> None:
        base = params or CorrelationParams()
        if options:
            known = set(asdict(base))
            unknown = sorted(set(options) - known)
            if unknown:
                raise ParameterError(
                    f"unknown correlation option(s) {', '.join(unknown)}; known: "
                    f"{', '.join(sorted(known))}"
                )
            base = CorrelationParams(**{**asdict(base), **options})
        self.params = base
        from jointwear.dic.icgn import prefilter

        self.reference_raw = check_image(reference, "reference image")
        self.ref = prefilter(self.reference_raw, base.interpolation)
        self._ref_invalid = _integral_invalid(self.ref.valid)
        h, w = self.ref.shape
        valid_vals = self.ref.image if self.ref.valid.all() else self.ref.image[self.ref.valid]
        if valid_vals.size == 0:
            raise BadInputError("reference image: every pixel is NaN")
        self.image_std = float(np.std(valid_vals))
        self.grid: tuple[np.ndarray, np.ndarray] | None = None
        self._loaded: tuple | None = None  # reference subsets kept by preload_references()
        if points is not None:
            pts = np.asarray(points, dtype=np.float64)
            if pts.ndim == 1 and pts.size == 2:
                pts = pts[None, :]
            if pts.ndim != 2 or pts.shape[1] != 2 or pts.shape[0] == 0:
                raise BadInputError(
                    f"points: expected an (N, 2) array of (x, y) pixel positions, got shape "
                    f"{np.shape(points)}"
                )
            if roi is not None:
                raise ParameterError("give either points or roi, not both")
            self.centres = np.ascontiguousarray(pts)
        else:
            half = base.half
            b = base.border
            if roi is None:
                x_min, y_min, x_max, y_max = b, b, w - 1 - b, h - 1 - b
            else:
                try:
                    x_min, y_min, x_max, y_max = (int(round(float(v))) for v in roi)
                except (TypeError, ValueError):
                    raise ParameterError(
                        f"roi={roi!r}: expected (x_min, y_min, x_max, y_max) in pixels"
                    ) from None
                if not (0 <= x_min < x_max <= w - 1 and 0 <= y_min < y_max <= h - 1):
                    raise ParameterError(
                        f"roi={tuple(roi)!r} must satisfy 0 <= x_min < x_max <= {w - 1} and "
                        f"0 <= y_min < y_max <= {h - 1} (image of {w}x{h} pixels)"
                    )
            # where the image edge (not the roi) limits the grid, the outer subsets keep
            # _GRID_SLACK pixels more than the border margin: on the margin itself any motion
            # towards the edge, even sub-pixel noise, flags them subset_outside_image
            lo, hix, hiy = b + _GRID_SLACK, w - 1 - b - _GRID_SLACK, h - 1 - b - _GRID_SLACK
            x_min, y_min = max(x_min, lo), max(y_min, lo)
            x_max, y_max = min(x_max, hix), min(y_max, hiy)
            xs = np.arange(x_min + half, x_max - half + 1, base.step, dtype=float)
            ys = np.arange(y_min + half, y_max - half + 1, base.step, dtype=float)
            if xs.size == 0 or ys.size == 0:
                raise ParameterError(
                    f"no subset of {base.subset_size} pixels fits in the region "
                    f"x {x_min}..{x_max}, y {y_min}..{y_max}; enlarge the roi or reduce subset_size"
                )
            # centre the grid in the region
            xs += (x_max - half - xs[-1]) // 2
            ys += (y_max - half - ys[-1]) // 2
            self.grid = (xs, ys)
            X, Y = np.meshgrid(xs, ys)
            self.centres = np.ascontiguousarray(np.column_stack([X.ravel(), Y.ravel()]))
        if _graph is not None and len(_graph[0]) == self.n_points + 1:
            self._nb_ptr, self._nb_idx = _graph
        else:
            self._neighbours()
        self._texture = None

    # ------------------------------------------------------------------ layout
    @property
    def graph(self) -> tuple[np.ndarray, np.ndarray]:
        """Neighbour graph of the points (CSR: pointer, indices)."""
        return self._nb_ptr, self._nb_idx

    @property
    def n_points(self) -> int:
        return self.centres.shape[0]

    def _neighbours(self) -> None:
        n = self.n_points
        if self.grid is not None:
            nx, ny = self.grid[0].size, self.grid[1].size
            idx = np.arange(n).reshape(ny, nx)
            lists = []
            for dy, dx in ((-1, 0), (1, 0), (0, -1), (0, 1)):
                src = idx[max(0, -dy) : ny - max(0, dy), max(0, -dx) : nx - max(0, dx)]
                dst = idx[max(0, dy) : ny - max(0, -dy), max(0, dx) : nx - max(0, -dx)]
                lists.append(np.column_stack([src.ravel(), dst.ravel()]))
            pairs = np.concatenate(lists) if lists else np.zeros((0, 2), int)
        elif n > 1:
            from scipy.spatial import cKDTree

            k = min(8, n - 1)
            _, nb = cKDTree(self.centres).query(self.centres, k=k + 1)
            src = np.repeat(np.arange(n), k)
            dst = nb[:, 1:].ravel()
            pairs = np.column_stack([src, dst])
            pairs = np.unique(np.concatenate([pairs, pairs[:, ::-1]]), axis=0)
        else:
            pairs = np.zeros((0, 2), int)
        order = np.argsort(pairs[:, 0], kind="stable")
        pairs = pairs[order]
        self._nb_idx = np.ascontiguousarray(pairs[:, 1].astype(np.int64))
        counts = np.bincount(pairs[:, 0], minlength=n) if len(pairs) else np.zeros(n, int)
        self._nb_ptr = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)

    def _texture_and_usable(self) -> tuple[np.ndarray, np.ndarray]:
        """Intensity std of every reference subset, and which points can be seeds."""
        from jointwear.dic import icgn as _icgn

        if self._texture is None:
            tex = _icgn.subset_std(
                self.ref.image,
                self._ref_invalid,
                self.centres,
                self.params.half,
                self.params.border,
            )
            usable = np.isfinite(tex) & (tex > self._min_subset_std)
            self._texture = (np.nan_to_num(tex), usable)
        return self._texture

    # ------------------------------------------------------------------ matching
    def _prepare_deformed(self, deformed) -> tuple[SplineImage, np.ndarray, np.ndarray]:
        from jointwear.dic.icgn import SplineImage, prefilter

        if isinstance(deformed, SplineImage):
            spl = deformed
            raw = deformed.image
        else:
            raw = check_image(deformed, "deformed image")
            check_pair(self.reference_raw, raw)
            spl = prefilter(raw, self.params.interpolation, gradients=False)
        if spl.order != self.ref.order:
            raise ParameterError("deformed SplineImage was prefiltered with another interpolation")
        inv = _integral_invalid(spl.valid) if not spl.valid.all() else np.zeros((1, 1), np.int64)
        return spl, inv, raw

    def _kernel_args(self, dspl, dinv) -> tuple[tuple, tuple]:
        """The kernels' packed ``ref`` and ``dfm`` arguments (see :mod:`jointwear.dic.icgn._match`)."""
        r = self.ref
        return (r.image, r.gx, r.gy, r.coef, self._ref_invalid), (dspl.coef, dinv)

    @property
    def _min_subset_std(self) -> float:
        """Smallest subset intensity std that counts as texture [grey levels]."""
        return self.params.min_texture * self.image_std

    def _solver_options(self) -> tuple:
        """IC-GN options in the kernels' order: half, second order (the shape function's
        kernel branch), max_iter, tol, min_std, max_shift, border, zncc_min, order."""
        p = self.params
        return (
            int(p.half),
            bool(p.shape_function.second_order),
            int(p.max_iterations),
            float(p.tolerance),
            float(self._min_subset_std),
            float(max(p.half, 5)),
            float(p.border),
            float(p.zncc_min),
            int(self.ref.order),
        )

    def preload_references(self) -> None:
        """Keep every reference subset, its gradients and Gauss-Newton matrix in memory.

        For matching the same points in many images (tracking): each later :meth:`match`
        then skips loading them (the IC-GN's per-point set-up, as costly as one or two
        iterations, and far more for points off the pixel grid, whose reference values are
        interpolated). Memory: 3 x 8 bytes x subset_size^2 per point, so meant for hundreds or
        thousands of points, not for dense fields. Affine shape only; the kernel then runs on
        one thread without holding the GIL, so several correlators can work in threads.
        """
        from jointwear.dic import icgn as _icgn

        if not self.params.shape_function.preload:
            raise ParameterError(
                f"preload_references: not for the {self.params.shape} shape function (affine only)"
            )
        n, m = self.n_points, self.params.subset_size**2
        F, GX, GY = np.empty((n, m)), np.empty((n, m)), np.empty((n, m))
        HINV, JF, JS = np.empty((n, 6, 6)), np.empty((n, 6)), np.empty((n, 6))
        FN, FLAG0 = np.empty(n), np.empty(n, dtype=np.int8)
        r = self.ref
        ref = (r.image, r.gx, r.gy, r.coef, self._ref_invalid)
        _icgn.affine_references(
            ref, self._solver_options(), self.centres, F, GX, GY, HINV, JF, JS, FN, FLAG0
        )
        self._loaded = (F, GX, GY, HINV, JF, JS, FN, FLAG0)

    def _run_many(self, dspl, dinv, P, active, st, serial=False):
        from jointwear.dic import icgn as _icgn

        ref, dfm = self._kernel_args(dspl, dinv)
        out = (st.zncc, st.iterations, st.flag, st.sigma)
        opts = self._solver_options()
        scale = self._kappa_of_points()
        if self._loaded is not None:
            _icgn.icgn_affine_loaded(self._loaded, dfm, opts, self.centres, scale, P, active, out)
            return
        kernel = _icgn.icgn_serial if serial else _icgn.icgn_many
        kernel(ref, dfm, opts, self.centres, scale, P, active, out)

    def _propagate(self, dspl, dinv, st, done, group, n_groups):
        from jointwear.dic import icgn as _icgn

        ref, dfm = self._kernel_args(dspl, dinv)
        _icgn.rg_propagate(
            n_groups,
            group,
            ref,
            dfm,
            self._solver_options(),
            self.centres,
            self._kappa_of_points(),
            self._nb_ptr,
            self._nb_idx,
            st.params,
            (st.zncc, st.iterations, st.flag, st.sigma),
            done,
            _icgn.CONTRACTION_PROBES
            if self._contraction_probes is None
            else int(self._contraction_probes),
        )

    def _retry_failed(self, dspl, dinv, st, done, group) -> None:
        """Give failed (but structurally fine) points one more chance from other neighbours."""
        retry = np.isin(
            st.flag, (_flags.FLAG_NOT_CONVERGED, _flags.FLAG_LOW_CORRELATION, _flags.FLAG_DIVERGED)
        )
        unreached = ~done
        if (retry | unreached).any() and st.ok.any():
            saved = (
                st.params.copy(),
                st.zncc.copy(),
                st.iterations.copy(),
                st.flag.copy(),
                st.sigma.copy(),
            )
            done[retry] = False
            self._propagate(dspl, dinv, st, done, group, 0)
            back = retry & ~done  # not reached again: keep the first attempt
            st.params[back], st.zncc[back] = saved[0][back], saved[1][back]
            st.iterations[back], st.flag[back] = saved[2][back], saved[3][back]
            st.sigma[back] = saved[4][back]
            done[back] = True

    def _seed(self, dspl, dinv, raw_def, st, done, i, guess=(0.0, 0.0)) -> bool:
        """Try point ``i`` as a seed: integer search (plain, then rotated), then IC-GN.

        If every attempt fails, the point keeps the outcome of the plain attempt.
        """
        from jointwear.dic.subset._guess import integer_search

        p = self.params
        xc, yc = self.centres[i]
        active = np.zeros(self.n_points, bool)
        active[i] = True

        def attempt(tu, tv, ang):
            th = math.radians(ang)
            P0 = np.zeros(12)
            P0[0], P0[6] = tu, tv
            P0[1], P0[2] = math.cos(th) - 1.0, -math.sin(th)
            P0[7], P0[8] = math.sin(th), math.cos(th) - 1.0
            st.params[i] = P0
            self._run_many(dspl, dinv, st.params, active, st, serial=True)
            return st.flag[i] == _flags.FLAG_OK

        u, v, peak, _ = integer_search(self.ref, raw_def, xc, yc, p.half, p.search_radius, guess)
        done[i] = True
        if attempt(u, v, 0.0) if np.isfinite(peak) else attempt(guess[0], guess[1], 0.0):
            return True
        first = (st.params[i].copy(), st.zncc[i], st.iterations[i], st.flag[i], st.sigma[i].copy())
        structural = (_flags.FLAG_OUTSIDE, _flags.FLAG_NO_TEXTURE, _flags.FLAG_INVALID_PIXELS)
        if first[3] not in structural:
            # rotated templates: the part may have turned
            scored = []
            for a in np.arange(-180.0, 180.0, 7.5):
                if a == 0.0:
                    continue
                r = integer_search(
                    self.ref, raw_def, xc, yc, p.half, p.search_radius, guess, (float(a),)
                )
                if np.isfinite(r[2]):
                    scored.append((r[2], r[0], r[1], float(a)))
            scored.sort(reverse=True)
            for _, tu, tv, ang in scored[:3]:
                if attempt(tu, tv, ang):
                    return True
        st.params[i], st.zncc[i], st.iterations[i], st.flag[i], st.sigma[i] = first
        return False

    def match(
        self,
        deformed,
        *,
        initial_guess: np.ndarray | None = None,
        seed_points: np.ndarray | None = None,
        search_centre: tuple[float, float] = (0.0, 0.0),
    ) -> MatchResult:
        """Correlate ``deformed`` against the reference; raw per-point arrays.

        ``search_centre`` ``(u, v)`` [pixel] centres the seeds' integer search window (default:
        no displacement); otherwise see :meth:`correlate` for the parameters.

        See :meth:`correlate` for the parameters.
        """
        set_threads(self.params.threads)
        dspl, dinv, raw_def = self._prepare_deformed(deformed)
        n = self.n_points
        st = MatchResult(
            params=np.zeros((n, 12)),
            zncc=np.full(n, np.nan),
            iterations=np.zeros(n, dtype=np.int32),
            flag=np.full(n, _flags.FLAG_NOT_REACHED, dtype=np.int8),
        )
        done = np.zeros(n, dtype=np.bool_)
        group = np.zeros(n, dtype=np.int64)
        if initial_guess is not None:
            st.params[:] = self._guess_array(initial_guess)
            active = np.isfinite(st.params).all(axis=1)
            st.params[~active] = 0.0
            self._run_many(dspl, dinv, st.params, active, st)
            done[active] = True
            self._retry_failed(dspl, dinv, st, done, group)
            st.sigma *= self._sigma_scale()[:, None]
            return st
        tex, usable = self._texture_and_usable()
        if seed_points is not None:
            seeds = self.check_seeds(seed_points)
            d = np.hypot(
                self.centres[:, None, 0] - seeds[None, :, 0],
                self.centres[:, None, 1] - seeds[None, :, 1],
            )
            group = np.argmin(d, axis=1).astype(np.int64)
            n_groups = seeds.shape[0]
            candidates = []
            for g in range(n_groups):
                order = np.argsort(d[:, g])
                cand = [int(j) for j in order[:20] if usable[j]][:5]
                candidates.append(cand)
        else:
            import numba

            from jointwear.dic.subset._guess import pick_seeds

            n_groups = int(min(2 * numba.get_num_threads(), max(1, n // 64)))
            group, candidates = pick_seeds(self.centres, usable, tex, n_groups)
        for g in range(n_groups):
            for i in candidates[g]:
                if self._seed(dspl, dinv, raw_def, st, done, i, search_centre):
                    break
        self._propagate(dspl, dinv, st, done, group, n_groups)
        # points of bands whose seeds failed, and failed points: global pass
        self._retry_failed(dspl, dinv, st, done, group)
        # disconnected leftovers: new seeds among them (a few attempts)
        for _ in range(5):
            left = np.flatnonzero(~done & usable)
            if left.size == 0:
                break
            best = left[np.argmax(tex[left])]
            ok = self._seed(dspl, dinv, raw_def, st, done, int(best), search_centre)
            done[best] = True
            if ok:
                self._propagate(dspl, dinv, st, done, group, 0)
        self._fill_unreached(dspl, dinv, st, done)
        st.sigma *= self._sigma_scale()[:, None]
        return st

    def _sigma_scale(self) -> np.ndarray:
        """Per-point factor on the IC-GN's ``sigma^2 H^-1`` uncertainty (N,): the points'
        kappa (:meth:`_kappa_of_points`)."""
        return self._kappa_of_points()

    def _kappa_of_points(self) -> np.ndarray:
        """Per-point ``kappa`` (N,), computed once per reference: the IC-GN's step factor
        (see :func:`jointwear.dic.icgn._solve._iterate`) and the factor on its
        ``sigma^2 H^-1`` uncertainty.

        The Jacobian uses central-difference gradients ``g_c`` (less biased, see
        :mod:`jointwear.dic.icgn._interp`), which on fine speckle are smaller than the interpolant's
        true gradient ``g_s``; the solution's actual covariance is then the sandwich
        ``s2 H_cs^-1 H_cc H_cs^-T``, about ``kappa^2`` times ``s2 H_cc^-1`` with
        ``kappa = sum |g_c|^2 / sum g_c . g_s`` over the subset (< 1; without it the reported
        uncertainty exceeds the scatter by 1.2-1.3 on 3-4 px speckle).
        """
        if getattr(self, "_kappa", None) is None:
            from jointwear.dic.icgn import subset_kappa

            r = self.ref
            k = np.ones(self.n_points)
            subset_kappa(r.coef, r.order, r.gx, r.gy, self.centres, self.params.half, k)
            self._kappa = np.clip(np.nan_to_num(k, nan=1.0), 0.5, 1.5)
        return self._kappa

    def check_seeds(self, seed_points) -> np.ndarray:
        """Seed points as a (K, 2) array of ``(x, y)`` [pixel] inside the reference image, or a
        BadInputError naming the first one that is not."""
        seeds = np.asarray(seed_points, dtype=float)
        if seeds.ndim == 1 and seeds.size == 2:
            seeds = seeds[None, :]
        if seeds.ndim != 2 or seeds.shape[1] != 2 or seeds.shape[0] == 0:
            raise BadInputError(
                f"seed_points: expected (K, 2) positions (x, y) [pixel], got shape {seeds.shape}"
            )
        h, w = self.ref.shape
        bad = ~(
            np.isfinite(seeds).all(axis=1)
            & (seeds[:, 0] >= 0)
            & (seeds[:, 0] <= w - 1)
            & (seeds[:, 1] >= 0)
            & (seeds[:, 1] <= h - 1)
        )
        if bad.any():
            x, y = seeds[np.argmax(bad)]
            raise BadInputError(
                f"seed point ({x:g}, {y:g}) [pixel] lies outside the {w}x{h} reference image "
                f"(x in 0..{w - 1}, y in 0..{h - 1}); give seeds on the specimen"
            )
        return seeds

    def _match_some(self, deformed, guess: np.ndarray, idx: np.ndarray) -> MatchResult:
        """Refine only the points ``idx`` from ``guess`` (N, 6) affine guesses; no retries.

        Returns their results (len(idx) rows). Used by trackers to correct a prediction from
        a few probe points before matching all of them.
        """
        dspl, dinv, _ = self._prepare_deformed(deformed)
        n = self.n_points
        st = MatchResult(
            params=self._guess_array(guess),
            zncc=np.full(n, np.nan),
            iterations=np.zeros(n, dtype=np.int32),
            flag=np.full(n, _flags.FLAG_NOT_REACHED, dtype=np.int8),
        )
        active = np.zeros(n, dtype=np.bool_)
        active[idx] = True
        active &= np.isfinite(st.params).all(axis=1)
        st.params[~active] = 0.0
        self._run_many(dspl, dinv, st.params, active, st)
        return MatchResult(st.params[idx], st.zncc[idx], st.iterations[idx], st.flag[idx])

    def _fill_unreached(self, dspl, dinv, st, done) -> None:
        """Points never reached: one attempt from the nearest good point's extrapolated
        parameters (or zero), so that each gets a real outcome and flag."""
        rest = ~done
        if not rest.any():
            return
        P0 = np.zeros((self.n_points, 12))
        good = np.flatnonzero(st.ok)
        if good.size:
            from scipy.spatial import cKDTree

            idx = np.flatnonzero(rest & np.isfinite(self.centres).all(axis=1))
            if idx.size:
                _, near = cKDTree(self.centres[good]).query(self.centres[idx])
                src = good[near]
                from jointwear.dic.icgn._match import _extrapolate

                for j, i in zip(idx, src, strict=True):
                    d = self.centres[j] - self.centres[i]
                    _extrapolate(st.params[i], d[0], d[1], P0[j])
        sub = MatchResult(P0, st.zncc.copy(), st.iterations.copy(), st.flag.copy())
        self._run_many(dspl, dinv, P0, rest, sub)
        st.sigma[rest] = sub.sigma[rest]
        st.params[rest] = P0[rest]
        st.zncc[rest] = sub.zncc[rest]
        st.iterations[rest] = sub.iterations[rest]
        st.flag[rest] = sub.flag[rest]
        done[rest] = True

    def _guess_array(self, guess) -> np.ndarray:
        g = np.asarray(guess, dtype=float)
        n = self.n_points
        if g.ndim == 1 and g.size in (2, 6, 12):
            g = np.broadcast_to(g, (n, g.size))
        elif g.ndim == 2 and g.shape[0] == 1 and g.shape[1] in (2, 6, 12):
            g = np.broadcast_to(g, (n, g.shape[1]))  # one row is broadcast, as documented
        if g.ndim != 2 or g.shape[0] != n or g.shape[1] not in (2, 6, 12):
            raise BadInputError(
                f"initial_guess: expected shape ({n}, 2) displacements (u, v) [pixel], ({n}, 6) "
                f"affine (u, du/dx, du/dy, v, dv/dx, dv/dy) or ({n}, 12) shape parameters; got "
                f"{g.shape}"
            )
        out = np.zeros((n, 12))
        if g.shape[1] == 2:
            out[:, 0], out[:, 6] = g[:, 0], g[:, 1]
        elif g.shape[1] == 6:
            out[:, _flags.AFFINE_INDEX] = g
        else:
            out[:] = g
        return out

    def correlate(
        self,
        deformed,
        *,
        initial_guess: np.ndarray | None = None,
        seed_points: np.ndarray | None = None,
    ) -> xr.Dataset:
        """Correlate a deformed image with the prepared reference.

        Parameters
        ----------
        deformed : ndarray (H, W)
            Deformed image, same size and dtype as the reference.
        initial_guess : ndarray, optional
            Per-point guesses: (N, 2) ``(u, v)`` [pixel], (N, 6) affine or (N, 12) parameters;
            a single row is broadcast. Rows with NaN are filled by propagation from converged
            neighbours.
        seed_points : ndarray (K, 2), optional
            Positions ``(x, y)`` [pixel] to start the propagation from (default: automatic,
            well-textured points in bands of rows).

        Returns
        -------
        Dataset
            See :func:`jointwear.dic.correlate`.
        """
        res = self.match(deformed, initial_guess=initial_guess, seed_points=seed_points)
        return self.to_dataset(res)

    # ------------------------------------------------------------------ output
    def to_record(self, res: MatchResult) -> Record:
        """Package a :class:`MatchResult` as the arrays of :meth:`to_dataset` (a
        :class:`~jointwear._netcdf.Record`, no xarray)."""
        return result_record(
            self.centres,
            res.params,
            res.zncc,
            res.iterations,
            res.flag,
            self.params,
            self.grid,
            sigma=res.sigma,
        )

    def to_dataset(self, res: MatchResult) -> xr.Dataset:
        """Package a :class:`MatchResult` as an xarray Dataset (grid ``(y, x)`` or ``point``)."""
        return self.to_record(res).to_dataset()
