"""From a parsed table to layers: angles, values and z of each trace."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from jointwear.errors import BadInputError
from jointwear.metrology.readers.meaning import absurd_length, angle_reading
from jointwear.metrology.readers.meaning import value_kind as decide_value_kind
from jointwear.metrology.readers.table import ParsedFile, unit_factor

__all__ = []


@dataclass
class _Layer:
    theta_deg: np.ndarray  # instrument convention, ascending in instrument angle
    value: np.ndarray  # [m]
    kind: str  # "radius" or "deviation"
    z: float | None
    source: str


_UNIT_OF_KIND = {"angle_deg": "deg", "angle_rad": "rad", "index": "index"}


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
    notes["angle_column"] = {"deg": "angle_deg", "rad": "angle_rad", "index": "index"}[reading.unit]
    return reading.theta_deg


def _check_angles(theta: np.ndarray, pf: ParsedFile, rows: np.ndarray, where: str) -> np.ndarray:
    """Angles of one layer must increase (or decrease) strictly; one wrap through 360 allowed."""
    th = np.asarray(theta, dtype=float)
    if th.size < 3:
        return th
    d = np.diff(th)
    sgn = 1.0 if np.sum(d > 0) >= np.sum(d < 0) else -1.0
    d = d * sgn
    # allow one wrap of about -360
    wraps = np.flatnonzero(d < -180.0)
    if wraps.size == 1:
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


def _layers_from_file(
    pf: ParsedFile,
    expected_points: int | None,
    *,
    value_kind: str | None = None,
    angle_unit: str | None = None,
    arc: str | None = None,
    notes: dict[str, str] | None = None,
) -> list[_Layer]:
    """Cut a parsed table into layers according to its column meanings.

    Every meaning that the file, the column names or the user do not state is decided by
    :mod:`~jointwear.metrology.readers.meaning` or refused.
    """
    notes = {} if notes is None else notes
    cols = pf.columns
    where = f"'{pf.path}'"
    if pf.units is None and any(c in ("radius", "deviation", "value", "x", "y") for c in cols):
        raise BadInputError(
            f"{where}: the length unit is not stated in the header; pass units='um' (--units um; "
            "or mm, m, inch) - jointwear does not guess units"
        )
    f = unit_factor(pf.units, where=where) if pf.units else 1.0
    zf = f
    zc_idx = [i for i, c in enumerate(cols) if c == "z"]
    if zc_idx and str(zc_idx[0]) in pf.column_units:
        zf = unit_factor(pf.column_units[str(zc_idx[0])], where=f"{where} column {zc_idx[0] + 1}")
    elif zc_idx and pf.z_units is not None:
        zf = unit_factor(pf.z_units, where=f"{where} z unit")
    elif zc_idx and pf.units is None:
        raise BadInputError(
            f"{where}: the unit of the z column is not stated; pass z_units=... (--z-units mm) "
            "or name the column with its unit, e.g. 'z [mm]'"
        )
    elif zc_idx:
        raise BadInputError(
            f"{where}: the unit of the z column is not stated (the header states the unit of "
            f"the values, {pf.units!r}, which need not be that of z); pass z_units=... "
            "(--z-units mm) or name the column with its unit, e.g. 'z [mm]'"
        )
    n = pf.data.shape[0]
    value_cols = [i for i, c in enumerate(cols) if c in ("radius", "deviation", "value")]
    angle_cols = [
        i for i, c in enumerate(cols) if c in ("angle", "angle_deg", "angle_rad", "index")
    ]
    has_xy = "x" in cols and "y" in cols
    zcols = [i for i, c in enumerate(cols) if c == "z"]
    out: list[_Layer] = []
    kind = "radius"
    if value_cols:
        named = {cols[i] for i in value_cols} - {"value"}
        if len(named) > 1:
            raise BadInputError(
                f"{where}: the value columns mix radius and deviation ({list(cols)}); pass "
                "columns=... (--columns) so every value column has the same meaning"
            )
        named_kind = named.pop() if named else None
        if value_kind is not None and named_kind is not None and value_kind != named_kind:
            raise BadInputError(
                f"{where}: value_kind={value_kind!r} (--value-kind) contradicts the column name, "
                f"which says {named_kind}; drop the option, or override the names with "
                "columns=... (--columns)"
            )
        kind, note = decide_value_kind(
            pf.data[:, value_cols],
            named=named_kind,
            stated=value_kind,
            where=f"{where} value column(s) {', '.join(str(i + 1) for i in value_cols)}",
            line_of=pf.line_numbers,
        )
        notes["value_kind"] = f"{kind} ({note})"
        notes["value_column"] = kind
        absurd_length(pf.data[:, value_cols], kind, f, where, pf.line_numbers)
    if has_xy:
        xy = pf.data[:, [cols.index("x"), cols.index("y")]]
        absurd_length(xy, "radius", f, where, pf.line_numbers)
    if not angle_cols and not has_xy and value_cols:
        if arc != "full" and angle_unit != "index":
            raise BadInputError(
                f"{where}: no angle column: the points can be read as equally spaced over one "
                "full turn only if you say so with arc='full' (--arc full); a partial arc needs "
                "an angle column"
            )
        notes["angle"] = "no angle column: points equally spaced over one full turn (stated)"

    def make(rows: np.ndarray, vcol: int | None, zval: float | None) -> _Layer:
        m = rows.size
        if has_xy:
            x = pf.data[rows, cols.index("x")] * f
            y = pf.data[rows, cols.index("y")] * f
            if m >= 3:
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
        assert vcol is not None
        val = pf.data[rows, vcol] * f
        if angle_cols:
            ac = angle_cols[0]
            th = _angles(pf, ac, rows, where, angle_unit=angle_unit, arc=arc, notes=notes)
            th = _check_angles(th, pf, rows, where)
        else:
            th = np.arange(m) * 360.0 / m
        return _Layer(th, val, kind, zval, pf.path)

    if not value_cols and not has_xy:
        raise BadInputError(
            f"{where}: no radius/deviation column among {list(cols)}; pass columns=(...) "
            "(--columns) naming the value column 'radius' or 'deviation'"
        )
    if zcols and (value_cols or has_xy):
        zc = pf.data[:, zcols[0]]
        # layers = runs of constant z
        change = np.flatnonzero(np.diff(zc) != 0) + 1
        starts = np.concatenate([[0], change])
        ends = np.concatenate([change, [n]])
        zs = zc[starts]
        if np.unique(zs).size != zs.size:
            dup = next(i for i in range(len(zs)) if zs[i] in zs[:i])
            raise BadInputError(
                f"{where} line {pf.line_numbers[starts[dup]]}: layer z = {zs[dup]:g} appears "
                "twice (the rows of one layer must be contiguous); sort the file by z"
            )
        for s, e, zv in zip(starts, ends, zs, strict=True):
            out.append(make(np.arange(s, e), value_cols[0] if value_cols else None, float(zv) * zf))
    elif len(value_cols) > 1:
        for vc in value_cols:
            out.append(make(np.arange(n), vc, None))
    else:
        out.append(make(np.arange(n), value_cols[0] if value_cols else None, None))
    for k, lay in enumerate(out):
        if lay.value.size < 4:
            raise BadInputError(
                f"{where}: layer {k + 1} has only {lay.value.size} point(s); a roundness trace "
                "needs at least 4 (the file looks truncated - re-export it)"
            )
    if expected_points is not None:
        for k, lay in enumerate(out):
            if lay.value.size != expected_points:
                raise BadInputError(
                    f"{where}: expected {expected_points} points in layer {k + 1}, found "
                    f"{lay.value.size} - the file looks truncated or the layer is incomplete; "
                    "re-export it or pass expected_points=None / allow_partial=True"
                )
    return out
