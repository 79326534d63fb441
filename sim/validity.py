"""Validity of the contact model of joint C: when a run leaves the range the law was made for.

The Lankarani-Nikravesh law with the Hertz-based stiffness of eqs. 7-9 assumes a small,
non-conforming, linear-elastic contact between metals. A run is checked against the limits of
:data:`CONTACT_LIMITS` (docs/sim.md, "Validity of the contact model"):

* ``penetration_clearance``: largest penetration over the radial clearance;
* ``penetration_stop``: largest penetration over the stop that ends a run
  (``contact.max_penetration_fraction`` x radial clearance);
* ``hertz_contact_angle``: the Hertz contact semi-angle sqrt(R' delta) / Rj [rad], R' =
  Rj Rb / (Rb - Rj): beyond it the contact conforms to the bore and the small-contact
  (paraboloid) assumption of Hertz's theory fails; with a softer pair the same load penetrates
  deeper, so this is where the material pair enters;
* ``polymer_with_metal_kw``: a polymer (modulus below :data:`POLYMER_MODULUS`) run with the
  default kw, which was calibrated for the study's steel/brass pair.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from typing import Any

__all__ = [
    "CONTACT_LIMITS",
    "POLYMER_MODULUS",
    "ContactLimit",
    "contact_validity",
    "hertz_deflections",
    "penetration_stop_advice",
]


@dataclass(frozen=True)
class ContactLimit:
    """One validity limit: the largest allowed value of a dimensionless ratio, and why."""

    limit: float
    quantity: str
    reason: str


#: The documented limits (dimensionless ratios; a value above the limit is a breach).
CONTACT_LIMITS: dict[str, ContactLimit] = {
    "penetration_clearance": ContactLimit(
        0.2,
        "largest penetration / radial clearance",
        "the law treats the overlap as a small local deformation; at 0.2 c the overlap spans a "
        "large arc of the bore (the study's pair reaches 0.13 c at its hardest impacts)",
    ),
    "penetration_stop": ContactLimit(
        0.8,
        "largest penetration / (contact.max_penetration_fraction x radial clearance)",
        "the run came within 20 % of the penetration at which it is stopped as failed",
    ),
    "hertz_contact_angle": ContactLimit(
        0.5,
        "Hertz contact semi-angle sqrt(R' delta) / Rj [rad], R' = Rj Rb / (Rb - Rj)",
        "Hertz's theory assumes a contact small against the radii (paraboloid surfaces, small "
        "strains); beyond ~30 degrees the contact conforms to the bore and eqs. 7-9 "
        "underestimate its stiffness (conformal contact, Persson 1964)",
    ),
    "polymer_with_metal_kw": ContactLimit(
        0.0,
        "1 if the softer body's modulus is below 10 GPa and kw is the default, else 0",
        "the default kw (9.0e-16 m2/N) was calibrated for the study's steel/brass pair; a "
        "polymer wears by other mechanisms (transfer film, creep): calibrate kw for the pair",
    ),
}

#: Young's modulus below which a body is taken to be a polymer [Pa].
POLYMER_MODULUS: float = 10e9


def _ratios(params: Any, max_penetration: float, kw: float | None) -> dict[str, float]:
    from jointwear.sim.wear._settings import DEFAULT_KW

    j, c = params.joint, params.contact
    clearance = j.radial_clearance
    rj, rb = j.journal_radius, j.bearing_radius
    delta = float(max_penetration)
    known = math.isfinite(delta)
    soft = min(c.journal_modulus, c.bearing_modulus)
    return {
        "penetration_clearance": delta / clearance if known else math.nan,
        "penetration_stop": delta / (c.max_penetration_fraction * clearance) if known else math.nan,
        "hertz_contact_angle": math.sqrt(rj * rb / clearance * max(delta, 0.0)) / rj
        if known
        else math.nan,
        "polymer_with_metal_kw": math.nan
        if kw is None
        else float(soft < POLYMER_MODULUS and kw == DEFAULT_KW),
    }


def contact_validity(
    params: Any, max_penetration: float, *, kw: float | None = None
) -> dict[str, Any]:
    """Check a run against :data:`CONTACT_LIMITS`.

    Parameters
    ----------
    params : SimParameters
        The run's parameters.
    max_penetration : float
        Largest penetration of the run (bore or end faces) [m]; NaN = unknown (those checks are
        "not assessed").
    kw : float, optional
        The wear coefficient of a wear run [m²/N] (None: a run without wear, that check is not
        assessed).

    Returns
    -------
    dict
        ``status`` ("within limits", "exceeded" or "not assessed"), ``checks`` (per limit:
        value, limit, status, quantity), ``warning`` (one sentence per breach, or None) and
        ``attrs`` (the netCDF attributes to record: ``contact_validity`` as JSON,
        ``contact_validity_status`` and, on a breach, ``contact_validity_warning``).
    """
    ratios = _ratios(params, max_penetration, kw)
    checks: dict[str, dict[str, Any]] = {}
    breaches = []
    for name, lim in CONTACT_LIMITS.items():
        value = ratios[name]
        if not math.isfinite(value):
            state = "not assessed"
        elif value > lim.limit:
            state = "exceeded"
            breaches.append(f"{name} = {value:.3g} > {lim.limit:g} ({lim.quantity})")
        else:
            state = "within limits"
        checks[name] = {
            "value": value if math.isfinite(value) else None,
            "limit": lim.limit,
            "status": state,
            "quantity": lim.quantity,
        }
    geometric = [checks[k]["status"] for k in ("penetration_clearance", "penetration_stop")]
    if breaches:
        status = "exceeded"
    elif "not assessed" in geometric:
        status = "not assessed"  # the penetration is unknown (a contact model without it)
    else:
        status = "within limits"
    warning = None
    if breaches:
        warning = (
            f"the contact model left its validity range (largest penetration "
            f"{1e6 * max_penetration:.1f} um): " + "; ".join(breaches) + "; see the limits in "
            "docs/sim.md (validity of the contact model) - results outside them are not "
            "supported by the model"
        )
    attrs = {
        "contact_validity": json.dumps(checks, sort_keys=True),
        "contact_validity_status": status,
        "contact_validity_max_penetration_m": float(max_penetration),
    }
    if warning:
        attrs["contact_validity_warning"] = warning
    return {"status": status, "checks": checks, "warning": warning, "attrs": attrs}


def hertz_deflections(params: Any, load: float) -> tuple[float, float, float]:
    """The contact's deflections under a joint load, with its stiffness.

    Parameters
    ----------
    params : SimParameters
    load : float
        Joint force [N].

    Returns
    -------
    (static, sudden, K)
        ``static = (F / K)^(1/n)`` [m], the line-contact deflection under ``F`` (K of eq. 7,
        ``n = contact.exponent``); ``sudden = ((n + 1) F / K)^(1/n)`` [m], the peak deflection
        when ``F`` is applied at once (energy: ``F d = K d^(n+1) / (n+1)``), what a journal
        crossing the clearance and landing under load reaches without any approach speed;
        ``K`` [N/m^n].
    """
    from jointwear.sim.contact import contact_constant

    n = params.contact.exponent
    k = contact_constant(params)[1]
    return (load / k) ** (1 / n), ((n + 1) * load / k) ** (1 / n), k


def _joint_load(params: Any) -> float:
    """The ideal joint's largest reaction over one crank cycle [N] (its own short run)."""
    import dataclasses

    from jointwear.sim.dynamics import run_cycles

    ideal = dataclasses.replace(params, joint=dataclasses.replace(params.joint, model="ideal"))
    ds = run_cycles(ideal, cycles=1.0).dataset
    return float(ds["contact_force"].max())


def penetration_stop_advice(params: Any) -> str:
    """Why a run stopped on ``contact.max_penetration_fraction``: the physics, compared.

    The joint's load (the ideal joint's largest reaction over a cycle) deflects the contact by
    the Hertz deflection of eq. 7's K; when that deflection, applied suddenly, reaches the stop
    (``max_penetration_fraction`` x the radial clearance), the clearance is too small for this
    load and contact stiffness (physically the joint runs closed, elastically preloaded, which
    an impact model of a clearance joint does not describe) and no solver setting changes it.
    The message names the parameters that do: the clearance, the materials, the speed.
    """
    j, c = params.joint, params.contact
    clearance = j.radial_clearance
    stop = c.max_penetration_fraction * clearance
    try:
        load = _joint_load(params)
    except Exception as exc:  # noqa: BLE001 - advice must never hide the stop itself
        return (
            f"the joint's load could not be estimated for a comparison with the clearance "
            f"({exc}); check the clearance, the materials and the speed, then the solver"
        )
    static, sudden, k = hertz_deflections(params, load)
    soft = min(c.journal_modulus, c.bearing_modulus)
    compared = (
        f"the ideal joint carries up to {load:.4g} N, which deflects this contact (K = "
        f"{k:.3g} N/m^{c.exponent:g} of eq. 7, E = {c.journal_modulus / 1e9:.3g} / "
        f"{c.bearing_modulus / 1e9:.3g} GPa) by {1e6 * static:.3g} um statically and "
        f"{1e6 * sudden:.3g} um when applied at once, against a radial clearance of "
        f"{1e6 * clearance:.3g} um and the stop at {1e6 * stop:.3g} um"
    )
    levers = (
        "what changes it is the physics: a larger clearance (joint.bearing_radius - "
        "joint.journal_radius), a stiffer pair (contact.journal_modulus, "
        f"contact.bearing_modulus; the softer here is {soft / 1e9:.3g} GPa), or a lower "
        "mechanism.crank_speed_rpm (the inertial load grows with its square); for a joint "
        "without play use joint.model = 'ideal'"
    )
    if sudden >= 0.5 * stop:
        from jointwear.sim.parameters import ContactParameters

        usual = ContactParameters.max_penetration_fraction * clearance
        if c.max_penetration_fraction < ContactParameters.max_penetration_fraction and (
            sudden < 0.5 * usual
        ):
            return (
                f"physical cause: the stop itself is set below the contact's deflection under "
                f"the joint's load (contact.max_penetration_fraction = "
                f"{c.max_penetration_fraction:g}, default {ContactParameters.max_penetration_fraction:g}) - "
                f"{compared}; raise contact.max_penetration_fraction"
            )
        if soft < POLYMER_MODULUS:
            cause = (
                f"the soft pair ({soft / 1e9:.3g} GPa) deflects under the joint's load by "
                "about the clearance or more"
            )
        elif sudden < clearance:
            cause = "the clearance is too small for this load and contact stiffness"
        else:
            cause = "the contact's elastic deflection under the load exceeds the clearance"
        return (
            f"physical cause: {cause} - {compared}; impacts add to that, so the journal does "
            "not fly within a clearance but presses through it (the joint runs closed, "
            "elastically preloaded), which the clearance-joint contact model does not describe; "
            f"tightening the solver does not help: {levers}"
        )
    return (
        f"{compared}: the load alone reaches {100 * sudden / stop:.0f} % of the stop, so the "
        "stop comes from an impact faster than the load explains or from the integration; "
        "check contact.restitution and the speed, then tighten solver.rtol or "
        f"solver.onset_penetration; otherwise {levers}"
    )
