"""From a parsed table to layers: angles, values and z of each trace."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from jointwear.errors import BadInputError
from jointwear.metrology.readers.advice import Refusal, advise, plausibility
from jointwear.metrology.readers.claims import (
    ValueUnit,
    check_filter,
    check_form,
    check_magnitude,
    check_points,
    layer_form,
    stated_filter,
    stated_points,
)
from jointwear.metrology.readers.meaning import (
    absurd_length,
    angle_reading,
    closed_profile,
    oriented_steps,
    rounded_full_turn,
)
from jointwear.metrology.readers.meaning import value_kind as decide_value_kind
from jointwear.metrology.readers.table import ParsedFile, unit_factor

__all__ = []


def _value_unit(pf: ParsedFile) -> ValueUnit:
    """The unit ``pf``'s values are read in: the header's (``"units"`` among the guessed
    claims) or the one ``units=`` gave."""
    return ValueUnit(pf.units, "units" in pf.guessed)


@dataclass
class _Layer:
    theta_deg: np.ndarray  # instrument convention, ascending in instrument angle
    value: np.ndarray  # [m]
    kind: str  # "radius" or "deviation"
    z: float | None
    source: str
    index: float | None = None  # layer number from a Layer column or name (z = index x spacing)


_UNIT_OF_KIND = {"angle_deg": "deg", "angle_rad": "rad", "angle_grad": "grad", "index": "index"}


def _angles(
    pf: ParsedFile,
    col: int,
    rows: np.ndarray,
    where: str,
    *,
    angle_unit: str | None,
    arc: str | None,
    notes: dict[str, str],
) -> np.ndarray:
    """Angles [degree] of one layer: the column read in its stated or only possible unit."""
    kind = pf.columns[col]
    named = _UNIT_OF_KIND.get(kind)
    if named is not None and pf.angle_unit is not None and named != pf.angle_unit:
        raise BadInputError(
            f"{where}: the file contradicts itself: column {col + 1} is read as {named!r} (its "
            f"name or columns=...) but the header says the angle unit is {pf.angle_unit!r}; "
            "correct the file or pass columns=... (--columns)"
        )
    stated = named or pf.angle_unit
    if angle_unit is not None and stated is not None and angle_unit != stated:
        raise BadInputError(
            f"{where}: angle_unit={angle_unit!r} (--angle-unit) contradicts the file, which "
            f"states {stated!r} (column {col + 1} '{pf.column_names[col] if pf.column_names else kind}'"
            " or the header); drop the option or correct the file"
        )
    reading, note = angle_reading(
        pf.data[rows, col],
        unit=angle_unit or stated,
        arc=arc,
        where=f"{where} column {col + 1} (lines {pf.line_numbers[rows[0]]}-{pf.line_numbers[rows[-1]]})",
    )
    notes["angle"] = note + (f", {reading.arc} turn" if reading.arc == "full" else ", partial arc")
    notes["angle_column"] = {
        "deg": "angle_deg",
        "rad": "angle_rad",
        "index": "index",
        "grad": "angle_grad",
    }[reading.unit]
    return reading.theta_deg


def _check_angles(theta: np.ndarray, pf: ParsedFile, rows: np.ndarray, where: str) -> np.ndarray:
    """Angles of one layer must increase (or decrease) strictly; one wrap through 360 allowed."""
    th = np.asarray(theta, dtype=float)
    if th.size < 3:
        return th
    sgn, d, wraps = oriented_steps(th)
    if wraps.size == 1:  # allow one wrap of about -360
        th = th.copy()
        th[wraps[0] + 1 :] += sgn * 360.0
        d = np.diff(th) * sgn
    dup = np.flatnonzero(d == 0)
    if dup.size:
        i = dup[0] + 1
        raise BadInputError(
            f"{where} line {pf.line_numbers[rows[i]]}: angle {theta[i]:g} repeats the previous "
            "point (duplicate angle); delete the duplicate or re-export"
        )
    back = np.flatnonzero(d < 0)
    if back.size:
        i = back[0] + 1
        raise BadInputError(
            f"{where} line {pf.line_numbers[rows[i]]}: angle {theta[i]:g} goes back after "
            f"{theta[i - 1]:g} (angles must increase monotonically within a layer); sort the "
            "points or check the column meaning (columns=...)"
        )
    if abs(th[-1] - th[0]) >= 360.0:
        i = int(np.argmax(np.abs(th - th[0]) >= 360.0))
        raise BadInputError(
            f"{where} line {pf.line_numbers[rows[i]]}: the angles span more than one revolution "
            f"({th[0]:g} to {th[-1]:g} degree); check the angle unit (columns=... angle_deg / "
            "angle_rad / index)"
        )
    return th


def _xy_about_origin(x: np.ndarray, y: np.ndarray, where: str) -> None:
    """Refuse Cartesian points that are not a trace about the origin (the spindle axis)."""
    from jointwear.metrology.fit import fit_circle

    fit = fit_circle(x, y)
    th = np.sort(np.arctan2(y, x))
    gaps = np.diff(np.concatenate([th, th[:1] + 2 * np.pi]))
    if fit.eccentricity >= 0.5 * fit.radius or np.max(gaps) > np.pi:
        raise BadInputError(
            f"{where}: the x, y points do not surround the origin (their least-squares circle "
            f"has radius {fit.radius:.6g} m and centre ({fit.x0:.6g}, {fit.y0:.6g}) m): they are "
            "not a trace about the instrument's spindle axis, so angle and radius about the "
            "origin would be meaningless; assess the point set directly (jointwear metrology "
            "assess FILE --units ..., an exact least-squares circle) or shift the points"
        )


def _check_layers(
    out: list[_Layer],
    pf: ParsedFile,
    where: str,
    pts,
    *,
    layered: bool,
    full_turn: bool,
    arc: str | None,
    notes: dict[str, str],
    limits: dict[str, float],
    expected_points: int | None,
) -> None:
    """Check the layers cut from a file against its header claims and ``expected_points``
    (points per layer, stated filter), noting what was checked in ``notes``."""
    for k, lay in enumerate(out):
        if lay.value.size < 4:
            raise BadInputError(
                f"{where}: layer {k + 1} has only {lay.value.size} point(s); a roundness trace "
                "needs at least 4 (the file looks truncated - re-export it)"
            )
        share = float(np.isnan(lay.value).mean())
        if share > limits["max_missing"]:
            text, sugg = advise(
                [({"max_missing": "<value>"}, f"at least {share:.3g}, to read it with them")]
            )
            raise Refusal(
                f"{where}: layer {k + 1} has {int(np.isnan(lay.value).sum())} of "
                f"{lay.value.size} points missing ({share:.1%}), more than max_missing = "
                f"{limits['max_missing']:g} of a layer (its form would rest on what is left); "
                f"re-export the layer, or {text}",
                sugg,
            )
    if out and out[0].kind == "deviation" and pf.units:
        check_form(
            max(layer_form(lay.theta_deg, lay.value) for lay in out),
            _value_unit(pf),
            pf.metadata,
            limits,
            where,
        )
    if pts is not None and layered:
        for lay in out:
            check_points(pts, lay.value.size, {"deg": lay.theta_deg}, arc, True, where, limits)
    filt = stated_filter(pf.metadata)
    if filt is not None:
        for lay in out:
            if full_turn:
                notes["filter"] = check_filter(lay.value, filt, where, limits)
            else:
                notes["filter"] = f"header {filt[0]} = {filt[1]!r} (partial arc: not checked)"
    if expected_points is not None:
        for k, lay in enumerate(out):
            if lay.value.size != expected_points:
                raise BadInputError(
                    f"{where}: expected {expected_points} points in layer {k + 1}, found "
                    f"{lay.value.size} - the file looks truncated or the layer is incomplete; "
                    "re-export it or pass expected_points=None / allow_partial=True"
                )


def _layers_from_file(
    pf: ParsedFile,
    expected_points: int | None,
    *,
    value_kind: str | None = None,
    angle_unit: str | None = None,
    arc: str | None = None,
    notes: dict[str, str] | None = None,
    limits: dict[str, float] | None = None,
) -> list[_Layer]:
    """Cut a parsed table into layers according to its column meanings.

    Every meaning that the file, the column names or the user do not state is decided by
    :mod:`~jointwear.metrology.readers.meaning` or refused; every header claim is checked
    against the numbers (:mod:`~jointwear.metrology.readers.claims`).
    """
    notes = {} if notes is None else notes
    limits = plausibility() if limits is None else limits
    cols = pf.columns
    where = f"'{pf.path}'"
    if pf.units is None and any(c in ("radius", "deviation", "value", "x", "y") for c in cols):
        raise Refusal(
            f"{where}: the length unit is not stated in the header; pass units='um' (--units um; "
            "or mm, m, inch) - jointwear does not guess units",
            ({"units": "<unit>"},),
        )
    f = unit_factor(pf.units, where=where) if pf.units else 1.0
    zcols = [i for i, c in enumerate(cols) if c == "z"]
    layer_cols = [i for i, c in enumerate(cols) if c == "layer"]
    zf = _z_factor(pf, zcols, where) if zcols else f
    n = pf.data.shape[0]
    value_cols = [i for i, c in enumerate(cols) if c in ("radius", "deviation", "value")]
    angle_cols = [i for i, c in enumerate(cols) if c in _ANGLE_KINDS]
    has_xy = "x" in cols and "y" in cols
    if len(angle_cols) > 1:
        _two_probes(pf, angle_cols, value_cols, where)
    if len(zcols) + len(layer_cols) > 1:
        raise BadInputError(
            f"{where}: {len(zcols) + len(layer_cols)} columns give the layer (z or layer number); "
            "pass columns=... (--columns) with one of them, the others 'ignore'"
        )
    out: list[_Layer] = []
    kind = "radius"
    if not value_cols and not has_xy:
        raise BadInputError(
            f"{where}: no radius/deviation column among {list(cols)}; pass columns=(...) "
            "(--columns) naming the value column 'radius' or 'deviation'"
        )
    pts = stated_points(pf.metadata, where)
    if pts is not None and not (zcols or layer_cols) and angle_cols:
        a = pf.data[:, angle_cols[0]]
        stated_unit = _stated_angle_unit(pf, angle_cols[0], angle_unit)
        check_points(
            pts,
            n - (1 if closed_profile(a, stated_unit) else 0),
            _angle_readings(a, stated_unit),
            arc,
            stated_unit is not None,
            where,
            limits,
        )
    elif pts is not None and not (zcols or layer_cols) and not has_xy:
        check_points(pts, n, {}, arc, False, where, limits)
    if value_cols:
        kind = _decide_kind(pf, value_cols, value_kind, where, notes)
        absurd_length(pf.data[:, value_cols], kind, f, where, pf.line_numbers)
        check_magnitude(
            pf.data[:, value_cols], kind, _value_unit(pf), pf.metadata, limits, where, notes
        )
    if has_xy:
        xy = pf.data[:, [cols.index("x"), cols.index("y")]]
        absurd_length(xy, "radius", f, where, pf.line_numbers)
    if not angle_cols and not has_xy and value_cols:
        if arc != "full" and angle_unit != "index":
            raise Refusal(
                f"{where}: no angle column: the points can be read as equally spaced over one "
                "full turn only if you say so with arc='full' (--arc full); a partial arc needs "
                "an angle column",
                ({"arc": "full"},),
            )
        notes["angle"] = "no angle column: points equally spaced over one full turn (stated)"

    def make(rows: np.ndarray, vcol: int | None, zval: float | None, idx=None) -> _Layer:
        if has_xy:
            return _xy_layer(pf, rows, f, zval, where)
        assert vcol is not None
        if angle_cols:
            ac = angle_cols[0]
            th, rows = _layer_angles(pf, ac, rows, where, angle_unit, arc, notes)
        else:
            th = np.arange(rows.size) * 360.0 / rows.size
        return _Layer(th, pf.data[rows, vcol] * f, kind, zval, pf.path, idx)

    if (zcols or layer_cols) and (value_cols or has_xy):
        zc = pf.data[:, (zcols or layer_cols)[0]]
        # layers = runs of constant z
        change = np.flatnonzero(np.diff(zc) != 0) + 1
        starts = np.concatenate([[0], change])
        ends = np.concatenate([change, [n]])
        zs = zc[starts]
        if np.unique(zs).size != zs.size:
            dup = next(i for i in range(len(zs)) if zs[i] in zs[:i])
            raise BadInputError(
                f"{where} line {pf.line_numbers[starts[dup]]}: layer "
                f"{'z' if zcols else 'number'} = {zs[dup]:g} appears twice (the rows of one "
                "layer must be contiguous); sort the file by z"
            )
        vc = value_cols[0] if value_cols else None
        for s, e, zv in zip(starts, ends, zs, strict=True):
            rows = np.arange(s, e)
            if zcols:
                out.append(make(rows, vc, float(zv) * zf))
            else:
                out.append(make(rows, vc, None, float(zv)))
    elif len(value_cols) > 1:
        for vc in value_cols:
            out.append(make(np.arange(n), vc, None))
    else:
        out.append(make(np.arange(n), value_cols[0] if value_cols else None, None))
    _check_layers(
        out,
        pf,
        where,
        pts,
        layered=bool(zcols or layer_cols),
        full_turn=angle_cols == [] or notes.get("angle", "").endswith("full turn"),
        arc=arc,
        notes=notes,
        limits=limits,
        expected_points=expected_points,
    )
    return out


_ANGLE_KINDS = ("angle", "angle_deg", "angle_rad", "angle_grad", "index")


def _z_factor(pf: ParsedFile, zcols: list[int], where: str) -> float:
    """Metres per unit of the z column: from its name, the header or the user; else refused."""
    if str(zcols[0]) in pf.column_units:
        return unit_factor(pf.column_units[str(zcols[0])], where=f"{where} column {zcols[0] + 1}")
    if pf.z_units is not None:
        return unit_factor(pf.z_units, where=f"{where} z unit")
    zc = pf.data[:, zcols[0]]
    runs = zc[np.concatenate([[0], np.flatnonzero(np.diff(zc) != 0) + 1])]
    numbers = bool(np.all(runs == np.round(runs)) and np.all(np.diff(runs) == 1))
    cols = list(pf.columns)
    cols[zcols[0]] = "layer"
    alts = [({"z_units": "<unit>"}, f"if column {zcols[0] + 1} holds heights")]
    if numbers:
        alts.append(
            (
                {"columns": tuple(cols), "layer_spacing": "<m>"},
                f"if column {zcols[0] + 1} holds layer numbers {runs[0]:g}, {runs[1]:g}, ..."
                if runs.size > 1
                else "if it holds layer numbers",
            )
        )
    text, sugg = advise(alts)
    also = (
        f" (the header states the unit of the values, {pf.units!r}, which need not be that of z)"
        if pf.units
        else ""
    )
    raise Refusal(
        f"{where}: the unit of the z column is not stated{also}; {text}; or name the column "
        "with its unit, e.g. 'z [mm]'",
        sugg,
    )


def _two_probes(pf: ParsedFile, angle_cols: list[int], value_cols: list[int], where: str):
    """Several angle columns: several probes (or traces) side by side, never layers."""
    pairs = []
    for k, a in enumerate(angle_cols):
        nxt = angle_cols[k + 1] if k + 1 < len(angle_cols) else len(pf.columns)
        vs = [v for v in value_cols if a < v < nxt]
        if vs:
            pairs.append((a, vs[0]))
    alts = []
    for a, v in pairs:
        cols = tuple(pf.columns[i] if i in (a, v) else "ignore" for i in range(len(pf.columns)))
        alts.append(({"columns": cols}, f"to read the trace of columns {a + 1} and {v + 1}"))
    text, sugg = advise(alts) if alts else ("re-export one trace per file", ())
    raise Refusal(
        f"{where}: the table has {len(angle_cols)} angle columns (columns "
        f"{', '.join(str(i + 1) for i in angle_cols)}): several probes or traces side by side, "
        f"not the layers of one scan (layers share one angle column or have a z); {text}",
        sugg,
    )


def _stated_angle_unit(pf: ParsedFile, col: int, option: str | None) -> str | None:
    return option or _UNIT_OF_KIND.get(pf.columns[col]) or pf.angle_unit


def _angle_readings(a: np.ndarray, unit: str | None) -> dict[str, np.ndarray]:
    """Angles [degree] of a column under each unit that could apply (the stated one only)."""
    closed = closed_profile(a, unit)
    if closed:
        a = a[:-1]
    out = {"deg": a.astype(float), "rad": np.degrees(a), "grad": a * 0.9}
    if a.size > 1 and np.all(a == np.round(a)) and np.all(np.diff(a) == 1):
        out["index"] = (a - a[0]) * 360.0 / a.size
    if unit is not None:
        return {unit: out[unit]} if unit in out else {}
    out.pop("grad")
    return out


def _layer_angles(
    pf: ParsedFile,
    ac: int,
    rows: np.ndarray,
    where: str,
    angle_unit: str | None,
    arc: str | None,
    notes: dict[str, str],
) -> tuple[np.ndarray, np.ndarray]:
    """(angles [degree], rows kept) of one layer: a closed profile loses its repeated last
    point; a dense full turn with coarsely rounded angles takes its angles from the row index."""
    a = pf.data[rows, ac]
    unit = _stated_angle_unit(pf, ac, angle_unit)
    closed = closed_profile(a, unit)
    if closed and unit is None and "index" in _angle_readings(a, None):
        raise Refusal(
            f"{where} column {ac + 1}: the angle unit is ambiguous (values {a[0]:g} to {a[-1]:g}, "
            f"{a.size} points): as degrees a closed profile of {a.size - 1} points whose last "
            "repeats the first one turn later; as a point index one full turn of "
            f"{a.size} points. Say which with angle_unit= (CLI --angle-unit deg|index)",
            ({"angle_unit": closed[0]}, {"angle_unit": "index"}),
        )
    if closed:
        v = pf.data[rows, :]
        notes["closed_profile"] = (
            f"the last point (line {pf.line_numbers[rows[-1]]}) repeats the first one turn later "
            f"(closed profile); dropped (values differ by {np.max(np.abs(v[-1] - v[0])):.3g} in "
            "the file unit)"
        )
        rows = rows[:-1]
        a = a[:-1]
        if unit is None:
            unit = closed[0]
    rounded = rounded_full_turn(a, unit)
    if rounded is not None and arc != "partial":
        u, th, res = rounded
        notes["angle"] = (
            f"angles written to {res:.3g} degree ({u}) repeat between rows: a dense full turn "
            f"of {a.size} points; angles taken from the row index (equal steps of "
            f"{360.0 / a.size:.6g} degree)"
        )
        notes["angle_column"] = {"deg": "angle_deg", "rad": "angle_rad", "grad": "angle_grad"}[u]
        return th, rows
    th = _angles(pf, ac, rows, where, angle_unit=angle_unit, arc=arc, notes=notes)
    return _check_angles(th, pf, rows, where), rows


def _decide_kind(
    pf: ParsedFile, value_cols: list[int], value_kind: str | None, where: str, notes: dict
) -> str:
    cols = pf.columns
    named = {cols[i] for i in value_cols} - {"value"}
    if len(named) > 1:
        raise BadInputError(
            f"{where}: the value columns mix radius and deviation ({list(cols)}); pass "
            "columns=... (--columns) so every value column has the same meaning"
        )
    named_kind = named.pop() if named else None
    if value_kind is not None and named_kind is not None and value_kind != named_kind:
        try:  # the user overrides a name only where the numbers agree with the user
            by_numbers, _ = decide_value_kind(pf.data[:, value_cols], where=where)
        except BadInputError:
            by_numbers = None
        if by_numbers != value_kind:
            raise BadInputError(
                f"{where}: value_kind={value_kind!r} (--value-kind) contradicts the column name, "
                f"which says {named_kind}, and the numbers do not settle it; drop the option, "
                "or override the names with columns=... (--columns)"
            )
        notes["value_name_overridden"] = (
            f"the column name says {named_kind}; value_kind={value_kind!r} was given and the "
            "numbers agree with it"
        )
        named_kind = None
    kind, note = decide_value_kind(
        pf.data[:, value_cols],
        named=named_kind,
        stated=value_kind,
        where=f"{where} value column(s) {', '.join(str(i + 1) for i in value_cols)}",
        line_of=pf.line_numbers,
    )
    notes["value_kind"] = f"{kind} ({note})"
    notes["value_column"] = kind
    return kind


def _xy_layer(pf: ParsedFile, rows: np.ndarray, f: float, zval, where: str) -> _Layer:
    cols = pf.columns
    x = pf.data[rows, cols.index("x")] * f
    y = pf.data[rows, cols.index("y")] * f
    if rows.size >= 3:
        _xy_about_origin(x, y, where)
    th = np.degrees(np.arctan2(y, x)) % 360.0
    val = np.hypot(x, y)
    order = np.argsort(th, kind="stable")
    th, val, rws = th[order], val[order], rows[order]
    if np.any(np.diff(th) == 0):
        i = int(np.flatnonzero(np.diff(th) == 0)[0]) + 1
        raise BadInputError(
            f"{where} line {pf.line_numbers[rws[i]]}: two points at the same angle "
            f"({th[i]:g} degree about the origin); delete the duplicate"
        )
    return _Layer(th, val, "radius", zval, pf.path)
