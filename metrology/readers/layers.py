"""From a parsed table to layers: angles, values and z of each trace."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from jointwear.errors import BadInputError
from jointwear.metrology.readers.table import ParsedFile, unit_factor

__all__ = []


@dataclass
class _Layer:
    theta_deg: np.ndarray  # instrument convention, ascending in instrument angle
    value: np.ndarray  # [m]
    kind: str  # "radius" or "deviation"
    z: float | None
    source: str


def _angles(
    pf: ParsedFile, col: int, kind: str, n: int, rows: np.ndarray, where: str
) -> np.ndarray:
    a = pf.data[rows, col]
    if kind == "angle_rad":
        return np.degrees(a)
    if kind == "index":
        return a * 360.0 / n
    return a


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


def _layers_from_file(pf: ParsedFile, expected_points: int | None, layer_kind: str) -> list[_Layer]:
    """Cut a parsed table into layers according to its column meanings."""
    cols = pf.columns
    where = f"'{pf.path}'"
    if pf.units is None and any(c in ("radius", "deviation", "x", "y") for c in cols):
        raise BadInputError(
            f"{where}: the length unit is not stated in the header; pass units='um' (or 'mm', "
            "'m', 'inch') - jointwear does not guess units"
        )
    f = unit_factor(pf.units, where=where) if pf.units else 1.0
    zf = f
    zc_idx = [i for i, c in enumerate(cols) if c == "z"]
    if zc_idx and str(zc_idx[0]) in pf.column_units:
        zf = unit_factor(pf.column_units[str(zc_idx[0])], where=f"{where} column {zc_idx[0] + 1}")
    elif zc_idx and pf.units is None:
        raise BadInputError(
            f"{where}: the unit of the z column is not stated; pass units=... (the z column is "
            "read in the same unit as the values unless its name says otherwise, e.g. 'z [mm]')"
        )
    n = pf.data.shape[0]
    value_cols = [i for i, c in enumerate(cols) if c in ("radius", "deviation")]
    angle_cols = [i for i, c in enumerate(cols) if c in ("angle_deg", "angle_rad", "index")]
    has_xy = "x" in cols and "y" in cols
    zcols = [i for i, c in enumerate(cols) if c == "z"]
    out: list[_Layer] = []

    def make(rows: np.ndarray, vcol: int | None, zval: float | None) -> _Layer:
        m = rows.size
        if has_xy:
            x = pf.data[rows, cols.index("x")] * f
            y = pf.data[rows, cols.index("y")] * f
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
            th = _angles(pf, ac, cols[ac], m, rows, where)
            th = _check_angles(th, pf, rows, where)
        else:
            th = np.arange(m) * 360.0 / m
        return _Layer(th, val, cols[vcol] if layer_kind == "auto" else layer_kind, zval, pf.path)

    if not value_cols and not has_xy:
        raise BadInputError(
            f"{where}: no radius/deviation column among {list(cols)}; pass columns=(...) naming "
            "the value column 'radius' or 'deviation'"
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
