"""Simulation versus measurement: alignment, metrics, validation decisions.

:func:`compare` takes simulated and measured datasets (wear maps and/or motion records, told
apart by their variables), aligns them (:mod:`jointwear.compare.align`), computes the metrics of
:mod:`jointwear.compare.metrics` and decides every criterion (:class:`Criteria`) in one of four
states (:mod:`jointwear.compare.verdicts`): pass, fail, not assessed (an uncertainty it needs is
unknown) or not comparable (the data do not cover what it judges). Scalar quantities are judged by
ASME V&V 20 (``|E| <= U_val``) with uncertainties from :mod:`jointwear.compare.sources`: the
ensemble of simulations (``ensemble=``) for u_input, a verification study (``verification=``)
for u_num; what is unknown stays unknown.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd
import xarray as xr

import jointwear.compare.verdicts as vd
from jointwear import conventions
from jointwear.compare._choices import ALIGN_METHOD, DEFAULT_AXES
from jointwear.compare._decide import DECISION_COLUMNS, Rows
from jointwear.compare._motion import motion_metrics, rms_quantities
from jointwear.compare._wear import sim_quantities, wear_metrics
from jointwear.compare.align import MOTION_VARIABLES, align_time_series, align_wear_maps
from jointwear.compare.criteria import Criteria, load_criteria
from jointwear.compare.ensemble import WEAR_QUANTITIES, Ensemble, as_ensemble
from jointwear.compare.origin import side_origin
from jointwear.compare.reported import reported_metrics, split_reported
from jointwear.compare.sensitivity import SENSITIVITY_COLUMNS, sensitivity_table
from jointwear.compare.sources import Sources
from jointwear.compare.study import band_study_uncertainty, is_study
from jointwear.compare.verification import GCI, LeastSquaresStudy, numerical_uncertainty
from jointwear.errors import BadInputError

__all__ = [
    "Criteria",
    "Comparison",
    "compare",
    "load_criteria",
    "DEFAULT_AXES",
]


@dataclass(frozen=True)
class Comparison:
    """Result of :func:`compare`.

    Attributes
    ----------
    wear : Dataset or None
        Aligned wear maps over ``(z, theta)`` (see :func:`align_wear_maps`), the whole simulated
        map over ``(z_sim, theta_sim)`` and, with an ensemble that keeps its maps,
        ``wear_depth_sim_ensemble`` over ``(run, z, theta)``.
    motion : Dataset or None
        Aligned motion over ``time`` (see :func:`align_time_series`), with ensemble members
        ``<var>_sim_ensemble`` over ``(run, time, ...)`` when available.
    metrics : DataFrame
        Tidy table: quantity, metric, value, units, long_name, definition, basis.
    decisions : DataFrame
        Decision card: quantity, criterion, value, state, basis, reason, passed.
    notes : tuple of str
        What was not compared and why.
    criteria : Criteria
        The criteria used.
    data_origin : dict
        ``{"simulation": ..., "measurement": ...}``: what each side's numbers are.
    partial : tuple of str
        Parts that were not compared (a side without wear maps or motion).
    sensitivity : DataFrame
        Which inputs dominate each quantity: the ensemble's Sobol indices (S1, ST), else
        squared standardised regression coefficients in the S1 column; ``estimator`` names which
        (``S1`` or ``SRC²``) and ``method`` how far an SRC² is a variance share
        (:mod:`jointwear.compare.sensitivity`).
    """

    wear: xr.Dataset | None
    motion: xr.Dataset | None
    metrics: pd.DataFrame
    decisions: pd.DataFrame
    notes: tuple[str, ...] = ()
    criteria: Criteria = field(default_factory=Criteria)
    data_origin: Mapping[str, str] = field(default_factory=dict)
    partial: tuple[str, ...] = ()
    sensitivity: pd.DataFrame = field(
        default_factory=lambda: pd.DataFrame(columns=SENSITIVITY_COLUMNS)
    )

    @property
    def states(self) -> pd.Series:
        """State of every decision."""
        return self.decisions["state"]

    @property
    def passed(self) -> bool:
        """True when every decision passed (and there is at least one)."""
        return bool(len(self.decisions)) and bool((self.states == vd.PASS).all())

    @property
    def any_failed(self) -> bool:
        """True when a criterion failed (exit code 1)."""
        return bool((self.states == vd.FAIL).any())

    @property
    def complete(self) -> bool:
        """True when nothing is not assessed, not comparable or left out (``--strict``)."""
        undecided = self.states.isin([vd.NOT_ASSESSED, vd.NOT_COMPARABLE]).any()
        return not undecided and not self.partial and bool(len(self.decisions))

    def quantities(self, state: str) -> list[str]:
        """Quantities with a decision in ``state``."""
        return [str(q) for q in self.decisions.loc[self.states == state, "quantity"]]

    def failed(self) -> list[str]:
        """Quantities whose criterion failed."""
        return self.quantities(vd.FAIL)

    def summary(self) -> str:
        """``"12 criteria: 3 pass, 1 fail, ..."``."""
        return vd.summary_line(self.states)

    def resolution(self) -> str:
        """``"this comparison detects maximum wear depth errors outside −24 %…+40 %; ..."``:
        the resolution of every decided V&V 20 criterion ('' when none is decided)."""
        decided = self.states.isin([vd.PASS, vd.FAIL])
        rows = self.decisions[decided & (self.decisions.resolution.astype(str) != "")]
        parts = [
            f"{r.quantity}: {str(r.resolution).removeprefix('detects ')}" for r in rows.itertuples()
        ]
        return "this comparison detects " + "; ".join(parts) if parts else ""

    def value(self, quantity: str, metric: str) -> float:
        """One number of the metrics table."""
        rows = self.metrics[(self.metrics.quantity == quantity) & (self.metrics.metric == metric)]
        if rows.empty:
            raise KeyError(f"no metric {metric!r} for quantity {quantity!r}")
        return float(rows["value"].iloc[0])

    def state(self, quantity: str, basis: str | None = None) -> str:
        """State of the (first) decision on ``quantity`` (optionally of one ``basis``).

        ``quantity`` is the card's label, with or without its band (``"maximum wear depth"``
        finds ``"maximum wear depth within z = −6…+6 mm"``).
        """
        label = self.decisions.quantity.astype(str)
        # a wear criterion is labelled with its band ("maximum wear depth within z = ...")
        d = self.decisions[(label == quantity) | label.str.startswith(quantity + " within ")]
        if basis is not None:
            d = d[d.basis == basis]
        if d.empty:
            raise KeyError(f"no decision on {quantity!r}")
        return str(d["state"].iloc[0])

    def to_dataset(self) -> xr.Dataset:
        """Aligned fields, differences, metrics (scalar variables) and decisions in one Dataset."""
        from jointwear.compare.storage import to_dataset

        return to_dataset(self)


def _split(objs: xr.Dataset | Sequence[xr.Dataset]) -> tuple[xr.Dataset | None, xr.Dataset | None]:
    """The wear-map dataset and the motion dataset among ``objs``."""
    items = [objs] if isinstance(objs, (xr.Dataset, xr.DataArray)) else list(objs)
    wear = motion = None
    for ds in items:
        if isinstance(ds, xr.DataArray):
            ds = ds.to_dataset(name=ds.name or "wear_depth")
        if "wear_depth" in ds.data_vars and wear is None:
            wear = ds
        if "time" in ds.coords and any(
            v in ds.data_vars for v in (*MOTION_VARIABLES, "follower_position")
        ):
            if motion is None:
                motion = ds
    return wear, motion


def _select_axes(ds: xr.Dataset, axes: Sequence[str] | None) -> tuple[xr.Dataset, list[str]]:
    """Keep the requested vector components; return the dataset and the components left out."""
    if axes is None or "axis" not in ds.dims:
        return ds, []
    have = [str(a) for a in ds["axis"].values]
    bad = [a for a in axes if a not in ("x", "y", "z")]
    if bad:
        raise BadInputError(f"axes: {', '.join(bad)} - components are 'x', 'y' and 'z'")
    keep = [a for a in have if a in axes]
    if not keep:
        raise BadInputError(
            f"none of the requested components ({', '.join(axes)}) is in the motion record "
            f"(it has {', '.join(have)})"
        )
    return ds.sel(axis=keep), [a for a in have if a not in axes]


def _ensemble_wear(
    ens: Ensemble, m_wear: xr.Dataset, al: xr.Dataset, cycles: float | None
) -> tuple[dict[str, list[tuple[int, np.ndarray]]], xr.DataArray | None]:
    """Per-run compared wear quantities and aligned maps from ensembles that keep ``wear_depth``."""
    values: dict[str, list[tuple[int, np.ndarray]]] = {}
    band = None
    step = 360.0 / al.sizes["theta"]
    for i, da in ens.field("wear_depth"):
        ds = ens.datasets[i]
        per_run: dict[str, list[float]] = {}
        maps = []
        snap = cycles
        if "cycles" in da.dims:
            avail = np.asarray(da["cycles"].values, dtype=float)
            if snap is None or not np.any(np.isclose(avail, snap, rtol=1e-9)):
                snap = float(avail[-1])
        for r in range(da.sizes["run"]):
            member = da.isel(run=r, drop=True)
            if not np.any(np.isfinite(member.values)):
                for key in per_run:
                    per_run[key].append(np.nan)
                maps.append(np.full(al["wear_depth_sim"].shape, np.nan))
                continue
            mds = member.to_dataset(name="wear_depth")
            radius = {k: v for k, v in al.attrs.items() if k == "bearing_radius_m"}
            mds.attrs = {**ds.attrs, **radius}
            # on the compared grid: a member run on another grid than the simulation is
            # averaged over the same cells (else its band could not be used)
            a = align_wear_maps(mds, m_wear, cycles=snap, theta_step_deg=step)
            q = sim_quantities(a)
            for key, v in q.items():
                per_run.setdefault(key, [np.nan] * r).append(v)
            same = a["wear_depth_sim"].shape == al["wear_depth_sim"].shape and np.allclose(
                a["z"], al["z"]
            )
            maps.append(np.asarray(a["wear_depth_sim"].values) if same else np.nan)
        for key, vals in per_run.items():
            values.setdefault(key, []).append((i, np.asarray(vals, dtype=float)))
        if band is None:
            band = xr.DataArray(
                np.stack([np.broadcast_to(m, al["wear_depth_sim"].shape) for m in maps]),
                dims=("run", "z", "theta"),
                attrs={
                    "units": "m",
                    "long_name": f"simulated wear depth of each run of {ens.names[i]}",
                },
            )
    return values, band


def _ensemble_motion(
    ens: Ensemble, m_motion: xr.Dataset, al: xr.Dataset, kwargs: dict[str, Any]
) -> tuple[dict[str, list[tuple[int, np.ndarray]]], dict[str, xr.DataArray]]:
    """Per-run RMS of the compared motion components from ensembles that keep motion histories."""
    values: dict[str, list[tuple[int, np.ndarray]]] = {}
    bands: dict[str, xr.DataArray] = {}
    names = [str(v)[: -len("_sim")] for v in al.data_vars if str(v).endswith("_sim")]
    for i, ds in enumerate(ens.datasets):
        have = [n for n in names if n in ds.data_vars and {"run", "time"} <= set(ds[n].dims)]
        if not have:
            continue
        per_run: dict[str, list[float]] = {}
        members: dict[str, list[np.ndarray]] = {n: [] for n in have}
        for r in range(ds.sizes["run"]):
            keep = [*have, *(["crank_angle"] if "crank_angle" in ds else [])]
            member = ds[keep].isel(run=r, drop=True)
            t = np.asarray(member["time"].values, dtype=float)
            finite = np.isfinite(t) & np.isfinite(
                np.asarray(member[have[0]].values, dtype=float).reshape(t.size, -1)
            ).all(axis=1)
            try:
                a = align_time_series(member.isel(time=np.flatnonzero(finite)), m_motion, **kwargs)
            except BadInputError:
                a = None
            q = rms_quantities(a) if a is not None else {}
            for key in set(per_run) | set(q):
                per_run.setdefault(key, [np.nan] * r).append(q.get(key, np.nan))
            for n in have:
                shape = al[f"{n}_sim"].shape
                ok = a is not None and f"{n}_sim" in a and a[f"{n}_sim"].shape == shape
                members[n].append(
                    np.asarray(a[f"{n}_sim"].values) if ok else np.full(shape, np.nan)
                )
        for key, vals in per_run.items():
            values.setdefault(key, []).append((i, np.asarray(vals, dtype=float)))
        for n in have:
            if n not in bands:
                bands[n] = xr.DataArray(
                    np.stack(members[n]),
                    dims=("run", *al[f"{n}_sim"].dims),
                    attrs={
                        "units": al[f"{n}_sim"].attrs.get("units", ""),
                        "long_name": f"simulated {n} of each run of {ens.names[i]}",
                    },
                )
    return values, bands


#: What ``compare(verification=...)`` takes: sim verify studies or 1-D refinement datasets, or
#: their u_num per quantity.
Verification = xr.Dataset | Sequence[xr.Dataset] | Mapping[str, GCI | LeastSquaresStudy]


def _verification(
    verification,
) -> tuple[Mapping[str, GCI | LeastSquaresStudy], list[xr.Dataset]]:
    """(u_num per quantity of 1-D refinement data, sim verify studies) of ``verification``."""
    studies: list[xr.Dataset] = []
    if verification is None:
        gci: Mapping[str, GCI | LeastSquaresStudy] = {}
    elif isinstance(verification, xr.Dataset) or not isinstance(verification, Mapping):
        # a Dataset is a Mapping too: test it first. sim verify studies (contract) apart from
        # the 1-D refinement datasets (GCI or least squares, by their number of levels)
        items = [verification] if isinstance(verification, xr.Dataset) else list(verification)
        studies = [ds for ds in items if is_study(ds)]
        older = [ds for ds in items if not is_study(ds)]
        gci = numerical_uncertainty(older) if older else {}
    else:
        gci = verification
    return gci, studies


def _compare_wear(
    s_wear, m_wear, cycles, theta_step_deg, ens, studies, criteria, gci, rows, decisions, notes,
    field_values,
) -> xr.Dataset:  # fmt: skip
    """Align the wear maps and add their metrics and decisions (``rows``, ``decisions``,
    ``notes`` and ``field_values`` are filled in)."""
    wear = align_wear_maps(s_wear, m_wear, cycles=cycles, theta_step_deg=theta_step_deg)
    if ens is not None:
        values, band = _ensemble_wear(ens, m_wear, wear, float(wear.attrs["cycles_sim"]))
        field_values.update(values)
        if band is not None:
            wear["wear_depth_sim_ensemble"] = band
    band_u = (
        band_study_uncertainty(
            studies,
            m_wear,
            WEAR_QUANTITIES,
            theta_step_deg=theta_step_deg,
            radius=wear.attrs.get("bearing_radius_m"),
        )
        if studies
        else {}
    )
    src = Sources(criteria, ens, gci, float(wear.attrs["cycles_sim"]), field_values, studies=band_u)
    domain = wear_metrics(wear, rows, decisions, src)
    if domain:
        notes.append(domain)
    if cycles is None and not np.isfinite(float(wear.attrs.get("cycles_meas", np.nan))):
        notes.append(
            "wear cycles: the measured map does not state after how many crank cycles it was "
            f"taken; it was compared with the simulation after {wear.attrs['cycles_sim']:g} "
            "cycles (its last snapshot) - give cycles= / --cycles, or a 'cycles' attribute"
        )
    return wear


def _partial_inputs(sims, meass) -> list[str]:
    """A line for every input that is the partial result of an interrupted run (never judged
    as if it had finished)."""
    partial: list[str] = []
    for side, group in (("simulation", sims), ("measurement", meass)):
        for ds in group:
            status = conventions.describe_status(ds) if isinstance(ds, xr.Dataset) else None
            if status:
                partial.append(f"{side} input {ds.attrs.get('title', '')!r}: {status}")
    return partial


def _add_motion_ensemble(ens, axes, m_sel, motion, kwargs, field_values) -> None:
    """The ensemble's motion values (into ``field_values``) and bands (into ``motion``)."""
    ens_sel = Ensemble(
        tuple(_select_axes(d, axes)[0] if "axis" in d.dims else d for d in ens.datasets),
        ens.names,
    )
    values, bands = _ensemble_motion(ens_sel, m_sel, motion, kwargs)
    field_values.update(values)
    for n, band in bands.items():
        motion[f"{n}_sim_ensemble"] = band


def _rig_notes(
    sim: xr.Dataset | None, studies: Sequence[xr.Dataset], ens: Ensemble | None, allow: bool
) -> list[str]:
    """Each study and ensemble checked against the simulation's rig
    (:func:`jointwear.compare.rig.check_rig`): the notes; refused when another rig is not
    allowed."""
    from jointwear.compare.rig import check_rig

    notes = []
    for i, study in enumerate(studies):
        name = str(study.attrs.get("title", f"verification study {i + 1}"))
        notes.append(check_rig(sim, study, f"verification study {name!r}", allow_other_rig=allow))
    for i, ds in enumerate(ens.datasets if ens is not None else ()):
        what = f"ensemble {ens.names[i]!r}"
        notes.append(check_rig(sim, ds, what, allow_other_rig=allow, varied=ens.parameters(i)))
    return [n for n in notes if n]


def compare(
    sim: xr.Dataset | Sequence[xr.Dataset],
    meas: xr.Dataset | Sequence[xr.Dataset],
    *,
    criteria: Criteria | None = None,
    cycles: float | None = None,
    theta_step_deg: float | None = None,
    motion_method: str = ALIGN_METHOD,
    period_s: float | None = None,
    variables: Sequence[str] | None = None,
    axes: Sequence[str] | None = DEFAULT_AXES,
    ensemble: xr.Dataset | Sequence[xr.Dataset] | Ensemble | None = None,
    verification: Verification | None = None,
    allow_other_rig: bool = False,
) -> Comparison:
    """Compare simulation and measurement: wear maps and/or motion, detected from the variables.

    Parameters
    ----------
    sim, meas : Dataset or sequence of Datasets
        Simulated and measured data following the data contract. A dataset with
        ``wear_depth`` is a wear map; one with a ``time`` coordinate and a motion variable
        (``follower_velocity``, ``journal_offset``, ...) a motion record.
    criteria : Criteria, optional
        Validation criteria (default :class:`Criteria`).
    cycles : float, optional
        Crank cycles at which to compare the wear maps (default: the measurement's).
    theta_step_deg : float, optional
        Angular step of the common wear grid [degree] (default: the coarser input's).
    motion_method : {"auto", "crank_angle", "cross_correlation"}
        Phase alignment of the motion records.
    period_s : float, optional
        Crank period [s] (default from the crank angle).
    variables : sequence of str, optional
        Motion variables to compare (default: all in common).
    axes : sequence of str or None
        Vector components of the motion to compare (default in-plane ``("x", "y")``; None =
        every component both sides have).
    ensemble : Dataset, sequence of Datasets or Ensemble, optional
        Ensembles of simulations over uncertain inputs (``run`` dimension); their spread is
        the u_input of each compared quantity (:mod:`jointwear.compare.ensemble`).
    verification : Dataset(s) or mapping of GCI / LeastSquaresStudy, optional
        Verification studies for u_num: a ``jointwear sim verify`` study (its stored wear maps
        give u_num of every band quantity, :mod:`jointwear.compare.study`), or 1-D
        refinement datasets (quantities over a refinement parameter: the GCI of three
        solutions, Eça & Hoekstra's least squares of four or more,
        :func:`jointwear.compare.verification.refinement_study`).
    allow_other_rig : bool
        Use a verification study or an ensemble whose recorded rig parameters differ from the
        simulation's (labelled in the notes); by default that is refused
        (:mod:`jointwear.compare.rig`).

    Returns
    -------
    Comparison
        Aligned data, metrics table, decision card (four states), notes, data origin.

    Raises
    ------
    BadInputError
        Nothing to compare, inputs that cannot be aligned, a malformed ensemble, or a study or
        an ensemble of another rig (without ``allow_other_rig``).
    ConventionError
        A wear map does not state its angle convention.

    Examples
    --------
    A simulated wear map (prescribed contact) against itself as the "measurement", with stated
    uncertainties: every decided criterion passes (the axial distribution of the wear needs an
    ensemble of maps: a stated relative u_input says nothing of the form); a bearing that wore
    50 % more fails the depth and the cylindricity:

    >>> from jointwear.compare import Criteria, compare
    >>> from jointwear.sim import BearingGrid, WearSettings, WinklerContact, simulate_wear
    >>> fixed, contact = WearSettings(scheme="fixed", dn=500), WinklerContact(BearingGrid(4, 36))
    >>> sim = simulate_wear(contact=contact, cycles=2000, snapshots=[1000, 2000], settings=fixed)
    >>> meas = sim.isel(cycles=-1, drop=True)[["wear_depth"]].copy(deep=True)
    >>> meas = meas.assign_attrs(data_origin="synthetic", cycles=2000)
    >>> u_d = 0.02 * float(meas["wear_depth"].max())  # the measurement's u_D [m]
    >>> meas["wear_depth_u"] = meas["wear_depth"].copy(data=0 * meas["wear_depth"].values + u_d)
    >>> stated = Criteria(wear_u_num_rel=0.05, wear_u_input_rel=0.1)  # u_num 5 %, u_input 10 %
    >>> compare(sim, meas, criteria=stated).summary()
    '8 criteria: 7 pass, 1 not assessed'
    >>> meas["wear_depth"].values *= 1.5  # a bearing that wore 50 % more
    >>> compare(sim, meas, criteria=stated).failed()
    ['maximum wear depth within z = −7.5…+7.5 mm', 'cylindricity of the wear (LSCY) within z = −7.5…+7.5 mm']
    """
    criteria = criteria or Criteria()
    ens = as_ensemble(ensemble)
    gci, studies = _verification(verification)
    sims = [sim] if isinstance(sim, (xr.Dataset, xr.DataArray)) else list(sim)
    meass = [meas] if isinstance(meas, (xr.Dataset, xr.DataArray)) else list(meas)
    s_wear, s_motion = _split(sims)
    reported, meass_maps = split_reported(meass)
    m_wear, m_motion = _split(meass_maps)
    rows = Rows()
    decisions: list[dict[str, Any]] = []
    notes = _rig_notes(s_wear if s_wear is not None else s_motion, studies, ens, allow_other_rig)
    partial = _partial_inputs(sims, meass)
    wear = motion = None
    field_values: dict[str, list[tuple[int, np.ndarray]]] = {}
    if s_wear is not None and m_wear is not None:
        wear = _compare_wear(
            s_wear, m_wear, cycles, theta_step_deg, ens, studies, criteria, gci,
            rows, decisions, notes, field_values,
        )  # fmt: skip
    elif (s_wear is not None and not reported) or m_wear is not None:
        side = "measurement" if s_wear is not None else "simulation"
        partial.append(f"wear maps not compared: the {side} has no wear map (wear_depth)")
    if s_motion is not None and m_motion is not None:
        s_sel, s_out = _select_axes(s_motion, axes)
        m_sel, m_out = _select_axes(m_motion, axes)
        left_out = sorted(set(s_out) | set(m_out))
        kwargs = {"variables": variables, "method": motion_method, "period_s": period_s}
        motion = align_time_series(s_sel, m_sel, **kwargs)
        if left_out:
            notes.append(
                f"motion component(s) {', '.join(left_out)} not compared: only "
                f"{', '.join(axes or ())} by default (the mechanism is planar; out-of-plane rig "
                "motion is not a prediction of it) - ask for them with axes= / --axis"
            )
        if ens is not None:
            _add_motion_ensemble(ens, axes, m_sel, motion, kwargs, field_values)
        src = Sources(criteria, ens, gci, None, field_values)
        motion_metrics(motion, rows, decisions, src)
    elif s_motion is not None or m_motion is not None:
        side = "measurement" if s_motion is not None else "simulation"
        partial.append(f"motion not compared: the {side} has no motion record over time")
    for rep in reported:  # reported measurements (a lab sheet's or a paper's numbers)
        reported_metrics(
            s_wear, rep, rows, decisions, notes, criteria=criteria, ensemble=ens,
            verification=verification if isinstance(verification, Sequence) else
            [verification] if isinstance(verification, xr.Dataset) else [],
        )  # fmt: skip
    if wear is None and motion is None and not reported:
        raise BadInputError(
            "nothing to compare: give a wear map (wear_depth over z, theta) and/or a motion "
            "record (follower_velocity, journal_offset, ... over time) on both sides"
        )
    card = pd.DataFrame(decisions, columns=DECISION_COLUMNS)
    card["passed"] = card["passed"].astype(bool)
    metrics = rows.frame()
    compared = list(dict.fromkeys(metrics.loc[metrics.metric == "value_sim", "quantity"]))
    return Comparison(
        wear=wear,
        motion=motion,
        metrics=metrics,
        decisions=card,
        notes=tuple([*partial, *notes]),
        criteria=criteria,
        data_origin={"simulation": side_origin(sims), "measurement": side_origin(meass)},
        partial=tuple(partial),
        sensitivity=sensitivity_table(ens, compared, field_values),
    )
