"""Numerical uncertainty from a refinement study: the Grid Convergence Index (Roache; Celik et al.).

A verification study repeats the simulation with a refinement parameter ``h`` made finer (grid
step, time step, tolerance of the adaptive wear update, ...) and records the quantities of
interest. From the three finest solutions ``f1`` (finest), ``f2``, ``f3`` with refinement ratios
``r21 = h2 / h1`` and ``r32 = h3 / h2`` (Celik et al. 2008, the ASME J. Fluids Eng. procedure):

* ``e21 = f2 - f1``, ``e32 = f3 - f2``; the convergence ratio ``R = e21 / e32`` decides the
  case: ``0 < R < 1`` monotone convergence (the only case a GCI is computed for),
  ``R < 0`` oscillatory, ``R >= 1`` divergence, ``e21 = 0`` or ``e32 = 0`` undecidable;
* the observed order ``p`` solves ``p = |ln|e32 / e21| + q(p)| / ln r21`` with
  ``q(p) = ln((r21^p - s) / (r32^p - s))``, ``s = sign(e32 / e21)`` (fixed-point iteration;
  ``q = 0`` for a constant ratio);
* the order used is capped at the formal order of the scheme, ``p_u = min(p, p_formal)``: an
  observed order above it (three solutions changing by 1 % with ``p = 6``) would claim an
  accuracy the scheme does not have;
* the factor of safety is ``Fs = 1.25`` only when the observed order is credible,
  ``0.5 <= p < p_formal + 0.1`` (Eça & Hoekstra 2014's range, scaled to the formal order);
  otherwise ``Fs = 3`` (Roache's value for an unconfirmed order);
* the extrapolated value ``f_ext = (r21^p_u f1 - f2) / (r21^p_u - 1)``, the relative error
  ``e_a = |(f1 - f2) / f1|`` and ``GCI_fine = Fs e_a / (r21^p_u - 1)``.

The formal order comes from the refinement coordinate's (or the dataset's) ``formal_order``
attribute; without one it is taken as 1 (the explicit update of the wear in cycles is first
order; a lower cap only makes the uncertainty larger) and the description says so.

With **four or more** solutions :func:`refinement_study` (and so :func:`numerical_uncertainty`)
takes Eça & Hoekstra's least-squares procedure instead (:func:`jointwear.refinement.eca_hoekstra`,
deterministic solutions): it fits every level, so a quantity whose solutions scatter or
oscillate with refinement - the RMS of a motion with impacts, over solver tolerances - gets an
uncertainty that covers the scatter (the data-range branch, ``Fs = 3``) instead of none. The
GCI's refusals stand for three solutions, which cannot tell scatter from a trend.

The GCI is an expanded (about 95 %) uncertainty; it is converted to the standard numerical
uncertainty by the project's one rule for such bounds, ``u_num = GCI / 2``
(:data:`jointwear.refinement.COVERAGE_K`, k = 2 of the GUM for about 95 %; the same factor as
Eça & Hoekstra's ``U_phi``, so three and four levels of the same data agree; ASME V&V 20's
alternative GCI / 1.15 is not used, see there). Two solutions cannot show that the sequence
converges and an oscillating or diverging one has no order: those are *not assessed*, with the
reason, never a number.

References
----------
- Roache, P. J. (1998). *Verification and Validation in Computational Science and
  Engineering*. Hermosa, Albuquerque.
- Celik, I. B., Ghia, U., Roache, P. J., Freitas, C. J., Coleman, H., Raad, P. E. (2008).
  Procedure for estimation and reporting of uncertainty due to discretization in CFD
  applications. *J. Fluids Eng.* 130, 078001.
- ASME V&V 20-2009 (R2021), section 2-4.
- Eça, L., Hoekstra, M. (2014). A procedure for the estimation of the numerical uncertainty of
  CFD calculations based on grid refinement studies. *J. Comput. Phys.* 262, 104-130.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import xarray as xr

from jointwear.errors import BadInputError
from jointwear.refinement import COVERAGE_K

__all__ = [
    "GCI",
    "GCI_TO_STANDARD",
    "LeastSquaresStudy",
    "gci",
    "numerical_uncertainty",
    "refinement_study",
]

#: standard numerical uncertainty = GCI / GCI_TO_STANDARD: the one rule for a ~95 % bound
GCI_TO_STANDARD = COVERAGE_K


@dataclass(frozen=True)
class GCI:
    """Result of a grid-convergence study of one quantity.

    Attributes
    ----------
    quantity : str
        Name of the studied quantity.
    assessed : bool
        True when the three finest solutions converge monotonically and a GCI was computed.
    reason : str
        Why the numerical uncertainty is not assessed ('' when it is).
    h : tuple of float
        Refinement parameter of the solutions used, finest first [units of the study].
    values : tuple of float
        The solutions used, finest first [units of the quantity].
    convergence_ratio : float
        ``R = (f2 - f1) / (f3 - f2)`` (NaN when undefined).
    order : float
        Observed order of convergence ``p`` [1] (NaN when not assessed).
    order_used : float
        ``min(p, formal_order)``, the order the GCI is computed with [1].
    formal_order : float
        Formal order of the refined scheme [1].
    formal_order_note : str
        Where the formal order came from.
    extrapolated : float
        Richardson-extrapolated value ``f_ext`` (NaN when not assessed).
    relative_error : float
        ``e_a = |(f1 - f2) / f1|`` [1].
    gci_fine : float
        Relative GCI of the finest solution [1] (NaN when not assessed).
    u_num_rel : float
        Relative standard numerical uncertainty ``GCI / 2`` (:data:`GCI_TO_STANDARD`) [1]
        (NaN when not assessed).
    safety_factor : float
        ``Fs`` used.
    """

    quantity: str
    assessed: bool
    reason: str
    h: tuple[float, ...]
    values: tuple[float, ...]
    convergence_ratio: float
    order: float
    extrapolated: float
    relative_error: float
    gci_fine: float
    u_num_rel: float
    safety_factor: float
    order_used: float = float("nan")
    formal_order: float = 1.0
    formal_order_note: str = "stated"
    refined: str = "h"

    @property
    def covers(self) -> frozenset[str]:
        """Error sources the study accounts for (beyond the refinement of ``refined`` itself)."""
        return _covers(self.refined)

    def describe(self) -> str:
        """One line for the report: the method and its figures, or why it was not assessed."""
        seq = " → ".join(f"{v:.4g}" for v in self.values[::-1])
        if not self.assessed:
            return f"{self.quantity}: not assessed - {self.reason} (coarse to fine: {seq})"
        cap = (
            f", capped at the formal order {self.formal_order:g} ({self.formal_order_note})"
            if self.order > self.formal_order
            else f" (formal order {self.formal_order:g}, {self.formal_order_note})"
        )
        credible = "p credible" if self.safety_factor == 1.25 else "p not credible"
        return (
            f"{self.quantity}: GCI (Roache; Celik et al. 2008), observed order p = "
            f"{self.order:.2f}{cap}, {credible}: Fs = {self.safety_factor:g}, "
            f"R = {self.convergence_ratio:.3g}, "
            f"GCI_fine = {self.gci_fine:.3g} -> u_num = GCI/{GCI_TO_STANDARD:g} = "
            f"{self.u_num_rel:.3g}·|S| (coarse to fine: {seq})"
        )


def _covers(refined: str) -> frozenset[str]:
    name = refined.lower()
    if any(key in name for key in UPDATE_INTERVAL_NAMES):
        return frozenset({"wear-update interval"})
    return frozenset()


@dataclass(frozen=True)
class LeastSquaresStudy:
    """Numerical uncertainty of one quantity from four or more deterministic solutions.

    The result of Eça & Hoekstra's least-squares procedure
    (:func:`jointwear.refinement.eca_hoekstra`), read like a :class:`GCI` (``assessed``,
    ``reason``, ``values`` finest first, ``u_num_rel``, ``covers``, ``describe``).

    Attributes
    ----------
    fit : RefinementFit
        The procedure's result (absolute uncertainties, k = 1).
    refined : str
        Name of the refinement parameter.
    """

    fit: Any
    refined: str = "h"

    @property
    def quantity(self) -> str:
        return self.fit.quantity

    @property
    def assessed(self) -> bool:
        return bool(self.fit.assessed) and math.isfinite(self.u_num_rel)

    @property
    def reason(self) -> str:
        if self.fit.assessed and not math.isfinite(self.u_num_rel):
            return "the finest solution is 0: a relative uncertainty is undefined"
        return self.fit.reason if not self.fit.assessed else ""

    @property
    def h(self) -> tuple[float, ...]:
        return self.fit.h

    @property
    def values(self) -> tuple[float, ...]:
        return self.fit.means

    @property
    def u_num_rel(self) -> float:
        """Standard numerical uncertainty of the finest solution relative to it [1]."""
        value = abs(self.fit.value)
        return self.fit.u_num / value if value > 0 else float("nan")

    @property
    def covers(self) -> frozenset[str]:
        return _covers(self.refined)

    def describe(self) -> str:
        return (
            f"least squares over {len(self.fit.h)} levels of {self.refined} "
            f"(Eça & Hoekstra 2014): {self.fit.describe()}; u_num = {self.u_num_rel:.3g}·|S|"
            if self.assessed
            else self.fit.describe()
        )


def refinement_study(
    h: Sequence[float], values: Sequence[float], **options: Any
) -> GCI | LeastSquaresStudy:
    """Numerical uncertainty of the finest of deterministic solutions over a refinement ``h``.

    The GCI (:func:`gci`) of three solutions; with four or more finite ones, Eça & Hoekstra's
    least squares (:func:`jointwear.refinement.eca_hoekstra`), which fits them all and covers
    their scatter.

    Parameters
    ----------
    h, values : sequence of float
        As :func:`gci`.
    **options
        ``quantity``, ``formal_order``, ``formal_order_note``, ``refined``: as :func:`gci`,
        with its defaults.
    """
    from jointwear.refinement import eca_hoekstra

    unknown = set(options) - set(gci.__kwdefaults__ or {})
    if unknown:
        raise TypeError(f"refinement_study: unknown options {sorted(unknown)}")
    h_arr = np.asarray(h, dtype=float)
    f_arr = np.asarray(values, dtype=float)
    ok = np.isfinite(f_arr) if f_arr.shape == h_arr.shape else np.zeros(0, bool)
    if ok.sum() < 4:
        return gci(h, values, **options)
    o = {**(gci.__kwdefaults__ or {}), **options}
    fit = eca_hoekstra(h_arr[ok], f_arr[ok], formal_order=o["formal_order"], quantity=o["quantity"])
    return LeastSquaresStudy(fit, o["refined"])


def _not_assessed(quantity, reason, h, f, ratio=float("nan"), e_a=float("nan"), fs=1.25) -> GCI:
    nan = float("nan")
    return GCI(quantity, False, reason, tuple(h), tuple(f), ratio, nan, nan, e_a, nan, nan, fs)


def _order(r21: float, r32: float, e21: float, e32: float) -> float:
    s = math.copysign(1.0, e32 / e21)
    ln_ratio = math.log(abs(e32 / e21))
    p = abs(ln_ratio) / math.log(r21)
    for _ in range(200):
        q = math.log((r21**p - s) / (r32**p - s))
        p_new = abs(ln_ratio + q) / math.log(r21)
        if abs(p_new - p) < 1e-12 * max(1.0, p):
            return p_new
        p = p_new
    return float("nan")


#: refinement coordinates that refine the wear-update interval (what sim wear's _u also covers)
UPDATE_INTERVAL_NAMES = ("update_tolerance", "update_dn", "update_interval", "delta_n", "dn")

#: Eça & Hoekstra's credible range of the observed order, as a fraction/offset of the formal one
CREDIBLE_MIN_ORDER = 0.5
CREDIBLE_ABOVE_FORMAL = 0.1
FS_CREDIBLE = 1.25
FS_NOT_CREDIBLE = 3.0


def gci(
    h: Sequence[float],
    values: Sequence[float],
    *,
    quantity: str = "quantity",
    formal_order: float = 1.0,
    formal_order_note: str = "stated",
    refined: str = "h",
) -> GCI:
    """Grid Convergence Index of a quantity from a refinement sequence (three finest solutions).

    Parameters
    ----------
    h : sequence of float
        Refinement parameter of each solution (grid step, time step, tolerance), > 0; smaller
        is finer. Any order.
    values : sequence of float
        The quantity computed with each ``h`` [any unit].
    quantity : str
        Name used in messages.
    formal_order : float
        Formal order of accuracy of the refined scheme [1], > 0: the cap of the order used.
    formal_order_note : str
        Where ``formal_order`` comes from (for the description).
    refined : str
        Name of the refinement parameter (what the study covers).

    Returns
    -------
    GCI
        ``assessed`` False (with the reason) unless the three finest solutions converge
        monotonically with refinement ratios > 1.
    """
    if not (math.isfinite(formal_order) and formal_order > 0):
        raise BadInputError(
            f"verification of {quantity}: formal_order must be a number > 0, got {formal_order!r}"
        )
    safety_factor = FS_NOT_CREDIBLE
    h_arr = np.asarray(h, dtype=float)
    f_arr = np.asarray(values, dtype=float)
    if h_arr.shape != f_arr.shape or h_arr.ndim != 1:
        raise BadInputError(
            f"verification of {quantity}: {h_arr.size} refinement values for {f_arr.size} solutions"
        )
    ok = np.isfinite(h_arr) & np.isfinite(f_arr)
    h_arr, f_arr = h_arr[ok], f_arr[ok]
    order = np.argsort(h_arr)
    h_arr, f_arr = h_arr[order], f_arr[order]
    if np.any(h_arr <= 0):
        raise BadInputError(f"verification of {quantity}: the refinement parameter must be > 0")
    if np.any(np.diff(h_arr) <= 0):
        raise BadInputError(
            f"verification of {quantity}: two solutions share the refinement value "
            f"{h_arr[np.argmin(np.diff(h_arr))]:g}; each solution needs its own"
        )
    if h_arr.size < 3:
        return _not_assessed(
            quantity,
            f"{h_arr.size} solution(s): three are needed to show monotone convergence and an "
            "observed order",
            h_arr,
            f_arr,
            fs=safety_factor,
        )
    (h1, h2, h3), (f1, f2, f3) = h_arr[:3], f_arr[:3]
    r21, r32 = h2 / h1, h3 / h2
    e21, e32 = f2 - f1, f3 - f2
    e_a = abs(e21 / f1) if f1 != 0 else float("nan")
    if e21 == 0 or e32 == 0:
        return _not_assessed(
            quantity,
            "two successive solutions are identical, the order of convergence is undefined",
            h_arr[:3],
            f_arr[:3],
            e_a=e_a,
            fs=safety_factor,
        )
    ratio = e21 / e32
    if ratio < 0:
        return _not_assessed(
            quantity,
            f"the solutions oscillate with refinement (convergence ratio R = {ratio:.3g} < 0)",
            h_arr[:3],
            f_arr[:3],
            ratio,
            e_a,
            safety_factor,
        )
    if ratio >= 1:
        return _not_assessed(
            quantity,
            f"the solutions do not converge with refinement (convergence ratio R = {ratio:.3g} "
            ">= 1: the finest step changes the result as much as or more than the previous one)",
            h_arr[:3],
            f_arr[:3],
            ratio,
            e_a,
            safety_factor,
        )
    p = _order(r21, r32, e21, e32)
    if not np.isfinite(p) or p <= 0:
        return _not_assessed(
            quantity,
            "the observed order of convergence could not be determined",
            h_arr[:3],
            f_arr[:3],
            ratio,
            e_a,
            safety_factor,
        )
    credible = CREDIBLE_MIN_ORDER <= p < formal_order + CREDIBLE_ABOVE_FORMAL * formal_order
    safety_factor = FS_CREDIBLE if credible else FS_NOT_CREDIBLE
    p_used = min(p, formal_order)
    rp = r21**p_used
    f_ext = (rp * f1 - f2) / (rp - 1)
    g = safety_factor * e_a / (rp - 1)
    return GCI(
        quantity,
        True,
        "",
        tuple(h_arr[:3]),
        tuple(f_arr[:3]),
        ratio,
        p,
        f_ext,
        e_a,
        g,
        g / GCI_TO_STANDARD,
        safety_factor,
        p_used,
        float(formal_order),
        formal_order_note,
        refined,
    )


def _formal_order(ds: xr.Dataset, dim: str) -> tuple[float, str]:
    for where, attrs in ((f"attribute of '{dim}'", ds[dim].attrs), ("dataset attribute", ds.attrs)):
        if "formal_order" in attrs:
            try:
                return float(attrs["formal_order"]), f"formal_order {where}"
            except (TypeError, ValueError):
                raise BadInputError(
                    f"verification data: formal_order {attrs['formal_order']!r} ({where}) is "
                    "not a number"
                ) from None
    return 1.0, "not stated: taken as 1, the first-order wear update"


def numerical_uncertainty(
    studies: xr.Dataset | Sequence[xr.Dataset],
) -> Mapping[str, GCI | LeastSquaresStudy]:
    """Numerical uncertainty of every 1-D quantity of one or more verification datasets.

    The GCI of three solutions, Eça & Hoekstra's least squares of four or more
    (:func:`refinement_study`).

    Parameters
    ----------
    studies : Dataset or sequence of Datasets
        Verification data: each quantity (``max_wear_depth``, ``worn_volume``,
        ``cylindricity``, ...) over one refinement dimension whose coordinate holds ``h`` (> 0,
        smaller = finer), e.g. ``update_tolerance`` or ``dN``.

    Returns
    -------
    dict
        Quantity name -> :class:`GCI` or :class:`LeastSquaresStudy`.
    """
    items = [studies] if isinstance(studies, xr.Dataset) else list(studies)
    out: dict[str, GCI | LeastSquaresStudy] = {}
    for ds in items:
        for name, var in ds.data_vars.items():
            if var.ndim != 1 or var.dtype.kind not in "fiu":
                continue
            dim = var.dims[0]
            if dim not in ds.coords:
                raise BadInputError(
                    f"verification data: '{name}' varies over '{dim}', which has no coordinate "
                    "values (the refinement parameter h of each solution)"
                )
            order, note = _formal_order(ds, str(dim))
            out[str(name)] = refinement_study(
                np.asarray(ds[dim].values, dtype=float),
                np.asarray(var.values, dtype=float),
                quantity=str(name),
                formal_order=order,
                formal_order_note=note,
                refined=str(dim),
            )
    return out
