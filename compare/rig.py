"""Is a verification study or an ensemble of the compared run's rig? Parameters compared.

A ``jointwear sim verify`` study gives u_num, an ensemble (``jointwear sim sweep``) u_input, of
*the rig they were run for*. Handed a study or an ensemble of another rig (another tilt
stiffness, clearance or speed), the comparison would judge the simulation with another model's
uncertainties: a wrong-clearance model passed every criterion with the right model's study and
failed two with its own (issue 36). So the physical parameters each file records are compared
with the simulation's:

* where they are: the attribute ``parameters_json`` (a study, a cycle record), else the
  ``parameters`` of the file's ``provenance`` (``jointwear sim wear``, ``sim sweep``,
  ``sim verify``); the simulator's parameters are the nested record with ``mechanism`` and
  ``joint``, the wear coefficient ``kw`` that of the wear settings;
* what is compared: every field of ``mechanism``, ``joint``, ``contact`` and ``friction`` and
  the wear coefficient ``wear.kw``, except what a study or an ensemble legitimately changes:
  the numerics (:data:`NUMERICAL`: solver, wear-update settings, the wear grid, the start
  phase a study's replicates vary) and, for an ensemble, the parameters it samples
  (``sweep_parameters``; ``joint.radial_clearance`` stands for the bore radius);
* the verdict: differences are named (``joint.tilt_stiffness: simulation 1000, study 0``) and
  the comparison refused (exit 3) unless the caller allows another rig (``--allow-other-rig``),
  when the note says whose uncertainty was used. A side that records no parameters cannot be
  checked; the note says so (never silently taken as the same rig).
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterable, Mapping
from typing import Any

import xarray as xr

from jointwear import io

__all__ = ["NUMERICAL", "rig_parameters", "rig_differences", "check_rig"]

#: sections of the simulator's parameters that describe the rig
PHYSICAL_SECTIONS = ("mechanism", "joint", "contact", "friction")

#: fields a study or an ensemble may change without being of another rig: numerics
NUMERICAL = frozenset(
    {
        "mechanism.initial_crank_angle_deg",  # a study's replicates start at other phases
        "joint.n_layers",  # the wear grid (a study refines it)
        "joint.n_points",
        "joint.axial_grading",
    }
)

#: a swept name that stands for several fields
_DERIVED = {"joint.radial_clearance": ("joint.bearing_radius",)}


def _records(ds: xr.Dataset) -> Iterable[Any]:
    """The parameter records a file carries: a study's ``parameters_json``, then its provenance's."""
    text = ds.attrs.get("parameters_json")
    if isinstance(text, str):
        try:
            yield json.loads(text)
        except ValueError:
            pass
    provenance = io.parse_provenance(ds)  # {} when absent or unreadable
    if isinstance(provenance, dict):
        yield provenance.get("parameters")


def _find(record: Any, keys: tuple[str, ...]) -> Mapping[str, Any] | None:
    """The first nested mapping of ``record`` that has all ``keys``."""
    stack = [record]
    while stack:
        item = stack.pop(0)
        if isinstance(item, Mapping):
            if all(k in item for k in keys):
                return item
            stack.extend(item.values())
        elif isinstance(item, list):
            stack.extend(item)
    return None


def rig_parameters(ds: xr.Dataset) -> dict[str, Any] | None:
    """The rig's physical parameters a file records, as ``{"joint.tilt_stiffness": 0.0, ...}``.

    None when the file records no simulator parameters (an in-memory result, a prescribed
    contact model, another tool's file).
    """
    for record in _records(ds):
        sim = _find(record, ("mechanism", "joint"))
        if sim is None:
            continue
        out: dict[str, Any] = {}
        for section in PHYSICAL_SECTIONS:
            for name, value in dict(sim.get(section) or {}).items():
                out[f"{section}.{name}"] = value
        wear = _find(record, ("kw", "scheme"))
        if wear is not None:
            out["wear.kw"] = wear["kw"]
        return out
    return None


def _same(a: Any, b: Any) -> bool:
    if isinstance(a, (list, tuple)) and isinstance(b, (list, tuple)):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, (int, float)) and isinstance(b, (int, float)):
        return math.isclose(float(a), float(b), rel_tol=1e-9, abs_tol=0.0) or a == b
    return a == b


def rig_differences(
    sim: Mapping[str, Any], other: Mapping[str, Any], varied: Iterable[str] = ()
) -> list[tuple[str, Any, Any]]:
    """``(field, simulation's value, other's value)`` of every physical field that differs.

    ``varied``: the parameters an ensemble samples (not compared); fields in
    :data:`NUMERICAL` are never compared.
    """
    skip = set(NUMERICAL)
    for name in varied:
        skip.update(_DERIVED.get(name, (name,)))
    return [
        (key, sim[key], other[key])
        for key in sorted(set(sim) & set(other))
        if key not in skip and not _same(sim[key], other[key])
    ]


def _shown(value: Any) -> str:
    return f"{value:g}" if isinstance(value, float) else str(value)


def check_rig(
    sim: xr.Dataset | None,
    other: xr.Dataset,
    what: str,
    *,
    allow_other_rig: bool = False,
    varied: Iterable[str] = (),
) -> str:
    """Check that ``other`` (a study or an ensemble) is of the rig of the simulation ``sim``.

    Returns the note for the comparison ('' when both record the same rig).

    Raises
    ------
    BadInputError
        The two record different rigs and ``allow_other_rig`` is False; the message names every
        difference and the options that settle it.
    """
    from jointwear.errors import BadInputError

    mine = rig_parameters(sim) if sim is not None else None
    theirs = rig_parameters(other)
    if mine is None or theirs is None:
        side = "the simulation" if mine is None else what
        return (
            f"rig of {what} not checked: {side} records no simulator parameters "
            "(provenance or parameters_json); its uncertainty is taken as of the compared run"
        )
    diff = rig_differences(mine, theirs, varied)
    if not diff:
        return ""
    named = "; ".join(f"{k}: simulation {_shown(a)}, {what} {_shown(b)}" for k, a, b in diff)
    if not allow_other_rig:
        raise BadInputError(
            f"{what} is of another rig than the compared simulation ({named}): its uncertainty "
            "would be another model's. Run it for the simulation's parameters, or give "
            "--allow-other-rig (allow_other_rig=True) to use it anyway, labelled"
        )
    return (
        f"{what} is of ANOTHER RIG than the compared simulation, used by --allow-other-rig: {named}"
    )
