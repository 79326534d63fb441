"""Reported measurements: the numbers a lab sheet or a publication gives, read from a TOML file.

A *reported-measurement file* lists named quantities (the cylindricity of a bore after so many
cycles, the angle of maximum wear at a layer, ...), each with its value and unit, the crank
cycles it belongs to, its standard uncertainty or what that is made of, where it was measured
(layer / axial position, angle convention) and its source (citation, table or figure). The
schema is documented in ``docs/compare-report.md`` ("Reported measurements");
:func:`read_reported` checks it and returns a CF dataset that :mod:`jointwear.compare` judges
against a simulation (``data_origin = "measured"`` unless the file says otherwise).

Uncertainty rules (GUM type B; every component is a standard uncertainty, k = 1, combined by
root sum of squares):

``standard = u``
    taken as it is;
``expanded = U`` with ``k = k``
    ``U / k`` (``k`` is required: an expanded value without its coverage factor is refused);
``accuracy = a``
    an instrument's stated accuracy, read as the half-width of a rectangular distribution:
    ``a / sqrt(3)``;
``resolution = r``
    the smallest step of the reading (display digit, last printed decimal): a rectangular
    distribution of full width ``r``, ``r / sqrt(12)``;
``figure_reading = a``
    the half-width within which a value was read off a figure (or a "near" in the text):
    rectangular, ``a / sqrt(3)``;
``not_stated = true``
    the uncertainty is unknown: stored as NaN, and every criterion that needs it is *not
    assessed* (never zero).

Each component is a number in the quantity's unit or a string with its own unit (``"0.03 um"``).
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from jointwear.conventions import CANONICAL, AngleConvention
from jointwear.errors import ConventionError, ParameterError

__all__ = [
    "SCHEMA",
    "KINDS",
    "UNCERTAINTY_RULES",
    "read_reported",
    "reported_dataset",
    "is_reported",
    "standard_uncertainty",
    "new_bore_baseline",
    "cylindricity_growth",
]

#: the value of the top-level ``schema`` key this reader understands
SCHEMA = "jointwear.reported/1"

#: quantity kinds: name -> (physical kind for units, long name)
KINDS: dict[str, tuple[str, str]] = {
    "cylindricity": ("length", "cylindricity of the bore (peak-to-valley form deviation)"),
    "max_wear_angle": ("angle", "angle of maximum wear depth at a layer"),
    "max_wear_depth": ("length", "largest wear depth at a layer or over the measured layers"),
    "other": ("any", "a reported quantity without a simulated counterpart in jointwear"),
}

#: uncertainty components: key -> (divisor, the rule in words)
UNCERTAINTY_RULES: dict[str, tuple[float, str]] = {
    "standard": (1.0, "standard uncertainty as stated (k = 1)"),
    "accuracy": (math.sqrt(3.0), "instrument accuracy +/-a, rectangular: a/sqrt(3)"),
    "resolution": (math.sqrt(12.0), "resolution r, rectangular of width r: r/sqrt(12)"),
    "figure_reading": (math.sqrt(3.0), "read off a figure within +/-a, rectangular: a/sqrt(3)"),
}

_TOP_KEYS = {"schema", "title", "data_origin", "source", "layers", "angle", "quantity"}
_QUANTITY_KEYS = {
    "kind",
    "value",
    "unit",
    "cycles",
    "layer",
    "layers",
    "z",
    "reference",
    "source",
    "definition",
    "note",
    "uncertainty",
}
_REFERENCES = ("LS", "MZ", "unstated")
_ORIGINS = ("measured", "synthetic")
_FIRST = ("+z", "-z", "unstated")


def _where(path: Path, field: str) -> str:
    return f"reported-measurement file '{path}': {field}"


def _require(table: Mapping[str, Any], key: str, path: Path, prefix: str, fix: str) -> Any:
    if key not in table:
        raise ParameterError(_where(path, f"{prefix}{key} is missing - {fix}"))
    return table[key]


def _unknown_keys(table: Mapping[str, Any], allowed: set[str], path: Path, prefix: str) -> None:
    bad = sorted(set(table) - allowed)
    if bad:
        raise ParameterError(
            _where(path, f"{prefix}{bad[0]} is not a field of the schema (allowed: ")
            + ", ".join(sorted(allowed))
            + ") - check its spelling (docs/compare-report.md, 'Reported measurements')"
        )


def _same_unit(value: float, unit: str, target: str, field: str) -> float:
    """``value`` in ``unit`` expressed in ``target`` (a quantity of kind "other")."""
    import pint

    from jointwear.external import _pint_unit, _registry

    try:
        return float(_registry().Quantity(value, _pint_unit(unit)).to(_pint_unit(target)).magnitude)
    except (pint.errors.PintError, ValueError, AssertionError) as exc:
        raise ParameterError(
            f"{field}: {unit!r} cannot be converted to {target!r} ({exc})"
        ) from None


def _amount(value: Any, unit: str, kind: str, field: str) -> float:
    """A number in ``unit`` or a string ``"<number> <unit>"``, converted to SI (degree).

    ``kind = "any"``: kept in ``unit`` (a string's own unit is converted to it).
    """
    from jointwear.external import to_si

    if isinstance(value, bool):
        raise ParameterError(f"{field} = {value!r}: expected a number")
    if isinstance(value, str):
        text = value.strip()
        number, _, own_unit = text.partition(" ")
        try:
            num = float(number)
        except ValueError:
            raise ParameterError(
                f"{field} = {value!r}: expected a number or '<number> <unit>' (e.g. '0.03 um')"
            ) from None
        if not own_unit.strip():
            raise ParameterError(f"{field} = {value!r}: give the unit after the number")
        if kind == "any":
            return _same_unit(num, own_unit.strip(), unit, field)
        return float(to_si(num, own_unit.strip(), kind=kind, option=field))
    if not isinstance(value, (int, float)):
        raise ParameterError(f"{field} = {value!r}: expected a number")
    if kind == "any":
        return float(value)
    return float(to_si(float(value), unit, kind=kind, option=field))


def standard_uncertainty(
    table: Mapping[str, Any] | str, unit: str, kind: str, field: str
) -> tuple[float, list[dict[str, Any]]]:
    """Combined standard uncertainty [SI] and its budget from an ``uncertainty`` table.

    Parameters
    ----------
    table : mapping
        The quantity's ``uncertainty`` table (keys of :data:`UNCERTAINTY_RULES`, ``expanded``
        with ``k``, or ``not_stated = true``).
    unit : str
        The quantity's unit (for bare numbers).
    kind : {"length", "angle"}
        Physical kind of the quantity.
    field : str
        Name of the table in error messages.

    Returns
    -------
    (float, list of dict)
        The standard uncertainty (NaN when not stated) and one record per component: key,
        stated value, divisor, standard uncertainty, rule.
    """
    if not isinstance(table, Mapping):
        raise ParameterError(
            f"{field} must be a table (e.g. {{ accuracy = '0.03 um' }}) or {{ not_stated = true }}"
        )
    allowed = {*UNCERTAINTY_RULES, "expanded", "k", "not_stated", "note"}
    bad = sorted(set(table) - allowed)
    if bad:
        raise ParameterError(
            f"{field}.{bad[0]} is not an uncertainty component; use "
            + ", ".join(sorted(allowed - {"note"}))
        )
    if table.get("not_stated") is True:
        if set(table) - {"not_stated", "note"}:
            raise ParameterError(f"{field}: not_stated = true cannot go with stated components")
        return float("nan"), [{"component": "not_stated", "rule": "unknown: not assessed"}]
    if "not_stated" in table:
        raise ParameterError(f"{field}.not_stated must be true (or left out)")
    if ("expanded" in table) != ("k" in table):
        missing = "k" if "expanded" in table else "expanded"
        raise ParameterError(
            f"{field}.{missing} is missing: an expanded uncertainty needs its coverage factor k "
            "(e.g. expanded = 0.1, k = 2); a standard uncertainty is 'standard = ...'"
        )
    budget: list[dict[str, Any]] = []
    for key, (divisor, rule) in UNCERTAINTY_RULES.items():
        if key in table:
            a = _amount(table[key], unit, kind, f"{field}.{key}")
            if not (np.isfinite(a) and a >= 0):
                raise ParameterError(f"{field}.{key} must be a finite number >= 0, got {a!r}")
            budget.append({"component": key, "stated": a, "divisor": divisor, "u": a / divisor})
            budget[-1]["rule"] = rule
    if "expanded" in table:
        k = table["k"]
        if isinstance(k, bool) or not isinstance(k, (int, float)) or not k > 0:
            raise ParameterError(f"{field}.k must be a number > 0, got {k!r}")
        big_u = _amount(table["expanded"], unit, kind, f"{field}.expanded")
        budget.append(
            {
                "component": "expanded",
                "stated": big_u,
                "divisor": float(k),
                "u": big_u / float(k),
                "rule": f"expanded uncertainty U with k = {k:g}: U/k",
            }
        )
    if not budget:
        raise ParameterError(
            f"{field} states no component; give standard, expanded + k, accuracy, resolution or "
            "figure_reading, or not_stated = true when the source gives none"
        )
    return float(math.sqrt(sum(b["u"] ** 2 for b in budget))), budget


def _layers(data: Mapping[str, Any], path: Path) -> dict[str, Any]:
    table = data.get("layers")
    if table is None:
        return {}
    if not isinstance(table, Mapping):
        raise ParameterError(_where(path, "[layers] must be a table"))
    _unknown_keys(table, {"count", "spacing", "z_centre", "first", "note"}, path, "layers.")
    fix = "state the measured layers: count, spacing, z_centre and which end layer 1 is at"
    count = _require(table, "count", path, "layers.", fix)
    if isinstance(count, bool) or not isinstance(count, int) or count < 1:
        raise ParameterError(
            _where(path, f"layers.count must be a whole number >= 1, got {count!r}")
        )
    spacing = _amount(
        _require(table, "spacing", path, "layers.", fix), "m", "length", "layers.spacing"
    )
    if count > 1 and not spacing > 0:
        raise ParameterError(_where(path, "layers.spacing must be > 0"))
    centre_text = _require(
        table, "z_centre", path, "layers.", fix + " (z from the bearing mid-width, or 'unstated')"
    )
    centre = (
        float("nan")
        if centre_text == "unstated"
        else _amount(centre_text, "m", "length", "layers.z_centre")
    )
    first = _require(table, "first", path, "layers.", "'+z', '-z' or 'unstated'")
    if first not in _FIRST:
        raise ParameterError(
            _where(
                path,
                f"layers.first = {first!r}: use '+z' or '-z' (the end of the bore layer 1 "
                "is at) or 'unstated' when the source does not say",
            )
        )
    return {
        "layers_count": int(count),
        "layers_spacing_m": spacing,
        "layers_z_centre_m": centre,  # NaN: unstated (anywhere in the bore)
        "layers_first": str(first),
        "layers_note": str(table.get("note", "")),
    }


def _angle(data: Mapping[str, Any], path: Path) -> dict[str, str] | None:
    table = data.get("angle")
    if table is None:
        return None
    if not isinstance(table, Mapping):
        raise ParameterError(_where(path, "[angle] must be a table"))
    _unknown_keys(table, {"zero", "direction", "note"}, path, "angle.")
    zero = _require(table, "zero", path, "angle.", "where 0 degree points: '+x', '-x', ...")
    direction = _require(
        table, "direction", path, "angle.", "'clockwise', 'counterclockwise' or 'unstated'"
    )
    try:
        AngleConvention(str(zero), "clockwise" if direction == "unstated" else str(direction))
    except ConventionError as exc:
        raise ParameterError(_where(path, f"[angle]: {exc}")) from None
    return {"zero": str(zero), "direction": str(direction), "note": str(table.get("note", ""))}


def _source_text(src: Any, path: Path, field: str) -> dict[str, str]:
    if isinstance(src, str):
        src = {"citation": src}
    if not isinstance(src, Mapping) or not str(src.get("citation", "")).strip():
        raise ParameterError(
            _where(path, f"{field}.citation is missing - name where the numbers come from")
        )
    return {str(k): str(v) for k, v in src.items()}


def _quantity(
    name: str,
    q: Mapping[str, Any],
    path: Path,
    layers: Mapping[str, Any],
    angle: Mapping[str, str] | None,
) -> tuple[xr.DataArray, xr.DataArray, dict[str, Any]]:
    p = f"quantity.{name}."
    if not isinstance(q, Mapping):
        raise ParameterError(_where(path, f"quantity.{name} must be a table"))
    _unknown_keys(q, _QUANTITY_KEYS, path, p)
    kind = _require(q, "kind", path, p, "one of " + ", ".join(KINDS))
    if kind not in KINDS:
        raise ParameterError(
            _where(path, f"{p}kind = {kind!r} is not known; use one of {', '.join(KINDS)}")
        )
    phys, long_name = KINDS[kind]
    unit = _require(q, "unit", path, p, "the unit of value (e.g. 'um', 'degree')")
    raw = _require(q, "value", path, p, "the reported number")
    if isinstance(raw, bool) or not isinstance(raw, (int, float)) or not math.isfinite(raw):
        raise ParameterError(_where(path, f"{p}value must be a finite number, got {raw!r}"))
    if phys == "any":
        value, si_unit = float(raw), str(unit)
    else:
        try:
            value = _amount(raw, str(unit), phys, f"{p}unit")
        except ParameterError as exc:
            raise ParameterError(_where(path, f"{exc} (quantity kind {kind!r})")) from None
        si_unit = "degree" if phys == "angle" else "m"
    cycles = _require(q, "cycles", path, p, "the crank cycles the value belongs to (0 = new)")
    if isinstance(cycles, bool) or not isinstance(cycles, (int, float)) or not cycles >= 0:
        raise ParameterError(_where(path, f"{p}cycles must be a number >= 0, got {cycles!r}"))
    attrs: dict[str, Any] = {
        "units": si_unit,
        "long_name": f"reported {long_name}",
        "kind": kind,
        "cycles": float(cycles),
        "reported_value": float(raw),
        "reported_unit": str(unit),
        "ancillary_variables": f"{name}_u",
    }
    src = _source_text(_require(q, "source", path, p, "table/figure/section"), path, p + "source")
    attrs["source_of_value"] = "; ".join(f"{k}: {v}" for k, v in src.items())
    for key in ("note", "definition"):
        if key in q:
            attrs[key] = str(q[key])
    if kind == "other" and not str(q.get("definition", "")).strip():
        raise ParameterError(_where(path, f"{p}definition is missing - say what was measured"))
    if kind in ("max_wear_angle", "max_wear_depth", "cylindricity"):
        where_keys = [k for k in ("layer", "layers", "z") if k in q]
        if kind == "max_wear_angle" and where_keys not in (["layer"], ["z"]):
            raise ParameterError(
                _where(
                    path,
                    f"{p}layer or {p}z: the angle of maximum wear belongs to one layer; "
                    "give layer = N (of [layers]) or z = '<value> mm' (from the bearing mid-width)",
                )
            )
        if kind != "max_wear_angle" and len(where_keys) != 1:
            raise ParameterError(
                _where(
                    path, f"{p}layers = 'all', layer = N or z = '...': say where it was measured"
                )
            )
        if "layer" in q:
            layer = q["layer"]
            count = layers.get("layers_count")
            if count is None:
                raise ParameterError(_where(path, f"{p}layer needs a [layers] table"))
            if isinstance(layer, bool) or not isinstance(layer, int) or not 1 <= layer <= count:
                raise ParameterError(
                    _where(path, f"{p}layer = {layer!r}: a layer number 1..{count} of [layers]")
                )
            attrs["layer"] = int(layer)
        elif "z" in q:
            attrs["z_m"] = _amount(q["z"], "m", "length", f"{p}z")
        else:
            if q["layers"] != "all" or not layers:
                raise ParameterError(
                    _where(
                        path, f"{p}layers must be 'all' (every layer of [layers], which must exist)"
                    )
                )
            attrs["layer"] = 0  # 0: all layers
    if kind == "cylindricity":
        ref = _require(q, "reference", path, p, "'LS', 'MZ' or 'unstated'")
        if ref not in _REFERENCES:
            raise ParameterError(
                _where(
                    path,
                    f"{p}reference = {ref!r}: use 'LS' (least-squares cylinder), 'MZ' "
                    "(minimum zone) or 'unstated'",
                )
            )
        attrs["reference"] = ref
    if kind == "max_wear_angle":
        if angle is None:
            raise ParameterError(
                _where(
                    path,
                    f"{p}: an angle needs the [angle] table (zero, direction) - jointwear "
                    "never guesses where 0 degree is",
                )
            )
        attrs["angle_zero"] = angle["zero"]
        attrs["angle_direction"] = angle["direction"]
        if angle["direction"] != "unstated":
            conv = AngleConvention(angle["zero"], angle["direction"])
            value = float(CANONICAL.from_physical(conv.to_physical(value)))
            attrs["angle_zero"], attrs["angle_direction"] = CANONICAL.zero, CANONICAL.direction
            attrs["comment"] = (
                f"converted to the canonical convention from {raw:g} {unit} with zero "
                f"{angle['zero']}, {angle['direction']}"
            )
    u_table = _require(q, "uncertainty", path, p, "a table of components, or { not_stated = true }")
    try:
        u, budget = standard_uncertainty(u_table, str(unit), phys, p + "uncertainty")
    except ParameterError as exc:
        raise ParameterError(_where(path, str(exc))) from None
    u_attrs = {
        "units": si_unit,
        "long_name": f"standard uncertainty of {name}",
        "coverage_factor": 1.0,
        "comment": "; ".join(str(b["rule"]) for b in budget),
        "uncertainty_budget": json.dumps(budget, sort_keys=True),
    }
    return xr.DataArray(value, attrs=attrs), xr.DataArray(u, attrs=u_attrs), {}


def _one_baseline(ds: xr.Dataset, path: Path) -> None:
    """Refuse two new-bore cylindricities that a growth could take as its baseline."""
    seen: dict[tuple[Any, ...], str] = {}
    for name, var in ds.data_vars.items():
        a = var.attrs
        if a.get("kind") != "cylindricity" or a.get("cycles") != 0.0:
            continue
        key = (a.get("reference"), a.get("layer"), a.get("z_m"))
        if key in seen:
            raise ParameterError(
                _where(
                    path,
                    f"quantity.{seen[key]} and quantity.{name} are both the new bore's "
                    "cylindricity (cycles = 0, same reference and place): a growth would not know "
                    "which to subtract - keep one (or their mean, with its uncertainty)",
                )
            )
        seen[key] = str(name)


def reported_dataset(data: Mapping[str, Any], path: str | Path = "<mapping>") -> xr.Dataset:
    """Check a parsed reported-measurement mapping and build its CF dataset.

    Parameters
    ----------
    data : mapping
        The TOML content (see the module docstring and docs/compare-report.md).
    path : path
        Where it came from, for messages.

    Returns
    -------
    Dataset
        One scalar variable per quantity (SI: m, or degree in the canonical convention when the
        direction is stated) with ``<name>_u`` (standard uncertainty, ``coverage_factor = 1``,
        NaN = not stated), and global attributes ``jointwear_file = "reported"``,
        ``data_origin``, ``reported_source`` (JSON) and the layer description.

    Raises
    ------
    ParameterError
        A field is missing, misspelt, of the wrong type or unit; the message names it.
    """
    path = Path(path)
    _unknown_keys(data, _TOP_KEYS, path, "")
    schema = _require(data, "schema", path, "", f"add schema = {SCHEMA!r}")
    if schema != SCHEMA:
        raise ParameterError(_where(path, f"schema = {schema!r}: this reader knows {SCHEMA!r}"))
    origin = data.get("data_origin", "measured")
    if origin not in _ORIGINS:
        raise ParameterError(
            _where(path, f"data_origin = {origin!r}: 'measured' (default) or 'synthetic'")
        )
    source = _source_text(
        _require(data, "source", path, "", "[source] citation = '...'"), path, "source"
    )
    layers = _layers(data, path)
    angle = _angle(data, path)
    quantities = _require(data, "quantity", path, "", "add [quantity.NAME] tables")
    if not isinstance(quantities, Mapping) or not quantities:
        raise ParameterError(_where(path, "quantity: at least one [quantity.NAME] table"))
    ds = xr.Dataset()
    for name, q in quantities.items():
        if not str(name).isidentifier():
            raise ParameterError(
                _where(path, f"quantity.{name}: names are letters, digits and '_' (no spaces)")
            )
        value, u, _ = _quantity(str(name), q, path, layers, angle)
        ds[str(name)] = value
        ds[f"{name}_u"] = u
    _one_baseline(ds, path)
    ds.attrs.update(
        {
            "title": str(data.get("title", "reported measurements")),
            "jointwear_file": "reported",
            "data_origin": origin,
            "source": f"reported: {source['citation']}",
            "reported_source": json.dumps(source, sort_keys=True),
            "reported_schema": SCHEMA,
            **layers,
        }
    )
    if angle is not None:
        ds.attrs["angle_note"] = angle["note"]
    return ds


def read_reported(path: str | Path) -> xr.Dataset:
    """Read and check a reported-measurement TOML file (see :func:`reported_dataset`)."""
    from jointwear.params import read_toml

    return reported_dataset(read_toml(path), path)


def is_reported(ds: xr.Dataset) -> bool:
    """True for a dataset of reported measurements (``jointwear_file = "reported"``)."""
    return isinstance(ds, xr.Dataset) and ds.attrs.get("jointwear_file") == "reported"


def new_bore_baseline(ds: xr.Dataset, q: Mapping[str, Any]) -> str | None:
    """The new bore's cylindricity of a cylindricity with attributes ``q``: the quantity of
    ``ds`` at ``cycles = 0`` with the same reference and place (layer or z), or None."""
    for other, var in ds.data_vars.items():
        a = var.attrs
        if (
            a.get("kind") == "cylindricity"
            and float(a.get("cycles", -1)) == 0.0
            and a.get("reference") == q.get("reference")
            and int(a.get("layer", -1)) == int(q.get("layer", -1))
            and a.get("z_m") == q.get("z_m")
        ):
            return str(other)
    return None


def cylindricity_growth(ds: xr.Dataset, name: str) -> tuple[float, float, str]:
    """The growth ``C(N) - C(0)`` of reported cylindricity ``name`` [m], its standard
    uncertainty [m] (NaN: not assessed) and the basis of it.

    Cylindricity does not add: the worn bore's value lies within ``C_wear ± C(0)``, so the
    new-bore form enters as a rectangular term ``C(0)/sqrt(3)`` besides the two readings' own
    uncertainties. Without the new bore's value (:func:`new_bore_baseline`) the growth is the
    reported value and its uncertainty NaN (the wear's part cannot be separated).
    """
    c, u = float(ds[name].values), float(ds[f"{name}_u"].values)
    base = new_bore_baseline(ds, ds[name].attrs)
    if base is None:
        return (
            c,
            float("nan"),
            (
                "the new bore's cylindricity is not reported (a cylindricity at cycles = 0, same "
                "reference and place): the growth due to wear cannot be separated from the "
                "initial form"
            ),
        )
    c0, u0 = float(ds[base].values), float(ds[f"{base}_u"].values)
    form = c0 / math.sqrt(3.0)
    return (
        c - c0,
        math.sqrt(u**2 + u0**2 + form**2),
        (
            f"growth {name} - {base}: u = sqrt(u({name})^2 + u({base})^2 + (C0/sqrt(3))^2), the last "
            "term because cylindricity does not add (the new bore's form may add to or cancel the "
            "wear's)"
        ),
    )
