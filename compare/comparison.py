"""Simulation versus measurement: alignment, metrics, validation decisions, tidy table, netCDF.

:func:`compare` takes simulated and measured datasets (wear maps and/or motion records, told
apart by their variables), aligns them (:mod:`jointwear.compare.align`), computes the metrics of
:mod:`jointwear.compare.metrics` and decides, per quantity, whether the simulation passes its
validation criterion (:class:`Criteria`): the ASME V&V 20 test ``|E| <= U_val`` where
uncertainties are available, otherwise a stated threshold.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import xarray as xr

import jointwear.compare.metrics as mt
from jointwear import io
from jointwear.compare.align import MOTION_VARIABLES, align_time_series, align_wear_maps
from jointwear.errors import BadInputError, ParameterError
from jointwear.params import from_mapping, read_toml

__all__ = [
    "Criteria",
    "Comparison",
    "compare",
    "load_criteria",
    "metrics_table",
    "save_comparison",
    "load_comparison",
]

METRIC_COLUMNS = ["quantity", "metric", "value", "units", "long_name", "definition"]
DECISION_COLUMNS = ["quantity", "criterion", "value", "passed", "basis"]


@dataclass(frozen=True)
class Criteria:
    """Validation criteria and uncertainty assumptions (all editable from a TOML file).

    Parameters
    ----------
    k : float
        Coverage factor of the expanded validation uncertainty ``U_val = k u_val`` [1].
    wear_nrmse_max : float
        Largest acceptable normalised RMSE of the wear map [1].
    wear_r_min : float
        Smallest acceptable Pearson correlation between the simulated and measured wear maps
        [1]. Together with ``wear_nrmse_max`` it makes the shape criterion: a low NRMSE alone
        is also reached by a simulation that predicts almost no wear against a peaky
        measurement.
    max_angle_error_deg : float
        Largest acceptable error of the angle of maximum wear [degree].
    max_z_error_m : float
        Largest acceptable error of the axial position of maximum wear [m].
    relative_error_max : float
        Largest acceptable ``|S - D| / |D|`` of a scalar quantity when no uncertainty is known
        (max wear depth, worn volume, cylindricity, RMS motion) [1].
    motion_sg_c_max : float
        Largest acceptable Sprague-Geers comprehensive error of a motion component [1].
    wear_u_input_rel, motion_u_input_rel : float
        Relative standard uncertainty of the simulated quantities from their inputs (e.g. the
        wear coefficient), ``u_input = rel * |S|`` [1]. 0 = not assessed.
    wear_u_num_rel, motion_u_num_rel : float
        Relative numerical standard uncertainty used where the simulation states none
        (``<name>_u``) [1]. 0 = not assessed.
    """

    k: float = 2.0
    wear_nrmse_max: float = 0.25
    wear_r_min: float = 0.5
    max_angle_error_deg: float = 30.0
    max_z_error_m: float = 3.0e-3
    relative_error_max: float = 0.30
    motion_sg_c_max: float = 0.30
    wear_u_input_rel: float = 0.0
    motion_u_input_rel: float = 0.0
    wear_u_num_rel: float = 0.0
    motion_u_num_rel: float = 0.0

    def __post_init__(self) -> None:
        for f in self.__dataclass_fields__:
            value = getattr(self, f)
            if not (np.isfinite(value) and value >= 0):
                raise ParameterError(f"criteria.{f} must be a finite number >= 0, got {value!r}")
        if self.k == 0:
            raise ParameterError("criteria.k (coverage factor) must be > 0")


def load_criteria(path: str | Path | None) -> Criteria:
    """Criteria from a TOML file (keys of :class:`Criteria`, optionally in a ``[criteria]`` table)."""
    if path is None:
        return Criteria()
    data = read_toml(path)
    data = data.get("criteria", data)
    return from_mapping(Criteria, data, where="criteria")


@dataclass(frozen=True)
class Comparison:
    """Result of :func:`compare`.

    Attributes
    ----------
    wear : Dataset or None
        Aligned wear maps over ``(z, theta)`` (see :func:`align_wear_maps`).
    motion : Dataset or None
        Aligned motion over ``time`` (see :func:`align_time_series`).
    metrics : DataFrame
        Tidy table: quantity, metric, value, units, long_name, definition.
    decisions : DataFrame
        Decision card: quantity, criterion, value, passed, basis.
    notes : tuple of str
        What was not compared and why.
    criteria : Criteria
        The criteria used.
    """

    wear: xr.Dataset | None
    motion: xr.Dataset | None
    metrics: pd.DataFrame
    decisions: pd.DataFrame
    notes: tuple[str, ...] = ()
    criteria: Criteria = field(default_factory=Criteria)

    @property
    def passed(self) -> bool:
        """True when every decision passed (and there is at least one)."""
        return bool(len(self.decisions)) and bool(self.decisions["passed"].all())

    def failed(self) -> list[str]:
        """Quantities whose criterion failed."""
        return [str(q) for q in self.decisions.loc[~self.decisions["passed"], "quantity"]]

    def value(self, quantity: str, metric: str) -> float:
        """One number of the metrics table."""
        rows = self.metrics[(self.metrics.quantity == quantity) & (self.metrics.metric == metric)]
        if rows.empty:
            raise KeyError(f"no metric {metric!r} for quantity {quantity!r}")
        return float(rows["value"].iloc[0])

    def to_dataset(self) -> xr.Dataset:
        """Aligned fields, differences, metrics (scalar variables) and decisions in one Dataset."""
        return _to_dataset(self)


# --------------------------------------------------------------------------- helpers


class _Rows:
    """Collects metric rows with units and definitions."""

    def __init__(self) -> None:
        self.rows: list[dict[str, Any]] = []

    def add(self, quantity: str, metric: str, value: float, units: str) -> None:
        long, definition, rule = mt.DEFINITIONS[metric]
        unit = units if rule == "same" else rule
        self.rows.append(
            {
                "quantity": quantity,
                "metric": metric,
                "value": float(value),
                "units": unit,
                "long_name": long,
                "definition": definition,
            }
        )

    def frame(self) -> pd.DataFrame:
        return pd.DataFrame(self.rows, columns=METRIC_COLUMNS)


def _fmt(value: float, units: str) -> str:
    if not np.isfinite(value):
        return "n/a"
    if units == "m" and abs(value) < 1e-2:
        return f"{value * 1e6:.3g} µm"
    if units == "m3":
        return f"{value * 1e9:.3g} mm³"
    if units == "1":
        return f"{value:.3g}"
    return f"{value:.4g} {units}"


def _scalar_decision(
    rows: _Rows,
    decisions: list[dict[str, Any]],
    quantity: str,
    label: str,
    s: float,
    d: float,
    units: str,
    *,
    u_num: float,
    u_input: float,
    u_d: float,
    criteria: Criteria,
) -> None:
    rows.add(quantity, "value_sim", s, units)
    rows.add(quantity, "value_meas", d, units)
    rel = (s - d) / abs(d) if d != 0 else float("nan")
    rows.add(quantity, "relative_error", rel, units)
    if not (np.isfinite(s) and np.isfinite(d)):
        return
    res = mt.vv20(s, d, u_num=u_num, u_input=u_input, u_d=u_d, k=criteria.k)
    if res.u_val > 0:
        for name, value in (
            ("E", res.E),
            ("u_num", res.u_num),
            ("u_input", res.u_input),
            ("u_D", res.u_D),
            ("u_val", res.u_val),
            ("U_val", res.U_val),
        ):
            rows.add(quantity, name, value, units)
        decisions.append(
            {
                "quantity": label,
                "criterion": f"|E| <= U_val = {criteria.k:g} u_val (ASME V&V 20)",
                "value": f"|E| = {_fmt(abs(res.E), units)}, U_val = {_fmt(res.U_val, units)}",
                "passed": res.passed,
                "basis": "V&V 20",
            }
        )
    else:
        rows.add(quantity, "E", res.E, units)
        ok = bool(np.isfinite(rel) and abs(rel) <= criteria.relative_error_max)
        decisions.append(
            {
                "quantity": label,
                "criterion": f"|S - D| / |D| <= {criteria.relative_error_max:g} (no uncertainty given)",
                "value": f"{rel:+.3g} (S = {_fmt(s, units)}, D = {_fmt(d, units)})",
                "passed": ok,
                "basis": "threshold",
            }
        )


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


# --------------------------------------------------------------------------- wear


def _wear_metrics(
    al: xr.Dataset, rows: _Rows, decisions: list[dict[str, Any]], criteria: Criteria
) -> None:
    s = np.asarray(al["wear_depth_sim"].values)
    d = np.asarray(al["wear_depth_meas"].values)
    z = np.asarray(al["z"].values)
    th = np.asarray(al["theta"].values)
    q = "wear_depth"
    rows.add(q, "rmse", mt.rmse(s, d), "m")
    nr = mt.nrmse(s, d)
    rows.add(q, "nrmse", nr, "m")
    rows.add(q, "pearson_r", mt.pearson_r(s, d), "m")
    rows.add(q, "mean_error", float(np.nanmean(s - d)), "m")
    rows.add(q, "max_abs_error", float(np.nanmax(np.abs(s - d))), "m")
    rows.add(q, "area_validation_metric", mt.area_validation_metric(s, d), "m")
    vs, zs, ts = mt.max_location(s, z, th)
    vd, zd, td = mt.max_location(d, z, th)
    ang = float(mt.wrap_angle_deg(ts - td))
    rows.add(q, "max_angle_error", ang, "m")
    rows.add(q, "max_z_error", zs - zd, "m")
    r = mt.pearson_r(s, d)
    decisions.append(
        {
            "quantity": "wear map shape",
            "criterion": f"NRMSE <= {criteria.wear_nrmse_max:g} and r >= {criteria.wear_r_min:g}",
            "value": f"NRMSE = {nr:.3g}, r = {r:.3g}",
            "passed": bool(
                np.isfinite(nr)
                and nr <= criteria.wear_nrmse_max
                and np.isfinite(r)
                and r >= criteria.wear_r_min
            ),
            "basis": "threshold",
        }
    )
    decisions.append(
        {
            "quantity": "angle of maximum wear",
            "criterion": f"|error| <= {criteria.max_angle_error_deg:g} degree",
            "value": f"{ang:+.1f} degree (sim {ts:.1f}, meas {td:.1f})",
            "passed": abs(ang) <= criteria.max_angle_error_deg,
            "basis": "threshold",
        }
    )
    decisions.append(
        {
            "quantity": "axial position of maximum wear",
            "criterion": f"|error| <= {criteria.max_z_error_m * 1e3:g} mm",
            "value": f"{(zs - zd) * 1e3:+.2f} mm (sim {zs * 1e3:+.2f}, meas {zd * 1e3:+.2f})",
            "passed": abs(zs - zd) <= criteria.max_z_error_m + 1e-12,
            "basis": "threshold",
        }
    )
    us = np.asarray(al["wear_depth_sim_u"].values) if "wear_depth_sim_u" in al else None
    ud = np.asarray(al["wear_depth_meas_u"].values) if "wear_depth_meas_u" in al else None

    def at_max(u: np.ndarray | None, field: np.ndarray) -> float:
        if u is None:
            return 0.0
        i, j = np.unravel_index(np.nanargmax(field), field.shape)
        return float(u[i, j])

    def u_num_of(value: float, u_field: float) -> float:
        return u_field if u_field > 0 else criteria.wear_u_num_rel * abs(value)

    _scalar_decision(
        rows,
        decisions,
        "max_wear_depth",
        "maximum wear depth",
        vs,
        vd,
        "m",
        u_num=u_num_of(vs, at_max(us, s)),
        u_input=criteria.wear_u_input_rel * abs(vs),
        u_d=at_max(ud, d),
        criteria=criteria,
    )
    radius = al.attrs.get("bearing_radius_m")
    if radius is not None and len(z) > 1:
        v_s = mt.worn_volume(s, z, th, float(radius))
        v_d = mt.worn_volume(d, z, th, float(radius))
        u_vs = mt.worn_volume(us, z, th, float(radius)) if us is not None else 0.0
        u_vd = mt.worn_volume(ud, z, th, float(radius)) if ud is not None else 0.0
        _scalar_decision(
            rows,
            decisions,
            "worn_volume",
            "worn volume (overlapping width)",
            v_s,
            v_d,
            "m3",
            u_num=u_num_of(v_s, u_vs),
            u_input=criteria.wear_u_input_rel * abs(v_s),
            u_d=u_vd,
            criteria=criteria,
        )
    if len(z) > 1:
        c_s = mt.lsq_cylindricity(s, z, th)
        c_d = mt.lsq_cylindricity(d, z, th)
        rms_u = lambda u: float(np.sqrt(np.nanmean(u**2))) if u is not None else 0.0  # noqa: E731
        _scalar_decision(
            rows,
            decisions,
            "cylindricity",
            "cylindricity of the wear (LSCY, common grid)",
            c_s,
            c_d,
            "m",
            u_num=u_num_of(c_s, math.sqrt(2) * rms_u(us)),
            u_input=criteria.wear_u_input_rel * abs(c_s),
            u_d=math.sqrt(2) * rms_u(ud),
            criteria=criteria,
        )
    cs, cd = al.attrs.get("cylindricity_stated_sim_m"), al.attrs.get("cylindricity_stated_meas_m")
    if cs is not None and cd is not None:
        rows.add("cylindricity_stated", "value_sim", float(cs), "m")
        rows.add("cylindricity_stated", "value_meas", float(cd), "m")
        rows.add("cylindricity_stated", "E", float(cs) - float(cd), "m")
    u_model = np.hypot(
        criteria.wear_u_input_rel * s, us if us is not None else criteria.wear_u_num_rel * s
    )
    if us is not None or ud is not None or np.any(u_model > 0):
        u_tot = np.sqrt(u_model**2 + (0 if ud is None else ud**2))
        ok = np.isfinite(s - d) & np.isfinite(u_tot)
        frac = float(np.mean(np.abs(s - d)[ok] <= criteria.k * u_tot[ok])) if ok.any() else np.nan
        rows.add(q, "fraction_within_U_val", frac, "m")


# --------------------------------------------------------------------------- motion


def _motion_metrics(
    al: xr.Dataset, rows: _Rows, decisions: list[dict[str, Any]], criteria: Criteria
) -> None:
    names = [str(v)[: -len("_sim")] for v in al.data_vars if str(v).endswith("_sim")]
    for name in names:
        sim = al[f"{name}_sim"]
        meas = al[f"{name}_meas"]
        units = str(sim.attrs.get("units", "1"))
        comps = [str(c) for c in al["axis"].values] if "axis" in sim.dims else [None]
        for c in comps:
            s = np.asarray(sim.sel(axis=c).values if c else sim.values, dtype=float)
            d = np.asarray(meas.sel(axis=c).values if c else meas.values, dtype=float)
            ok = np.isfinite(s) & np.isfinite(d)
            if ok.sum() < 4:
                continue
            s, d = s[ok], d[ok]
            q = f"{name}_{c}" if c else name
            label = q.replace("_", " ")
            rows.add(q, "rmse", mt.rmse(s, d), units)
            rows.add(q, "nrmse", mt.nrmse(s, d), units)
            rows.add(q, "pearson_r", mt.pearson_r(s, d), units)
            sg = mt.sprague_geers(s, d)
            rows.add(q, "sg_magnitude", sg.M, units)
            rows.add(q, "sg_phase", sg.P, units)
            rows.add(q, "sg_comprehensive", sg.C, units)
            rows.add(q, "area_validation_metric", mt.area_validation_metric(s, d), units)
            decisions.append(
                {
                    "quantity": f"{label} history",
                    "criterion": f"Sprague-Geers C <= {criteria.motion_sg_c_max:g}",
                    "value": f"C = {sg.C:.3g} (M = {sg.M:+.3g}, P = {sg.P:.3g})",
                    "passed": bool(np.isfinite(sg.C) and sg.C <= criteria.motion_sg_c_max),
                    "basis": "threshold",
                }
            )
            u = {}
            for side in ("sim", "meas"):
                uname = f"{name}_{side}_u"
                if uname in al:
                    uv = al[uname].sel(axis=c).values if c else al[uname].values
                    u[side] = np.asarray(uv, dtype=float)[ok]
            u_model = np.hypot(
                criteria.motion_u_input_rel * s,
                u["sim"] if "sim" in u else criteria.motion_u_num_rel * s,
            )
            if "meas" in u or np.any(u_model > 0):
                u_tot = np.sqrt(u_model**2 + u.get("meas", 0.0) ** 2)
                good = np.isfinite(u_tot)
                rows.add(
                    q,
                    "fraction_within_U_val",
                    float(np.mean(np.abs(s - d)[good] <= criteria.k * u_tot[good])),
                    units,
                )
            rms_s = float(np.sqrt(np.mean(s**2)))
            rms_d = float(np.sqrt(np.mean(d**2)))
            rms_u = {k: float(np.sqrt(np.nanmean(v**2))) for k, v in u.items()}
            _scalar_decision(
                rows,
                decisions,
                f"{q}_rms",
                f"{label} RMS",
                rms_s,
                rms_d,
                units,
                u_num=rms_u.get("sim", criteria.motion_u_num_rel * rms_s),
                u_input=criteria.motion_u_input_rel * rms_s,
                u_d=rms_u.get("meas", 0.0),
                criteria=criteria,
            )


# --------------------------------------------------------------------------- main entry


def compare(
    sim: xr.Dataset | Sequence[xr.Dataset],
    meas: xr.Dataset | Sequence[xr.Dataset],
    *,
    criteria: Criteria | None = None,
    cycles: float | None = None,
    theta_step_deg: float | None = None,
    motion_method: str = "auto",
    period_s: float | None = None,
    variables: Sequence[str] | None = None,
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

    Returns
    -------
    Comparison
        Aligned data, metrics table, decision card, notes.

    Raises
    ------
    BadInputError
        Nothing to compare (no wear map or motion record on both sides), or the inputs cannot
        be aligned.
    ConventionError
        A wear map does not state its angle convention.
    """
    criteria = criteria or Criteria()
    s_wear, s_motion = _split(sim)
    m_wear, m_motion = _split(meas)
    rows = _Rows()
    decisions: list[dict[str, Any]] = []
    notes: list[str] = []
    wear = motion = None
    if s_wear is not None and m_wear is not None:
        wear = align_wear_maps(s_wear, m_wear, cycles=cycles, theta_step_deg=theta_step_deg)
        _wear_metrics(wear, rows, decisions, criteria)
        if cycles is None and not np.isfinite(float(wear.attrs.get("cycles_meas", np.nan))):
            notes.append(
                "wear cycles: the measured map does not state after how many crank cycles it was "
                f"taken; it was compared with the simulation after {wear.attrs['cycles_sim']:g} "
                "cycles (its last snapshot) - give cycles= / --cycles, or a 'cycles' attribute"
            )
    elif s_wear is not None or m_wear is not None:
        side = "measurement" if s_wear is not None else "simulation"
        notes.append(f"wear maps not compared: the {side} has no wear map (wear_depth)")
    if s_motion is not None and m_motion is not None:
        motion = align_time_series(
            s_motion, m_motion, variables=variables, method=motion_method, period_s=period_s
        )
        _motion_metrics(motion, rows, decisions, criteria)
    elif s_motion is not None or m_motion is not None:
        side = "measurement" if s_motion is not None else "simulation"
        notes.append(f"motion not compared: the {side} has no motion record over time")
    if wear is None and motion is None:
        raise BadInputError(
            "nothing to compare: give a wear map (wear_depth over z, theta) and/or a motion "
            "record (follower_velocity, journal_offset, ... over time) on both sides"
        )
    card = pd.DataFrame(decisions, columns=DECISION_COLUMNS)
    card["passed"] = card["passed"].astype(bool)
    return Comparison(
        wear=wear,
        motion=motion,
        metrics=rows.frame(),
        decisions=card,
        notes=tuple(notes),
        criteria=criteria,
    )


def metrics_table(comparison: Comparison | xr.Dataset) -> pd.DataFrame:
    """The tidy metrics table (quantity, metric, value, units, long_name, definition)."""
    if isinstance(comparison, Comparison):
        return comparison.metrics.copy()
    return load_comparison(comparison).metrics


# --------------------------------------------------------------------------- netCDF


def _to_dataset(c: Comparison) -> xr.Dataset:
    parts = []
    attrs: dict[str, Any] = {}
    for prefix, part in (("wear", c.wear), ("motion", c.motion)):
        if part is None:
            continue
        parts.append(part)
        attrs.update({f"{prefix}_{k}": v for k, v in part.attrs.items() if k != "title"})
    ds = xr.merge(parts, combine_attrs="override", join="outer") if parts else xr.Dataset()
    for row in c.metrics.itertuples():
        name = f"{row.quantity}__{row.metric}"
        ds[name] = xr.DataArray(
            float(row.value),
            attrs={
                "units": row.units,
                "long_name": f"{row.long_name} of {row.quantity}",
                "definition": row.definition,
                "quantity": row.quantity,
                "metric": row.metric,
            },
        )
    for i, row in enumerate(c.decisions.itertuples()):
        ds[f"decision_{i:02d}"] = xr.DataArray(
            np.int8(bool(row.passed)),
            attrs={
                "units": "1",
                "long_name": f"validation decision: {row.quantity}",
                "quantity": row.quantity,
                "criterion": row.criterion,
                "value": row.value,
                "basis": row.basis,
                "flag_values": np.array([0, 1], dtype=np.int8),
                "flag_meanings": "fail pass",
            },
        )
    attrs.update(
        {
            "title": "jointwear comparison of simulation and measurement",
            "validation_passed": int(c.passed),
            "n_criteria": len(c.decisions),
            "n_failed": len(c.failed()),
            "notes": "\n".join(c.notes),
            "criteria": json_dumps(c.criteria),
        }
    )
    ds.attrs = attrs
    return ds


def json_dumps(criteria: Criteria) -> str:
    """Criteria as JSON text (sorted keys)."""
    import json

    from jointwear.params import to_jsonable

    return json.dumps(to_jsonable(criteria), sort_keys=True)


def load_comparison(source: str | Path | xr.Dataset) -> Comparison:
    """Rebuild a :class:`Comparison` from the netCDF written by :func:`save_comparison`."""
    import json

    ds = io.load(source) if not isinstance(source, xr.Dataset) else source
    metric_rows = []
    decision_rows = []
    for name, var in ds.data_vars.items():
        if "__" in str(name) and "metric" in var.attrs:
            metric_rows.append(
                {
                    "quantity": var.attrs["quantity"],
                    "metric": var.attrs["metric"],
                    "value": float(var.values),
                    "units": var.attrs.get("units", ""),
                    "long_name": mt.DEFINITIONS.get(var.attrs["metric"], ("",))[0],
                    "definition": var.attrs.get("definition", ""),
                }
            )
        elif str(name).startswith("decision_"):
            decision_rows.append(
                {
                    "quantity": var.attrs.get("quantity", str(name)),
                    "criterion": var.attrs.get("criterion", ""),
                    "value": var.attrs.get("value", ""),
                    "passed": bool(int(var.values)),
                    "basis": var.attrs.get("basis", ""),
                }
            )
    wear_vars = [v for v in ds.data_vars if set(ds[v].dims) == {"z", "theta"}]
    motion_vars = [v for v in ds.data_vars if "time" in ds[v].dims]
    wear = ds[wear_vars] if wear_vars else None
    motion = ds[motion_vars] if motion_vars else None
    for prefix, part in (("wear_", wear), ("motion_", motion)):
        if part is not None:
            part.attrs = {k[len(prefix) :]: v for k, v in ds.attrs.items() if k.startswith(prefix)}
    try:
        crit = from_mapping(Criteria, json.loads(ds.attrs.get("criteria", "{}")), where="criteria")
    except (ValueError, ParameterError):
        crit = Criteria()
    notes = tuple(n for n in str(ds.attrs.get("notes", "")).splitlines() if n)
    return Comparison(
        wear=wear,
        motion=motion,
        metrics=pd.DataFrame(metric_rows, columns=METRIC_COLUMNS),
        decisions=pd.DataFrame(decision_rows, columns=DECISION_COLUMNS).astype({"passed": bool}),
        notes=notes,
        criteria=crit,
    )


def save_comparison(
    comparison: Comparison,
    path: str | Path,
    *,
    inputs: Sequence[str | Path] = (),
    parents: Sequence[xr.Dataset] = (),
    command: str | None = None,
) -> Path:
    """Write the aligned fields, differences, metrics and decisions to netCDF (atomic, provenance)."""
    ds = comparison.to_dataset()
    return io.save(
        ds,
        path,
        inputs=inputs,
        parameters=comparison.criteria,
        parents=parents,
        command=command,
        source="jointwear compare",
    )
