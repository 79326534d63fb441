"""Outputs of a wear map: the scalar quantities with their uncertainties, the refusals where
wear cannot be told from form, and the cylindricities of the scans."""

from __future__ import annotations

import numpy as np
import xarray as xr

from jointwear.conventions import CANONICAL, theta_coord, z_coord
from jointwear.errors import BadInputError
from jointwear.metrology._wear_fit import _dilate, _robust_reference, _smooth_theta
from jointwear.metrology.form import cylinder_zone
from jointwear.metrology.wear_quantities import derived_quantities, uncertainty_attrs


def _lobing_rms(surface: np.ndarray) -> float:
    """RMS of the harmonics 2 and up of a fitted surface (nz, nt) [m]."""
    spec = np.fft.rfft(surface, axis=1) / surface.shape[1]
    return float(np.sqrt(np.mean(2.0 * np.sum(np.abs(spec[:, 2:]) ** 2, axis=1))))


def _separable(
    q: dict, s2: float, noise: float, unworn: np.ndarray, threshold: float, lobing: float
) -> None:
    """Refuse a map without a before-scan where wear cannot be told from form."""
    frac = float(unworn.mean())
    fix = (
        "pass the scan of the bore before wear (before=..., CLI --before BEFORE.nc), or an "
        "explicit unworn mask"
    )
    if frac < 0.25:
        raise BadInputError(
            f"wear_map: only {frac:.0%} of the points look unworn: too little of the bore is "
            f"left to fit its unworn form, so wear cannot be separated from form; {fix}"
        )
    depth, u_depth, _ = q["max_wear_depth"]
    s = float(np.sqrt(s2))
    if depth < 5.0 * u_depth and np.isfinite(noise) and lobing > 2.0 * noise:
        raise BadInputError(
            f"wear_map: without a before-wear scan no significant wear stands out (max "
            f"{depth * 1e6:.3g} ± {u_depth * 1e6:.2g} µm), but the bore's "
            f"lobing ({lobing * 1e6:.3g} µm RMS, instrument noise {noise * 1e6:.3g} µm) could "
            "hold wear as broad as its lobes: whether the bore is unworn or evenly worn "
            f"cannot be separated from its form; {fix}"
        )
    if u_depth > 0.3 * depth and not (np.isfinite(noise) and u_depth <= 5.0 * noise):
        raise BadInputError(
            f"wear_map: without a before-wear scan the wear found (max {depth * 1e6:.3g} µm) "
            f"depends on the form model (standard uncertainty {u_depth * 1e6:.2g} µm, including "
            "the change at the neighbouring lobing order): the worn region is as wide as the "
            f"bore's lobes, so wear cannot be separated from form; {fix}"
        )
    if np.isfinite(noise) and s > 3.0 * noise and depth < 5.0 * s:
        raise BadInputError(
            f"wear_map: without a before-wear scan the form model leaves {s * 1e6:.3g} µm RMS "
            f"on the unworn points (instrument noise {noise * 1e6:.3g} µm): unmodelled form of "
            f"the size of the wear found (max {depth * 1e6:.3g} ± {u_depth * 1e6:.2g} µm), so "
            f"wear cannot be separated from form; {fix}"
        )


def _cylindricities(rw, rbz, z, th, thb, unworn):
    """(MZ cylindricity of the worn scan, of the before-scan or the unworn points, note)."""
    if z.size < 2:
        return float("nan"), float("nan"), "not assessed: one layer"

    def zone(v, t):
        return cylinder_zone(
            np.broadcast_to(z[:, None], v.shape), np.broadcast_to(t, v.shape), v
        ).total

    if rbz is not None:
        return zone(rw, th), zone(rbz, thb), "MZ cylindricity of the before-wear scan"
    return (
        zone(rw, th),
        zone(np.where(unworn, rw, np.nan), th),
        "MZ cylindricity of the unworn points of the worn scan (estimate of the cylindricity "
        "before wear; no before-wear scan)",
    )


_LONG = {
    "worn_volume": ("m3", "volume of material removed over the measured band"),
    "max_wear_depth": ("m", "largest wear depth (map averaged over about 1 degree)"),
    "wear_cylindricity": ("m", "MZ cylindricity of the wear map"),
}


def _scalars(q: dict, cyl_before, cyl_after, note: str, noise: float) -> dict:
    """The map's scalar quantities with their ``_u`` variables."""
    out = {}
    for name, (v, u, comment) in q.items():
        unit, long_name = _LONG[name]
        out[name] = (
            (),
            v,
            {"units": unit, "long_name": long_name, "ancillary_variables": f"{name}_u"},
        )
        out[f"{name}_u"] = (
            (),
            u,
            {
                "units": unit,
                "long_name": f"standard uncertainty of {name}",
                **uncertainty_attrs(comment),
            },
        )
    u_zone = float(np.sqrt(2.0) * noise) if np.isfinite(cyl_after) else float("nan")
    zone_comment = (
        "instrument noise (from successive differences) at the zone's two extreme points; the "
        "upward bias of a zone by noise is not corrected"
    )
    for name, v, long_name in (
        ("cylindricity_before", cyl_before, note),
        ("cylindricity_after", cyl_after, "MZ cylindricity of the worn scan"),
    ):
        out[name] = (
            (),
            v,
            {"units": "m", "long_name": long_name, "ancillary_variables": f"{name}_u"},
        )
        out[f"{name}_u"] = (
            (),
            u_zone,
            {
                "units": "m",
                "long_name": f"standard uncertainty of {name}",
                **uncertainty_attrs(zone_comment),
            },
        )
    return out


def _changes(wear: np.ndarray, other: np.ndarray, wts: np.ndarray, z, th) -> dict:
    """How much each quantity changes when the map is ``other`` instead of ``wear``
    (absolute; both without noise corrections)."""
    zeros = np.zeros_like(other)
    args = (zeros, 0.0, 1.0, np.zeros(1), np.zeros((1, 1)), wts, z, th)
    mine, alt = derived_quantities(wear, *args), derived_quantities(other, *args)
    return {name: abs(alt[name][0] - v) for name, (v, _, _) in mine.items()}


def _model_order_term(q: dict, wear, other: np.ndarray, wts: np.ndarray, z, th, what: str) -> None:
    """Add, in quadrature, how much each quantity changes when the map ``wear`` is ``other``
    under another defensible choice (the form model's order): a source of uncertainty."""
    for name, dv in _changes(wear, other, wts, z, th).items():
        v, u, comment = q[name]
        if np.isfinite(dv):
            q[name] = (v, float(np.hypot(u, dv)), comment + f"; {what} ({dv:.3g})")


def selection_term(q, wear, d, X, mask2, wts, z, th, threshold, margin_deg):
    """The dependence on the unworn selection: (change of each quantity, of every depth [m]);
    None where no other selection can be fitted.

    Faint wear tails next to the worn region, too faint for the band test, bias the reference:
    refit without the points within a further 10, 20 and 30 degree of it and take the largest
    change of the volume (each a defensible selection; while at least 10 % of the points stay).
    The worn region: where most of a 2-degree window is not unworn (not every isolated noise
    outlier).
    """
    win = max(1, int(round(2.0 * th.size / 360.0)))
    region = _smooth_theta((~mask2).astype(float), win) <= 0.5
    vol = float(np.sum(wts * np.nan_to_num(wear)))
    best, change = None, -1.0
    for width in (10.0, 20.0, 30.0):
        narrower = (mask2 & _dilate(region, th, width)).ravel()
        if narrower.sum() <= 0.1 * narrower.size:
            break
        try:
            sel, *_ = _robust_reference(
                d, X, threshold, narrower, 1, "wear_map", mask2.shape, th, margin_deg
            )
        except BadInputError:
            break
        other = sel.reshape(mask2.shape)
        dv = abs(float(np.sum(wts * np.nan_to_num(other))) - vol)
        if dv > change:
            best, change = other, dv
    if best is None:
        return None
    return _changes(wear, best, wts, z, th), np.abs(wear - best)


def tail_term(q: dict, wear: np.ndarray, wts, dv: float, shift):
    """The standard uncertainty of a faint wear tail the band test cannot see: (of each
    quantity, of every depth [m]); None where the tails could not be tested (``dv`` NaN).

    :func:`undetected_tail` bounds the tail: it shifts the reference by at most ``shift`` at
    every point [m] (``wts`` the points' areas [m^2]). A bound +-a on an effect is, per the GUM
    (4.3.7), a rectangular distribution of standard uncertainty a/sqrt(3). (The tail is one-
    sided - it pulls the reference up, every depth reads low - but its correction by a/2 with
    u = a/sqrt(12) over-corrected: the bound is a worst case, most maps hold far less, and
    read high by 0.7-1.3 u; so no correction and the symmetric bound.)"""
    if not np.isfinite(dv):
        return None
    shift = np.asarray(shift, dtype=float).reshape(wear.shape)
    k = np.unravel_index(int(np.argmax(np.nan_to_num(wear))), wear.shape)
    bound = {
        "worn_volume": abs(float(np.sum(wts * shift))),
        "max_wear_depth": abs(float(shift[k])),
        "wear_cylindricity": float(np.ptp(shift)),
    }
    return {name: b / np.sqrt(3.0) for name, b in bound.items()}, np.abs(shift) / np.sqrt(3.0)


def reference_bias_terms(
    q: dict, u: np.ndarray, selection, tail, note: str, unseen=None
) -> np.ndarray:
    """Add to ``q`` the uncertainty of the reference's bias by faint wear tails and return the
    widened per-point u. ``selection`` (:func:`selection_term`) and ``tail``
    (:func:`tail_term`) are two estimates of that one effect (leaving the tails out changes
    the map by about what they bias it), and so is ``unseen`` (the wear up to a level the
    selection cannot see on the unworn points: (per quantity, per point, level [m]),
    :mod:`._wear_unseen`): the largest counts, not their sum. Each may be None (not assessed;
    ``unseen``: not needed); ``note`` describes the tail."""
    per_point = [t[1] for t in (selection, tail, unseen) if t is not None]
    for name, (v, uu, comment) in list(q.items()):
        parts, terms = [], []
        if selection is not None and np.isfinite(selection[0][name]):
            parts.append(f"unworn selection ({selection[0][name]:.3g})")
            terms.append(selection[0][name])
        if tail is None:
            parts.append(f"faint wear tails {note}")
        elif np.isfinite(tail[0][name]):
            parts.append(
                f"undetected wear tail ({tail[0][name]:.3g}: bound/sqrt(3), rectangular; {note})"
            )
            terms.append(tail[0][name])
        if unseen is not None and np.isfinite(unseen[0][name]):
            parts.append(
                f"unseen wear ({unseen[0][name]:.3g}: bound/sqrt(3), rectangular, of wear up to "
                f"{unseen[2] * 1e9:.2g} nm on the unworn points the worn regions' tails can "
                "reach; wear spread round the bore)"
            )
            terms.append(unseen[0][name])
        du = max(terms, default=0.0)
        text = "; " + " and ".join(parts)
        if len(terms) >= 2:
            text += f" (one effect: the {'larger' if len(terms) == 2 else 'largest'} counted)"
        q[name] = (v, float(np.hypot(uu, du)) if np.isfinite(uu) else uu, comment + text)
    if per_point:
        u = np.hypot(u, np.maximum.reduce(per_point))
    return u


def refuse_inseparable_difference(s2: float, noise: float, tau: float, arcs=()) -> None:
    """Refuse a difference of scans whose unworn points hold smooth structure, not noise
    (``arcs``: the theta arcs [degree] the data find least worn, for the fix)."""
    from jointwear.metrology._wear_unseen import WearMapRefusal, format_arcs

    if np.sqrt(s2) > max(1.5 * noise, 1e-9) and tau > 20.0:
        fix = (
            f"if the bore is known to be unworn at theta {format_arcs(arcs)} degree (canonical), "
            f"pass them as unworn (CLI --unworn {format_arcs(arcs)})"
            if arcs
            else "give the theta arcs known to be unworn (CLI --unworn THETA1:THETA2)"
        )
        raise WearMapRefusal(
            f"wear_map: the difference of the scans leaves {np.sqrt(s2) * 1e9:.3g} nm RMS of "
            f"smooth structure (correlation length {tau:.0f} samples) on the points taken as "
            f"unworn, against {noise * 1e9:.3g} nm of noise: wear spread around most of the "
            "bore (or a change of form between the scans) cannot be separated from the change "
            "of set-up",
            fix,
            arcs,
        )


def random_part(u: np.ndarray, noise: float, tau: float) -> tuple[str, tuple]:
    """``wear_depth_u_random``: the independent (point-to-point) part of each point's u [m].

    The instrument noise estimate (successive differences of the map: form, set-up and the
    fitted reference vary smoothly between neighbouring samples, noise does not), capped at the
    point's whole u. The rest of ``wear_depth_u`` (reference fit, unmodelled form, selection
    and tail terms) is correlated over the map and does not average down; this part does, over
    about ``tau`` samples per independent one (``correlation_length_samples``).
    """
    ur = np.minimum(u, noise) if np.isfinite(noise) else np.full_like(u, np.nan)
    attrs = {
        "units": "m",
        "long_name": "independent (point-to-point random) part of wear_depth_u",
        **uncertainty_attrs(
            "instrument noise estimate (1.4826 MAD of second differences of the map / sqrt(6)) "
            "capped at wear_depth_u; included in wear_depth_u, independent from point to point "
            "(the rest of wear_depth_u is correlated over the map)"
        ),
        "correlation_length_samples": float(tau) if np.isfinite(tau) else 1.0,
    }
    return "wear_depth_u_random", (("z", "theta"), ur, attrs)


def wear_dataset(
    z, th, wear, u, mask2, scalars: dict, offset: float, attrs: dict, extra: dict | None = None
):
    """The wear map Dataset: per-point depth and u, the unworn flag, scalars, attributes;
    ``extra`` further variables (e.g. :func:`random_part`)."""
    return xr.Dataset(
        {
            "wear_depth": (
                ("z", "theta"),
                wear,
                {
                    "units": "m",
                    "long_name": "wear depth of the bearing surface (positive = material removed)",
                    "ancillary_variables": "wear_depth_u",
                },
            ),
            "wear_depth_u": (
                ("z", "theta"),
                u,
                {
                    "units": "m",
                    "long_name": "standard uncertainty of wear_depth",
                    **uncertainty_attrs(
                        "scatter of the unworn points about the reference (instrument noise, "
                        "unmodelled form and set-up) and the fitted reference's standard error"
                    ),
                },
            ),
            "unworn": (
                ("z", "theta"),
                mask2.astype(np.int8),
                {
                    "units": "1",
                    "long_name": "point used as unworn reference",
                    "flag_values": np.array([0, 1], dtype=np.int8),
                    "flag_meanings": "worn_or_outlier unworn_reference",
                },
            ),
            **(extra or {}),
            **scalars,
            "angle_offset": (
                (),
                offset,
                {
                    "units": "degree",
                    "long_name": "rotation applied to the before-wear scan (canonical theta)",
                },
            ),
        },
        coords={"z": z_coord(z), "theta": theta_coord(th, CANONICAL)},
        attrs={"title": "wear map", **attrs},
    )
