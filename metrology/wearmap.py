"""Wear maps: wear depth over (z, theta) from a worn scan and a reference.

Two ways to get the unworn reference
------------------------------------
* **With a before-wear scan** of the same bearing: both scans are put in the canonical angle
  convention, the before-scan is rotated by the set-up's angular offset (or, only if asked, by
  the offset found by registering the unworn regions) and interpolated onto the worn scan's
  grid. The difference d = r_worn - r_before still contains the change of set-up (the part is
  re-mounted: a different eccentricity and tilt, and for deviation data an unknown radius
  offset), so a limaçon cylinder c + (x0 + tx z) cos(theta) + (y0 + ty z) sin(theta) is fitted to
  d on the *unworn* points and removed. The bore's own form errors cancel in d.
  Each scan is re-centred exactly on its axis first (:mod:`._wear_setup`), and the faint wear
  tails next to the worn region are tested band by band (:func:`._wear_fit._exclude_tails`).
* **Without one**: the form model of :mod:`~jointwear.metrology.baseline` (or a cylinder, or one
  circle per layer, ``shape="circle"``) is fitted by least squares to the unworn part of the
  worn scan itself; what the model does not hold is counted in the uncertainty.

How the unworn part is chosen: unless given explicitly (``unworn``), it is found iteratively.
Start with all points; fit the reference; estimate the scatter of the residuals of the current
unworn set robustly (1.4826 x median absolute deviation); call unworn the points whose residual
lies within ``threshold`` times that scatter of the median; refit; repeat until the set no longer
changes. Worn points (material removed) sit far on one side and drop out after one or two
rounds; once the worn region is found, the noise is rejected symmetrically about its centre (a
one-sided cut keeps the low tail of the noise only, and every depth reads high). This assumes that a part of the bore is unworn (true for a journal bearing loaded on one
side); if wear covers the whole circumference, pass a before-scan.

Uncertainty: ``wear_depth_u`` [m] combines in quadrature the RMS residual of the unworn points
(noise of both scans, unmodelled form and misalignment: how far an unworn point's "wear" scatters
about 0) with the standard error of the fitted reference at each point; with a before-scan,
also the dependence on the unworn selection and the largest faint wear tail the band test
cannot see (:func:`._wear_fit.undetected_tail`) and, where the bore is worn nearly all round,
the wear its selection cannot see on the unworn points (:mod:`._wear_unseen`: such a map is
refused only where that bound exceeds 30 % of the volume or the maximum depth). Without one, a
map is refused where such a tail could change the volume by more than 30 % (the form model
absorbs it).
``wear_depth_u_random`` [m] states the part of ``wear_depth_u`` that is independent from point
to point (the instrument noise estimate): it averages down when the map is averaged over cells
(:func:`jointwear.compare.align_wear_maps`), the rest does not.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from jointwear.conventions import (
    CANONICAL,
    angle_convention_of,
    convert_theta,
)
from jointwear.errors import BadInputError
from jointwear.metrology._wear_fit import (
    _basis,
    _design_sum,
    _exclude_tails,
    _lsq,
    _reference,
    _robust_reference,
    undetected_tail,
)
from jointwear.metrology._wear_output import (
    _cylindricities,
    _lobing_rms,
    _model_order_term,
    _scalars,
    _separable,
    random_part,
    reference_bias_terms,
    refuse_inseparable_difference,
    selection_term,
    tail_term,
    wear_dataset,
)
from jointwear.metrology._wear_setup import (
    _axis,
    _recentre,
    _rotate,
    before_on_layers,
    exact_difference,
    register_angle,
    registered_offset,
)
from jointwear.metrology._wear_unseen import (
    STRUCTURE_SHARE,
    exposed,
    refuse_by_consequence,
    smooth_structure,
    unseen_bound,
    unseen_level,
    unseen_term,
    unworn_arcs,
)
from jointwear.metrology.baseline import FormBasis, correlation_length, noise_sigma
from jointwear.metrology.choices import UNWORN_THRESHOLD, WEAR_SHAPE, WEAR_SHAPES
from jointwear.metrology.form import SCAN_VARIABLES, scan_variable
from jointwear.metrology.wear_quantities import derived_quantities

__all__ = ["wear_map", "worn_volume", "register_angle"]


def _radius_var(ds: xr.Dataset | xr.DataArray, what: str) -> tuple[xr.DataArray, str]:
    if isinstance(ds, xr.DataArray):
        name = str(ds.name) if ds.name in SCAN_VARIABLES else "radius"
        da = ds
    else:
        da, name = scan_variable(ds, what)
    if set(da.dims) != {"z", "theta"}:
        raise BadInputError(f"{what}: '{name}' must have dims (z, theta), found {da.dims}")
    units = da.attrs.get("units", "m")
    if units != "m":
        raise BadInputError(f"{what}: '{name}' has units {units!r}; expected 'm' (SI)")
    angle_convention_of(da, what=what)
    da = convert_theta(da, CANONICAL).transpose("z", "theta")
    return da, name


def _theta_weights(theta: np.ndarray) -> np.ndarray:
    """Periodic trapezoid weights [rad] for angles ``theta`` [degree] (sorted)."""
    th = np.radians(np.sort(theta))
    gaps = np.diff(np.concatenate([th, th[:1] + 2 * np.pi]))
    return 0.5 * (gaps + np.roll(gaps, 1))


def _z_weights(z: np.ndarray) -> np.ndarray:
    """Trapezoid weights [m] over the measured z range (one layer: weight 1 m -> per metre)."""
    if z.size == 1:
        return np.ones(1)
    w = np.zeros_like(z)
    d = np.diff(z)
    w[:-1] += 0.5 * d
    w[1:] += 0.5 * d
    return np.abs(w)


def worn_volume(
    wear_depth: np.ndarray, z: np.ndarray, theta_deg: np.ndarray, radius: float
) -> float:
    """Volume of removed material over the measured band [m^3].

    V = integral of h(z, theta) R dtheta dz (trapezoid in z between the first and last layer,
    periodic trapezoid in theta); R the bore radius [m], h the wear depth [m] (NaN ignored).
    """
    h = np.nan_to_num(np.asarray(wear_depth, dtype=float))
    w = _z_weights(np.asarray(z, dtype=float))[:, None] * _theta_weights(theta_deg)[None, :]
    return float(radius * np.sum(w * h))


def wear_map(
    worn: xr.Dataset | xr.DataArray,
    before: xr.Dataset | xr.DataArray | None = None,
    *,
    angle_offset_deg: float = 0.0,
    register: bool = False,
    shape: str = WEAR_SHAPE,
    threshold: float = UNWORN_THRESHOLD,
    unworn: np.ndarray | xr.DataArray | None = None,
    unworn_z=None,
    surface: str = "bore",
    radius: float | None = None,
    margin_deg: float | None = None,
    exact_centring: bool = True,
    max_iter: int = 30,
    harmonics: int = 4,
    axial_degree: int = 2,
) -> xr.Dataset:
    """Wear depth over (z, theta) from a worn scan and a before-scan or a fitted reference.

    Parameters
    ----------
    worn : Dataset or DataArray
        Worn scan: ``radius`` or ``radial_deviation`` [m] over (``z`` [m], ``theta`` [degree]);
        theta must state its angle convention.
    before : Dataset or DataArray, optional
        Scan of the same bearing before wear, same layers (z values within 1 µm or inside the
        worn scan's z range for interpolation). Without it the reference is fitted to the
        unworn part of the worn scan (see the module docstring).
    angle_offset_deg : float
        Set-up rotation [degree, canonical convention]: a feature at theta in the before-scan is
        at theta + offset in the worn scan.
    register : bool
        Estimate the offset by correlating the unworn regions instead (added to
        ``angle_offset_deg``). Only when asked.
    shape : {"auto", "cylinder", "circle", "form"}
        Reference fitted to the unworn points: a limaçon cylinder (centre and tilt), one circle
        per layer, or the form model of :mod:`~jointwear.metrology.baseline` (a centre per layer,
        taper/barrel and lobing smooth in z). ``auto``: cylinder with a before-scan (the form
        cancels in the difference), form without one.
    harmonics, axial_degree : int
        Highest lobing harmonic and degree in z of the form model (``shape="form"``).
    threshold : float
        Unworn points lie within ``threshold`` robust standard deviations of the reference.
    unworn : bool array (z, theta) or sequence of (start, end), optional
        Explicit unworn mask (canonical theta order of the worn scan), or the theta arcs
        [degree, canonical convention; start > end wraps through 0] whose points are unworn
        (CLI ``--unworn 200:330``); skips the iteration.
    unworn_z : sequence of (start, end), optional
        z ranges [m] whose points are unworn (with ``unworn`` arcs: both must hold; CLI
        ``--unworn-z-mm``).
    surface : {"bore", "shaft"}
        A bore's radius grows with wear, a shaft's shrinks; wear depth is positive for material
        removed in both.
    radius : float, optional
        Bore radius for the worn volume [m]; by default the mean worn radius (``radius`` data) or
        the ``nominal_radius`` attribute (deviation data).
    margin_deg : float, optional
        Points within this angle [degree] of a worn region are not used as unworn reference
        (default 5, or 15 for the form model, where faint wear tails would bias the form).
    exact_centring : bool
        Re-centre each scan exactly on its own axis before differencing (needs the bore radius:
        ``radius`` data, the ``nominal_radius`` attribute or ``radius=``); removes the
        set-up's second-order term e^2/(4R) that the limaçon leaves.
    max_iter : int
        Maximum rounds of the unworn-region iteration.

    Returns
    -------
    Dataset
        ``wear_depth`` and ``wear_depth_u`` [m] over (z, theta) in the canonical convention,
        ``wear_depth_u_random`` [m] (its point-to-point independent part), ``unworn`` (flag: 1 if the point was used as unworn reference), scalars
        ``worn_volume`` and ``worn_volume_u`` [m^3], ``cylindricity_before`` and
        ``cylindricity_after`` [m] (MZ), ``angle_offset`` [degree]; method in attrs.
    """
    shape, margin_deg = _options(shape, before, margin_deg, surface, threshold)
    w, wname = _radius_var(worn, "worn scan")
    z = np.asarray(w["z"].values, dtype=float)
    th = np.asarray(w["theta"].values, dtype=float)
    rw = np.asarray(w.values, dtype=float)
    sign = 1.0 if surface == "bore" else -1.0
    X = FormBasis(z, th, harmonics, axial_degree) if shape == "form" else _basis(z, th, shape)
    mask_in = _mask_in(unworn, rw.shape, z, th, unworn_z)
    method = _method(shape, X, before is not None)
    fit_args = (threshold, mask_in, max_iter, margin_deg)
    offset = float(angle_offset_deg)
    rbz = thb = None
    if before is not None:
        b, bname = _radius_var(before, "before scan")
        thb = np.asarray(b["theta"].values, dtype=float)
        rbz = before_on_layers(
            z, np.asarray(b["z"].values, dtype=float), thb, np.asarray(b.values, dtype=float)
        )
        if register:
            Xcyl = X if shape == "cylinder" else _basis(z, th, "cylinder")
            offset = registered_offset(rw, rbz, z, th, thb, X, Xcyl, sign, offset, fit_args)
        d = sign * (rw - _rotate(th, thb, rbz, offset)).ravel()
    elif register:
        raise BadInputError("wear_map: register=True needs a before scan")
    else:
        d = sign * rw.ravel()
    X, fit, alt, first = _reference(d, X, shape, z, th, harmonics, *fit_args, rbz is not None)
    resid, mask, var_fit, s2, n_iter = fit
    # exact centring: the limaçon leaves each scan's e^2/(4R) second harmonic, which differs
    # between set-ups; with the bore radius known, re-centre each scan exactly on its axis
    r0_w = 0.0 if wname == "radius" else (radius or _attr_radius(worn, w))
    centring = _centring_note(exact_centring, X, r0_w, rbz is not None)
    if exact_centring and r0_w is not None and not isinstance(X, FormBasis):
        if rbz is not None:
            r0_b = 0.0 if bname == "radius" else (radius or _attr_radius(before, b) or r0_w)
            rb_abs = _rotate(th, thb, rbz, offset) + r0_b
            d = exact_difference(rw + r0_w, rb_abs, z, th, mask, sign)
        else:
            rw_c = _recentre(rw + r0_w, z, th, _axis(rw + r0_w, z, th, mask))
            d = sign * (rw_c - r0_w).ravel()
        X, fit, alt, _ = _reference(d, X, shape, z, th, harmonics, *fit_args, rbz is not None)
        resid, mask, var_fit, s2, n_iter = fit
    tails = _tails_note(mask_in is not None, margin_deg)
    remaining = None
    if mask_in is None and rbz is not None:
        fit, tails, remaining = _without_tails(d, X, mask, rw.shape, th, threshold, margin_deg)
        resid, mask, var_fit, s2, _ = fit
    radius = _volume_radius(radius, wname, rw, worn, w)
    terms = ("selection", "tail") if rbz is not None else ("tail",)
    terms = terms if mask_in is None else ()
    structure = 0.0
    if rbz is not None:  # an explicit mask is tested as well: it may hold wear
        r2 = resid.reshape(rw.shape)
        structure = smooth_structure(
            s2, noise_sigma(r2), correlation_length(r2, mask.reshape(rw.shape))
        )
        noisy = structure > STRUCTURE_SHARE * noise_sigma(r2)
        if remaining is not None or noisy or exposed(mask.reshape(rw.shape)).mean() > 0.01:
            terms += ("unseen",)  # wear spread round the bore: decided by consequence
            remaining = (remaining, structure if noisy else 0.0)
    q, u, tau, noise, tail, unseen = _quantities(
        d, X, fit, alt, z, th, radius, terms, fit_args, remaining
    )
    mask2 = mask.reshape(rw.shape)
    wear = resid.reshape(rw.shape)
    if rbz is not None:
        arcs = unworn_arcs(mask2, th, wear) if mask_in is None else ()
        refuse_inseparable_difference(s2, noise, tau, arcs)
        if unseen is not None:
            refuse_by_consequence(q, *unseen, float(mask.mean()), arcs, mask_in is not None)
    else:
        _refuse_inseparable(q, d, X, fit, noise, threshold, rw.shape)
        _refuse_form_tails(q, tail)
        if first is not None:  # the one-sided search of the worn region must pass as well
            q1 = _quantities(d, X, first[0], first[1], z, th, radius, (), fit_args)[0]
            _refuse_inseparable(q1, d, X, first[0], noise, threshold, rw.shape)
    cyl_after, cyl_before, cyl_before_note = _cylindricities(
        rw, rbz, z, th, thb if rbz is not None else th, mask2
    )
    attrs = {
        "wear_reference": method,
        "unworn_selection": _explicit_note(unworn, unworn_z)
        if mask_in is not None
        else f"iterative: |residual - median| <= {threshold} x 1.4826 MAD ({n_iter} rounds)",
        "n_unworn_points": int(mask.sum()),
        "reference_rms_residual": float(np.sqrt(s2)),
        "residual_correlation_length_samples": float(tau),
        "instrument_noise_estimate": float(noise),
        "volume_radius": float(radius),
        "surface": surface,
        "registered": bool(register),
        "centring": centring,
        "faint_wear_tails": tails,
    }
    scalars = _scalars(q, cyl_before, cyl_after, cyl_before_note, noise)
    extra = dict([random_part(u, noise, tau)])
    out = wear_dataset(z, th, wear, u, mask2, scalars, offset, attrs, extra)
    out.attrs.update(_origin(worn, before))
    return out


def _origin(worn, before) -> dict:
    """The inputs' data_origin: one synthetic scan makes the map synthetic ({} if none)."""
    origins = {str(getattr(o, "attrs", {}).get("data_origin", "")) for o in (worn, before)}
    origins.discard("")
    if not origins:
        return {}
    return {"data_origin": "synthetic" if "synthetic" in origins else sorted(origins)[0]}


def _refuse_inseparable(q, d, X, fit, noise, threshold, shape) -> None:
    """Refuse a map without a before-scan where wear cannot be told from form."""
    resid, mask, _, s2, _ = fit
    lobing = _lobing_rms((d - resid).reshape(shape)) if isinstance(X, FormBasis) else 0.0
    _separable(q, s2, noise, mask.reshape(shape), threshold, lobing)


def _refuse_form_tails(q, tail, limit: float = 0.3) -> None:
    """Refuse a map without a before-scan where faint wear tails that the data cannot tell
    from the form model could change the volume by more than ``limit`` of itself.

    The form model fitted to the unworn part absorbs tails of the wear beyond the margin and
    extrapolates them to the worn side (a shallow groove as wide as the lobes read 35 % low);
    :func:`undetected_tail` gives the largest such tail the data allow and its volume change
    ``tail`` = (change [m^3], description, u of the volume without it [m^3]), in the u below
    the limit.
    """
    if tail is None:
        return
    dv, note, u_vol = tail
    vol = q["worn_volume"][0]
    if np.isfinite(dv) and dv > limit * max(abs(vol), 3.0 * u_vol):
        raise BadInputError(
            f"wear_map: without a before-wear scan the wear cannot be separated from form: "
            f"{note} (bands next to the worn region against the form model fitted to the rest), "
            f"yet it would change the worn volume "
            f"({vol * 1e9:.3g} mm³) by {dv * 1e9:.2g} mm³ ({dv / max(abs(vol), 1e-30):.0%}); "
            "pass the scan of the bore before wear (before=..., CLI --before BEFORE.nc)"
        )


def _options(shape, before, margin_deg, surface, threshold) -> tuple[str, float]:
    """Checked options: (reference shape, margin around worn regions [degree])."""
    if shape not in WEAR_SHAPES:
        raise BadInputError(
            f"wear_map: shape must be one of {', '.join(map(repr, WEAR_SHAPES))}, got {shape!r}"
        )
    if shape == "auto":
        shape = "cylinder" if before is not None else "form"
    if margin_deg is None:  # without a before-scan faint wear tails would bias the form fit
        margin_deg = 15.0 if shape == "form" else 5.0
    if surface not in ("bore", "shaft"):
        raise BadInputError(f"wear_map: surface must be 'bore' or 'shaft', got {surface!r}")
    if not threshold > 0:
        raise BadInputError(f"wear_map: threshold must be > 0, got {threshold!r}")
    return shape, margin_deg


def _explicit_note(unworn, unworn_z) -> str:
    """The ``unworn_selection`` attribute of an explicit mask."""
    if unworn is not None and np.ndim(unworn) == 2 and np.shape(unworn)[1] == 2:
        arcs = ", ".join(f"{a:g}..{b:g}" for a, b in np.asarray(unworn, dtype=float))
        text = f"explicit: theta {arcs} degree (canonical)"
    elif unworn is not None and np.shape(unworn) == (2,):
        text = f"explicit: theta {float(unworn[0]):g}..{float(unworn[1]):g} degree (canonical)"
    else:
        text = "explicit mask" if unworn is not None else "explicit: all theta"
    if unworn_z is not None:
        zs = ", ".join(f"{a * 1e3:g}..{b * 1e3:g}" for a, b in np.asarray(unworn_z, dtype=float))
        text += f", z {zs} mm"
    return text


def _in_arcs(values: np.ndarray, ranges, what: str, period: float | None) -> np.ndarray:
    """Which ``values`` lie in any of the closed ``ranges`` (lo, hi); with a ``period`` an arc
    with lo > hi wraps through 0 [degree]."""
    inside = np.zeros(values.shape, dtype=bool)
    for r in ranges:
        try:
            lo, hi = (float(x) for x in r)
        except (TypeError, ValueError):
            raise BadInputError(f"wear_map: {what} must be (start, end) pairs, got {r!r}") from None
        if not (np.isfinite(lo) and np.isfinite(hi)) or lo == hi:
            raise BadInputError(f"wear_map: {what} {lo:g}:{hi:g} is empty; give start:end")
        if period is None:
            inside |= (values >= min(lo, hi)) & (values <= max(lo, hi))
            continue
        span = (hi - lo) % period or period
        inside |= (values - lo) % period <= span + 1e-9
    return inside


def _mask_in(unworn, shape: tuple[int, int], z=None, th=None, unworn_z=None) -> np.ndarray | None:
    """The explicit unworn mask, flattened (None if not given): a bool array (z, theta), or
    theta arcs [degree, canonical] and/or z ranges ``unworn_z`` [m] (both must hold)."""
    if unworn is None and unworn_z is None:
        return None
    if unworn is not None and np.shape(unworn) == (2,):  # one arc
        unworn = [tuple(unworn)]
    as_arcs = unworn is None or (np.ndim(unworn) == 2 and np.shape(unworn)[1] == 2)
    as_arcs = as_arcs and not (unworn is not None and np.shape(unworn) == shape)
    if as_arcs:
        mask_in = np.ones(shape, dtype=bool)
        if unworn is not None:
            mask_in &= _in_arcs(th, unworn, "unworn theta arc", 360.0)[None, :]
        if unworn_z is not None:
            mask_in &= _in_arcs(z, unworn_z, "unworn z range", None)[:, None]
        if not mask_in.any():
            raise BadInputError(
                "wear_map: the unworn arcs/z ranges hold no point of the worn scan "
                f"(theta {th.min():g}..{th.max():g} degree, z {z.min():g}..{z.max():g} m)"
            )
        return mask_in.ravel()
    mask_in = np.asarray(unworn, dtype=bool)
    if mask_in.shape != shape:
        raise BadInputError(
            f"wear_map: unworn mask has shape {mask_in.shape}, expected {shape} (z, theta)"
        )
    return mask_in.ravel()


def _method(shape: str, X, with_before: bool) -> str:
    """How the reference was obtained (the ``wear_reference`` attribute)."""
    if with_before:
        return (
            "difference to the before-wear scan (rotated by angle_offset and interpolated onto "
            "the worn grid) minus a limaçon "
            + ("cylinder" if shape == "cylinder" else "circle per layer")
            + " fitted to the unworn points (change of set-up)"
        )
    model = {
        "cylinder": "a limaçon cylinder",
        "circle": "a limaçon circle per layer",
        "form": f"the form model (a centre per layer; radius and lobing "
        f"2..{getattr(X, 'harmonics', 0)} UPR as polynomials of degree {getattr(X, 'deg', 0)} "
        "in z)",
    }[shape]
    return (
        f"residual from {model} fitted by least squares to the unworn part of the worn "
        "scan (no before-wear scan)"
    )


def _centring_note(exact: bool, X, r0_w, with_before: bool) -> str:
    """The ``centring`` attribute."""
    if not exact:
        return "limaçon only (exact_centring=False)"
    if isinstance(X, FormBasis):
        return "form model: its second harmonic, quadratic in z, holds the limaçon's e^2/(4R) term"
    if r0_w is None:
        return "limaçon only (bore radius unknown: pass radius= for exact centring)"
    return (
        "exact: the before scan re-centred on its least-squares axis (all points), the "
        "worn scan on that axis plus the change of set-up (difference on the unworn "
        "points)"
        if with_before
        else "exact: the scan re-centred on its least-squares axis (unworn points)"
    ) + ", then the limaçon reference fitted to the unworn points"


def _without_tails(d, X, mask, shape, th, threshold, margin_deg):
    """The robust fit after the faint-tail test (:func:`_exclude_tails`), its note and the
    tail it still measures where the tails reach around the bore [m] (else None)."""
    mask, tails, remaining = _exclude_tails(d, X, mask, shape, th, 2.0, 5.0)
    fit = _robust_reference(d, X, threshold, mask, 1, "wear_map", shape, th, margin_deg)
    return fit, tails, remaining


def _tails_note(explicit: bool, margin_deg: float) -> str:
    """The ``faint_wear_tails`` attribute when the tails are not tested."""
    if explicit:
        return "not assessed (explicit unworn mask)"
    return (
        "not tested (no before-scan: the unworn form is modelled; a margin of "
        f"{margin_deg:g} degree around the worn region is left out instead)"
    )


def _quantities(d, X, fit, alt, z, th, radius, terms, fit_args, remaining=None):
    """Derived quantities with their u, the per-point u, the residual's correlation length
    [samples], the instrument noise [m] (successive differences of the map), the undetected
    tail (volume change [m^3], description, u of the volume without it [m^3]; None if not
    assessed) and the unseen wear's (bound of each quantity, level [m]) or None.
    ``terms``: which of the "selection", "tail" and "unseen" terms to add to the u;
    ``remaining``: (the tail the band test still measures where it stopped [m] or None, the
    RMS smooth structure of the unworn points [m] or 0) for the "unseen" term."""
    resid, mask, var_fit, s2, _ = fit
    threshold, _, _, margin = fit_args
    shape = (z.size, th.size)
    wear = resid.reshape(shape)
    u = np.sqrt(s2 + var_fit).reshape(shape)
    mask2 = mask.reshape(shape)
    wts = _z_weights(z)[:, None] * _theta_weights(th)[None, :] * radius
    _, _, G = _lsq(X, d, mask)
    cov = np.linalg.inv(G) * s2
    if cov.ndim == 3:  # one block per layer (circle per layer)
        from scipy.linalg import block_diag

        cov = block_diag(*cov)
    tau = correlation_length(wear, mask2)
    q = derived_quantities(
        wear,
        var_fit.reshape(shape),
        s2,
        tau,
        _design_sum(X, wts),
        cov,
        wts,
        z,
        th,
        noise_sigma(wear),
    )
    if alt is not None:
        other = alt[0].reshape(shape)
        _model_order_term(q, wear, other, wts, z, th, "form-model order")
        u = np.hypot(u, wear - other)  # each depth's dependence on the model order
    tail = unseen = None
    if mask2.all() or not terms:
        return q, u, tau, noise_sigma(wear), tail, unseen
    selection = tail_u = unseen_u = None
    note = "not assessed"
    if "selection" in terms:
        selection = selection_term(q, wear, d, X, mask2, wts, z, th, threshold, margin)
    if "tail" in terms:
        dv, shift, note = undetected_tail(d, X, mask, shape, th, wts)
        tail = (dv, note, q["worn_volume"][1])
        tail_u = tail_term(q, wear, wts, dv, shift)
    if "unseen" in terms:
        tail_left, structure = remaining
        level = unseen_level(wear, mask2, th, threshold, tail_left, structure)
        where = mask2 if tail_left is not None or structure else exposed(mask2)
        bound, per_point = unseen_bound(X, G, where * level, z, th, wts, wear)
        unseen = (bound, level)
        unseen_u = (*unseen_term(bound, per_point), level)
    u = reference_bias_terms(q, u, selection, tail_u, note, unseen_u)
    return q, u, tau, noise_sigma(wear), tail, unseen


def _attr_radius(orig: xr.Dataset | xr.DataArray, da: xr.DataArray) -> float | None:
    for src in (da.attrs, getattr(orig, "attrs", {})):
        for key in ("nominal_radius", "radius"):
            if key in src:
                try:
                    return float(src[key])
                except (TypeError, ValueError):
                    pass
    return None


def _volume_radius(radius, wname, rw, worn, w) -> float:
    """Bore radius for the volume [m]: given, the mean radius, or the nominal radius."""
    if radius is None:
        radius = float(np.nanmean(rw)) if wname == "radius" else _attr_radius(worn, w)
    if radius is None or not np.isfinite(radius) or radius <= 0:
        raise BadInputError(
            "wear_map: the worn scan holds radial deviations without a 'nominal_radius' "
            "attribute; pass radius=<bore radius in m> for the worn volume"
        )
    return float(radius)
