"""Reported measurements (a lab sheet's or a paper's numbers) judged against a simulated wear map.

Each reported quantity (:mod:`jointwear.reported`) is matched to the simulated quantity of the
same definition, computed on the simulated wear map at the reported cycles and at the measured
places (:mod:`jointwear.compare._reported_quantities`), and decided with ASME V&V 20 in the four
states of :mod:`jointwear.compare.verdicts`:

* **cylindricity** after N cycles: the reported growth ``D = C(N) - C(0)`` (the new bore's
  cylindricity reported at ``cycles = 0``) against the cylindricity of the simulated wear
  (the simulation starts from a perfect bore) on the measured layers. Cylindricity does not
  add: the worn bore's value lies within ``C_wear +- C(0)``, so the new-bore form enters u_D as
  a rectangular term ``C(0)/sqrt(3)`` besides the two readings' own uncertainties. A reference
  stated as ``"unstated"`` (least squares or minimum zone) takes the midpoint of the two
  simulated values with their half-difference as a rectangular term of u_D. Without the
  new-bore value u_D is not assessed.
* **angle of maximum wear** at a layer: a circular quantity; ``E`` is wrapped to (-180, 180]
  degree before it meets ``U_val``; the screening threshold shown when V&V 20 is not
  assessed is ``max_angle_error_deg`` of the criteria (never a verdict).
* **maximum wear depth** at a layer or over the measured layers.
* derived: the **angle between the maxima** of two reported layers at the same cycles,
  ``|wrap(theta_a - theta_b)|``, which does not depend on the angles' zero, their direction or
  the layer order (decidable when those are unstated); u_D = sqrt(u_a^2 + u_b^2).
* ``kind = "other"``, a place outside the simulated bore, cycles beyond the simulation, the
  new bearing itself (0 cycles): *not comparable*, with the reason.

What the source leaves unstated (the direction of its angles, which end layer 1 is at, where
the stack of layers lies along the bore) is enumerated (:func:`readings`): each reading is decided, and the verdict stands only when every reading gives the
same state; otherwise the quantity is *not comparable*, the reason listing each reading's
outcome and the field that settles it.

u_num: a verification study of ``jointwear sim verify`` (``jointwear_file =
"verification_study"``, run to the quantity's cycles: the quantity on every stored run's map
through :func:`jointwear.refinement.study_uncertainty`), a verification dataset with a variable
of the quantity's own name, or one that keeps a wear map per refinement level (``wear_depth`` over ``(h, [cycles,] z, theta)``: the quantity
is computed on each level, then the GCI of three levels, least squares of four or more,
:func:`jointwear.compare.verification.refinement_study`); else the
criteria's ``wear_u_num_rel`` (not for angles); else not assessed. u_input: an ensemble that
keeps its wear maps (the quantity per member, the spread of
:func:`jointwear.compare.ensemble.spread`; for angles the wrapped deviations, and only from an
ensemble at the same cycles); else ``wear_u_input_rel`` (not for angles); else not assessed.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import xarray as xr

import jointwear.compare.metrics as mt
import jointwear.compare.verdicts as vd
from jointwear.compare._decide import (
    Budget,
    Discrepancy,
    Rows,
    Uncertainty,
    decision,
    fmt,
    scalar_discrepancy,
    unknown,
    vv20_decision,
)
from jointwear.compare._reported_quantities import (
    SEPARATION,
    Reading,
    evaluate,
    measured_angle,
    readings,
    reference_spread,
)
from jointwear.compare.align import _prepare_map
from jointwear.compare.criteria import Criteria
from jointwear.compare.ensemble import Ensemble, not_a_distribution, spread
from jointwear.compare.verification import _formal_order, refinement_study
from jointwear.errors import BadInputError
from jointwear.reported import is_reported

__all__ = ["split_reported", "reported_metrics", "circular_discrepancy"]


def split_reported(items: Sequence[xr.Dataset]) -> tuple[list[xr.Dataset], list[xr.Dataset]]:
    """The reported-measurement datasets among ``items``, and the others."""
    rep = [d for d in items if is_reported(d)]
    return rep, [d for d in items if not is_reported(d)]


def circular_discrepancy(s: float, d: float, max_error_deg: float) -> Discrepancy:
    """The error of an angle [degree]: ``E = wrap(S - D)`` in (-180, 180].

    Like :func:`jointwear.compare._decide.scalar_discrepancy`, but the error is circular and the
    screening threshold shown when V&V 20 is not assessed is an angle, ``|E| <= max_error_deg``
    (screening only, never a pass or a fail).
    """
    finite = bool(np.isfinite(s) and np.isfinite(d))
    e = float(mt.wrap_angle_deg(s - d)) if finite else float("nan")
    shown = f"S = {s:.1f} degree, D = {d:.1f} degree"
    screen = (
        f"; screening only, not a verdict: |E| {'<=' if abs(e) <= max_error_deg else '>'} "
        f"{max_error_deg:g} degree"
    )
    return Discrepancy(
        d + e,
        d,
        e,
        "degree",
        values=(("value_sim", s), ("value_meas", d)),
        shown=shown,
        not_assessed_text=f"E = {e:+.1f} degree ({shown}){screen}",
        result_text=lambda res: (
            f"|E| = {abs(e):.1f} degree, U_val = {res.U_val:.1f} degree ({shown})"
        ),
        criterion_note=", E wrapped to (-180, 180] degree",
        relative=False,
    )


def _wear_at(ds: xr.Dataset, cycles: float, what: str) -> tuple[xr.DataArray, float]:
    """Canonical (z, theta) map [m] of ``ds`` at ``cycles`` (exact or interpolated snapshot)."""
    da, _, n, _, _ = _prepare_map(ds, "wear_depth", cycles, what)
    return da, float(cycles if n is None else n)


def _label(name: str, q: Mapping[str, Any]) -> str:
    kind, cyc = q["kind"], float(q["cycles"])
    where = (
        f"layer {int(q['layer'])}"
        if int(q.get("layer", 0)) > 0
        else (f"z = {float(q['z_m']) * 1e3:+.2f} mm" if "z_m" in q else "measured layers")
    )
    if kind == SEPARATION:
        a, b = (int(p["layer"]) for p in q["pair"])
        return f"{name} (angle between the maxima at layers {a} and {b}, {cyc:g} cycles)"
    what = {
        "cylindricity": "cylindricity growth since new",
        "max_wear_angle": "angle of maximum wear",
        "max_wear_depth": "maximum wear depth",
        "other": "reported quantity",
    }[kind]
    return f"{name} ({what}, {where}, {cyc:g} cycles)"


def _baseline(rep: xr.Dataset, q: Mapping[str, Any]) -> str | None:
    """The new-bore cylindricity (cycles = 0, same reference and place) of a cylindricity."""
    from jointwear.reported import new_bore_baseline

    return new_bore_baseline(rep, q)


def _measured(
    rep: xr.Dataset, name: str, q: Mapping[str, Any], reading: Reading
) -> tuple[float, Uncertainty]:
    """The measured value D and its u_D as compared (growth for a cylindricity)."""
    if q["kind"] == SEPARATION:  # one file, one convention: its zero and direction cancel
        (va, ua), (vb, ub) = (
            (float(rep[p].values), float(rep[f"{p}_u"].values)) for p in q["names"]
        )
        d = abs(float(mt.wrap_angle_deg(va - vb)))
        if not (np.isfinite(ua) and np.isfinite(ub)):
            return d, unknown("the reported file states no uncertainty of one of the two angles")
        return d, Uncertainty(
            math.hypot(ua, ub), f"u = sqrt(u_a^2 + u_b^2) of {q['names'][0]}, {q['names'][1]}"
        )
    d = float(rep[name].values)
    u = float(rep[f"{name}_u"].values)
    basis = f"reported file: {rep[f'{name}_u'].attrs.get('comment', '')}"
    if q["kind"] == "max_wear_angle":
        d = measured_angle(d, q, reading)
    if q["kind"] != "cylindricity":
        if not np.isfinite(u):
            return d, unknown("the reported file states no uncertainty (not_stated)")
        return d, Uncertainty(u, basis)
    base = _baseline(rep, q)
    if base is None:
        return d, unknown(
            "the new bore's cylindricity is not reported (a cylindricity at cycles = 0, same "
            "reference and layers): the growth due to wear cannot be separated from the "
            "initial form"
        )
    c0 = float(rep[base].values)
    u0 = float(rep[f"{base}_u"].values)
    if not (np.isfinite(u) and np.isfinite(u0)):
        return d - c0, unknown(f"the reported file states no uncertainty of {name} or {base}")
    form = c0 / math.sqrt(3.0)
    return d - c0, Uncertainty(
        math.sqrt(u**2 + u0**2 + form**2),
        f"growth {name} - {base}: u = sqrt(u({name})^2 + u({base})^2 + (C0/sqrt(3))^2), the last "
        f"term ({fmt(form, 'm')}) because cylindricity does not add - the new bore's form "
        f"({fmt(c0, 'm')}) may add to or cancel the wear's; {basis}",
    )


def _level_dim(ds: xr.Dataset) -> str:
    return str(next(d for d in ds["wear_depth"].dims if d not in ("cycles", "z", "theta")))


def _level_values(
    ds: xr.Dataset, q, attrs, reading, cycles
) -> tuple[np.ndarray, np.ndarray] | None:
    """The quantity on each refinement level of a verification dataset that keeps its maps."""
    if "wear_depth" not in ds or ds["wear_depth"].ndim < 3:
        return None
    dims = [d for d in ds["wear_depth"].dims if d not in ("cycles", "z", "theta")]
    if len(dims) != 1 or dims[0] not in ds.coords:
        return None
    h = np.asarray(ds[dims[0]].values, dtype=float)
    values = []
    for i in range(h.size):
        level = ds.isel({dims[0]: i})
        try:
            wear, _ = _wear_at(level, cycles, "verification level")
        except BadInputError:
            return None
        values.append(evaluate(wear, q, attrs, reading)[0])
    return h, np.asarray(values, dtype=float)


def _study_u_num(
    study: xr.Dataset, name, q, attrs, reading, s: float, cycles: float
) -> Uncertainty:
    """u_num from a ``jointwear sim verify`` study: the quantity on every stored run's map."""
    try:
        from jointwear.refinement import study_uncertainty
    except ImportError:  # pragma: no cover - the refinement module ships with sim verify
        return unknown("this installation cannot read verification studies (jointwear.refinement)")
    ran = float(study.attrs.get("cycles", np.nan))
    if not np.isclose(ran, cycles, rtol=1e-6):
        return unknown(
            f"the verification study was run for {ran:g} cycles, the quantity is at {cycles:g}: "
            "its numerical uncertainty is not that of this quantity - run the study to "
            f"{cycles:g} cycles"
        )

    def fn(wear: xr.DataArray) -> float:
        value = evaluate(wear, q, attrs, reading)[0]
        if q["kind"] == "max_wear_angle":  # continuous around S for the level statistics
            return s + float(mt.wrap_angle_deg(value - s))
        return value

    fit = study_uncertainty(study, name, fn)
    if not fit.assessed:
        return unknown(f"verification study: {fit.reason}")
    # the compared simulation is one run: its u_num has the run-to-run scatter, not the
    # standard error of the replicates' mean
    u_run = float(getattr(fit, "u_num_run", float("nan")))
    if not np.isfinite(u_run):
        return unknown(
            "the verification study does not give the uncertainty of a single run (replicate "
            "counts unknown); the compared simulation is one run"
        )
    return Uncertainty(u_run, "verification study, u_num of one run: " + fit.describe())


def _u_num(
    name: str, q, attrs, reading, s: float, cycles: float, studies, criteria: Criteria
) -> Uncertainty:
    angle = q["kind"] in ("max_wear_angle", SEPARATION)
    skipped = []
    for ds in studies:
        if ds.attrs.get("jointwear_file") == "verification_study":
            u = _study_u_num(ds, name, q, attrs, reading, s, cycles)
            if u.known or "was run for" not in u.basis:
                return u
            skipped.append(u)  # another study may be run to these cycles
            continue
        if name in ds.data_vars and ds[name].ndim == 1 and ds[name].dims[0] in ds.coords:
            h, values = np.asarray(ds[ds[name].dims[0]].values, float), ds[name].values
        else:
            found = _level_values(ds, q, attrs, reading, cycles)
            if found is None:
                continue
            h, values = found
        values = np.asarray(values, dtype=float)
        if q["kind"] == "max_wear_angle":  # unwrap around the finest level's angle
            ref = values[np.nanargmin(np.where(np.isfinite(values), h, np.inf))]
            values = ref + mt.wrap_angle_deg(values - ref)
        dim = ds[name].dims[0] if name in ds.data_vars else _level_dim(ds)
        order, note = _formal_order(ds, str(dim))
        g = refinement_study(
            h, values, quantity=name, formal_order=order, formal_order_note=note, refined=str(dim)
        )
        if not g.assessed:
            return unknown(f"verification study: {g.reason}")
        return Uncertainty(g.u_num_rel * abs(g.values[0]), "verification: " + g.describe())
    if criteria.wear_u_num_rel is not None and not angle:
        rel = criteria.wear_u_num_rel
        return Uncertainty(
            rel * abs(s), f"user-stated {rel:.3g}·|S| (criteria wear_u_num_rel)", 1.0
        )
    if skipped:
        return skipped[0]
    return unknown(
        "no verification study with this quantity or with a wear map per refinement level "
        "(--verification)" + ("" if angle else ", and the criteria state no wear_u_num_rel")
    )


def _u_input(
    q, attrs, reading, s: float, cycles: float, ens: Ensemble | None, criteria: Criteria
) -> Uncertainty:
    angle = q["kind"] in ("max_wear_angle", SEPARATION)
    found = ens.field("wear_depth") if ens is not None else []
    parts = []
    for i, da in found:
        why = not_a_distribution(ens.datasets[i], ens.names[i])
        if why:
            return unknown(why)
        values, run_cycles = [], None
        for r in range(da.sizes["run"]):
            member = da.isel(run=r, drop=True).to_dataset(name="wear_depth")
            member.attrs = dict(ens.datasets[i].attrs)
            try:
                wear, run_cycles = _wear_at(member, cycles, "ensemble member")
            except BadInputError:
                wear, run_cycles = _wear_at(member, None, "ensemble member")  # type: ignore[arg-type]
                run_cycles = ens.cycles(i)
            values.append(evaluate(wear, q, attrs, reading)[0])
        v = np.asarray(values, dtype=float)
        same = run_cycles is not None and np.isclose(run_cycles, cycles, rtol=1e-6)
        if angle:
            if not same:
                return unknown(
                    f"{ens.names[i]} was run for {run_cycles} cycles: the spread of an angle "
                    f"cannot be scaled to {cycles:g} cycles - run the ensemble to that number"
                )
            if q["kind"] == "max_wear_angle":
                v = s + mt.wrap_angle_deg(v - s)
        parts.append((ens.names[i], v, cycles if same else run_cycles))
    if parts:
        return spread(parts, s, compared_cycles=None if angle else cycles)
    if criteria.wear_u_input_rel is not None and not angle:
        rel = criteria.wear_u_input_rel
        return Uncertainty(
            rel * abs(s), f"user-stated {rel:.3g}·|S| (criteria wear_u_input_rel)", 1.0
        )
    return unknown(
        "no ensemble that keeps its wear maps (--ensemble from jointwear sim sweep with maps)"
        + ("" if angle else " and the criteria state no wear_u_input_rel")
    )


def _one_reading(
    rep, name, q, reading, wear, cycles, studies, ens, criteria, label
) -> tuple[Rows, list[dict[str, Any]]]:
    rows, decs = Rows(), []
    attrs = rep.attrs
    s, why = evaluate(wear, q, attrs, reading)
    d, u_d = _measured(rep, name, q, reading)
    if q["kind"] == "cylindricity" and q.get("reference") == "unstated" and u_d.known:
        half = reference_spread(wear, q, attrs, reading)
        if np.isfinite(half):
            u_d = Uncertainty(
                math.sqrt(u_d.value**2 + (half / math.sqrt(3.0)) ** 2),
                u_d.basis + f"; reference (LS or MZ) not stated: S is the midpoint, +-"
                f"{fmt(half, 'm')} rectangular ({fmt(half / math.sqrt(3.0), 'm')})",
            )
    nan = float("nan")
    u_num = (
        _u_num(name, q, attrs, reading, s, cycles, studies, criteria) if not why else unknown(why)
    )
    u_in = _u_input(q, attrs, reading, s, cycles, ens, criteria) if not why else unknown(why)
    budget = Budget(u_num, u_in, u_d, criteria.k)
    if q["kind"] == "max_wear_angle":
        error = circular_discrepancy(s, d, criteria.max_angle_error_deg)
    else:
        unit = "m" if q["units"] == "m" else str(q["units"])
        error = scalar_discrepancy(s if not why else nan, d, unit, criteria.relative_error_max)
    vv20_decision(rows, decs, name, label, error, budget, not_comparable=why)
    return rows, decs


def _combine(
    name: str, outcomes: list[tuple[str, Rows, list[dict[str, Any]]]], settle: str
) -> tuple[list[dict[str, Any]], list[dict[str, Any]]]:
    """Metric rows and decisions from every reading: a state stands only if all agree."""
    if len(outcomes) == 1:
        _, rows, decs = outcomes[0]
        return rows.rows, decs
    all_rows = list(outcomes[0][1].rows)  # the first reading under the plain name
    for label, rows, _ in outcomes[1:]:
        for row in rows.rows:
            all_rows.append({**row, "quantity": f"{name} [{label}]"})
    shapes = {tuple(d["criterion"] for d in decs) for _, _, decs in outcomes}
    first = outcomes[0][2]
    n = len(first) if len(shapes) == 1 else 1
    out = []
    for i in range(n):
        each = [(label, decs[min(i, len(decs) - 1)]) for label, _, decs in outcomes]
        states = {d["state"] for _, d in each}
        base = dict(each[0][1])
        if len(states) == 1 and len(shapes) == 1:
            if len({d["value"] for _, d in each}) > 1:
                base["value"] = " | ".join(f"{label}: {d['value']}" for label, d in each)
            out.append(base)
            continue
        groups = {st: [label for label, d in each if d["state"] == st] for st in vd.STATES}
        listing = "; ".join(
            f"{vd.LABELS[st]} under {len(labels)} of {len(each)} ({' | '.join(labels)})"
            for st, labels in groups.items()
            if labels
        )
        base.update(
            state=vd.NOT_COMPARABLE,
            passed=False,
            value="depends on the reading",
            reason=f"the verdict depends on what the source leaves unstated - {listing} (each "
            f"reading's numbers: metrics '{name} [reading]'); state {settle} in the reported "
            "file to decide it",
        )
        out.append(base)
    return all_rows, out


def _separations(quantities: list[tuple[str, dict[str, Any]]]) -> list[tuple[str, dict[str, Any]]]:
    """Derived quantities: the angle between the maxima of two reported layers, same cycles.

    ``|wrap(theta_a - theta_b)|`` does not depend on where the angles' zero is, on their
    direction, nor on which end of the bore layer 1 is at: it can be decided when those are
    unstated.
    """
    angles = [
        (n, q)
        for n, q in quantities
        if q["kind"] == "max_wear_angle" and int(q.get("layer", 0)) > 0 and q["cycles"] > 0
    ]
    out = []
    for (na, qa), (nb, qb) in itertools.combinations(angles, 2):
        if qa["cycles"] == qb["cycles"] and qa["layer"] != qb["layer"]:
            q = {
                "kind": SEPARATION,
                "cycles": qa["cycles"],
                "units": "degree",
                "layer": 0,
                "pair": (qa, qb),
                "names": (na, nb),
            }
            out.append((f"angle_between_{na}_and_{nb}", q))
    return out


def reported_metrics(
    sim_wear: xr.Dataset | None,
    rep: xr.Dataset,
    rows: Rows,
    decisions: list[dict[str, Any]],
    notes: list[str],
    *,
    criteria: Criteria,
    ensemble: Ensemble | None = None,
    verification: Sequence[xr.Dataset] = (),
) -> None:
    """Metric rows and decisions of every quantity of a reported-measurement dataset.

    Parameters
    ----------
    sim_wear : Dataset or None
        The simulated wear map (``wear_depth`` over ``cycles, z, theta``); None: every quantity
        is not comparable.
    rep : Dataset
        Reported measurements (:func:`jointwear.reported.read_reported`).
    rows, decisions, notes
        Collected in place (see :func:`jointwear.compare.compare`).
    criteria, ensemble, verification
        As for :func:`jointwear.compare.compare` (verification as datasets).
    """
    studies = [v for v in verification if isinstance(v, xr.Dataset)]
    a = rep.attrs
    unstated = [
        field
        for field, missing in (
            (
                "angle.direction",
                any(v.attrs.get("angle_direction") == "unstated" for v in rep.data_vars.values()),
            ),
            ("layers.first", a.get("layers_first") == "unstated"),
            (
                "layers.z_centre",
                "layers_count" in a and not np.isfinite(float(a.get("layers_z_centre_m", 0.0))),
            ),
        )
        if missing
    ]
    if unstated:
        notes.append(
            f"reported measurements '{a.get('title', '')}': the source does not state "
            f"{', '.join(unstated)}; each quantity was decided under every reading of what "
            "matters to it, and its verdict stands only where they agree"
        )
    names = [str(n) for n, v in rep.data_vars.items() if "kind" in v.attrs]
    quantities = [(n, {**rep[n].attrs, "units": rep[n].attrs["units"]}) for n in names]
    quantities += _separations(quantities)
    for name, q in quantities:
        label = _label(name, q)
        cycles = float(q["cycles"])
        why = ""
        if cycles == 0:
            why = (
                "a measurement of the new bearing (0 cycles): the simulation starts from a perfect "
                "bore; it is the baseline of the growth quantities, not a prediction"
            )
        elif sim_wear is None:
            why = "the simulation has no wear map (wear_depth) to compute it from"
        wear = None
        if not why:
            try:
                wear, _ = _wear_at(sim_wear, cycles, "simulated wear map")
            except BadInputError as exc:
                why = f"the simulation cannot give it at {cycles:g} cycles: {exc}"
        if why:
            d = (
                _measured(rep, name, q, Reading("stated", ""))[0]
                if q["kind"] == SEPARATION
                else float(rep[name].values)  # as reported (a baseline is not its own growth)
            )
            rows.add(name, "value_sim", float("nan"), q["units"])
            rows.add(name, "value_meas", d, q["units"])
            decisions.append(
                decision(
                    label,
                    "|E| <= U_val (ASME V&V 20)",
                    f"D = {fmt(d, q['units'])}",
                    vd.NOT_COMPARABLE,
                    "V&V 20",
                    why,
                    key=name,
                )
            )
            continue
        zs = np.asarray(wear["z"].values, dtype=float)
        reads = readings(a, q, (float(zs.min()), float(zs.max())))
        settle = [
            field
            for field, varies in (
                ("angle.direction", len({r.direction for r in reads}) > 1),
                ("layers.first", len({r.first for r in reads}) > 1),
                ("layers.z_centre", len({r.z_centre for r in reads}) > 1),
            )
            if varies
        ]
        outcomes = []
        for reading in reads:
            r_rows, r_decs = _one_reading(
                rep, name, q, reading, wear, cycles, studies, ensemble, criteria, label
            )
            outcomes.append((reading.label(rep.attrs), r_rows, r_decs))
        new_rows, new_decs = _combine(name, outcomes, " / ".join(settle))
        rows.rows.extend(new_rows)
        decisions.extend(new_decs)
