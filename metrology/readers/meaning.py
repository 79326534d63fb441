"""What the numbers of a column mean: angle unit, angular span and value kind.

Every decision here is either certain or a refusal. The candidate readings of an angle column
(degrees, radians, sample index) are each turned into angles and classified by their span (one
full turn, a partial arc, several whole turns). A reading whose span is an odd number of turns
(integers 0..179 read as radians: 28.6 turns) is impossible and dropped. When the readings that
remain give different angles, the column is ambiguous and :func:`angle_reading` refuses it,
naming what each reading would give and the option that settles it (``angle_unit`` /
``--angle-unit``, ``arc`` / ``--arc``). Values are radii or deviations by their column name
(matched as a phrase: "radius deviation" is a deviation) or, without a name, by their numbers;
numbers that fit neither clearly, or radius data with a corrupt sign, are refused
(``value_kind`` / ``--value-kind``).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from jointwear.errors import BadInputError
from jointwear.metrology.choices import ANGLE_UNITS, ARCS, VALUE_KINDS
from jointwear.metrology.readers.advice import Refusal

__all__ = [
    "ANGLE_UNITS",
    "ARCS",
    "VALUE_KINDS",
    "AngleReading",
    "angle_reading",
    "angle_span",
    "value_kind",
]

#: One full turn in each angle unit that has one.
TURN = {"deg": 360.0, "rad": 2.0 * np.pi, "grad": 400.0}

_ANGLE_FLAG = "angle_unit= (CLI --angle-unit deg|rad|index|grad)"
_ARC_FLAG = "arc= (CLI --arc full|partial)"
_VALUE_FLAG = "value_kind= (CLI --value-kind radius|deviation)"

#: |value| above which a length is physically absurd for a bore [m]: radius / x / y, deviation.
MAX_RADIUS = 10.0
MAX_DEVIATION = 0.1


@dataclass(frozen=True)
class AngleReading:
    """One reading of an angle column.

    Attributes
    ----------
    unit : str
        ``deg``, ``rad`` or ``index``.
    theta_deg : ndarray
        The angles this reading gives [degree].
    arc : str
        ``full`` (one turn), ``partial`` (less than one turn) or ``turns`` (several whole turns).
    span_deg : float
        Angular span including one sample step [degree].
    """

    unit: str
    theta_deg: np.ndarray
    arc: str
    span_deg: float

    def describe(self) -> str:
        name = {
            "deg": "degrees",
            "rad": "radians",
            "index": "a point index",
            "grad": "gradians",
        }[self.unit]
        n = self.theta_deg.size
        if self.arc == "full":
            what = f"one full turn of {n} points, {self.span_deg / n:.4g} degree apart"
        elif self.arc == "partial":
            what = (
                f"a partial arc of {self.span_deg:.4g} degree "
                f"({self.theta_deg.min():.4g} to {self.theta_deg.max():.4g} degree)"
            )
        else:
            what = f"{self.span_deg / 360:.3g} turns ({self.span_deg:.4g} degree)"
        return f"as {name}: {what}"


def oriented_steps(th: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
    """(direction +1/-1 of most steps, the steps times it, where a step wraps back through 360:
    indices of steps below -180 degree)."""
    d = np.diff(th)
    sgn = 1.0 if np.sum(d > 0) >= np.sum(d < 0) else -1.0
    d = d * sgn
    return sgn, d, np.flatnonzero(d < -180.0)


def angle_span(theta_deg: np.ndarray) -> float:
    """Span of monotonic angles including one sample step [degree]; one wrap through 360 allowed.

    Parameters
    ----------
    theta_deg : ndarray
        Angles in sample order [degree].
    """
    th = np.asarray(theta_deg, dtype=float)
    if th.size < 2:
        return 0.0
    _, d, wraps = oriented_steps(th)
    if wraps.size == 1:
        d = d.copy()
        d[wraps[0]] += 360.0
    step = float(np.median(np.abs(d)))
    return float(np.sum(d)) + step


def _classify(theta_deg: np.ndarray) -> tuple[str | None, float]:
    span = angle_span(theta_deg)
    n = theta_deg.size
    step = span / n if n else 0.0
    tol = 0.5 * step + 1e-9 * 360
    if abs(span - 360.0) <= tol:
        return "full", span
    if span < 360.0:
        return "partial", span
    # several whole turns: only with a sampling step that can trace a circle (< 90 degree)
    k = round(span / 360.0)
    return ("turns" if step < 90.0 and abs(span - 360.0 * k) <= tol else None), span


def _is_index(a: np.ndarray) -> bool:
    return bool(
        a.size >= 2
        and np.all(np.isfinite(a))
        and np.all(a == np.round(a))
        and a[0] in (0.0, 1.0)
        and np.all(np.diff(a) == 1.0)
    )


def _candidates(a: np.ndarray, grad: bool = False) -> dict[str, np.ndarray]:
    out = {"deg": a.astype(float), "rad": np.degrees(a)}
    if _is_index(a):
        out["index"] = (a - a[0]) * 360.0 / a.size
    if grad:  # gradians only when stated: 0..300 is a partial arc in degrees or in gradians
        out["grad"] = a * 0.9
    return out


def closed_profile(a: np.ndarray, unit: str | None) -> list[str]:
    """Units in which the angle column ends one full turn after it starts (a closed profile
    repeating its first point as the last), strictly increasing or decreasing."""
    a = np.asarray(a, dtype=float)
    if a.size < 5 or not np.all(np.isfinite(a)):
        return []
    d = np.diff(a)
    if not (np.all(d > 0) or np.all(d < 0)):
        return []
    step = float(np.median(np.abs(d)))
    out = []
    for u, turn in TURN.items():
        if (unit is None and u == "grad") or (unit is not None and u != unit):
            continue
        if abs(abs(a[-1] - a[0]) - turn) <= 1e-9 * turn + 1e-3 * step:
            out.append(u)
    return out


def rounded_full_turn(a: np.ndarray, unit: str | None) -> tuple[str, np.ndarray, float] | None:
    """A dense full turn whose angles were written with too few decimals (consecutive rows
    share an angle): (unit, angles from the row index [degree], rounding step [degree]) when
    exactly one unit makes every written angle the uniform full-turn grid rounded to the
    column's resolution, else None."""
    a = np.asarray(a, dtype=float)
    if a.size < 8 or not np.all(np.isfinite(a)):
        return None
    d = np.diff(a)
    sgn = 1.0 if np.sum(d > 0) >= np.sum(d < 0) else -1.0
    d = d * sgn
    if not np.any(d == 0) or np.any(d < 0):
        return None
    res = float(np.min(d[d > 0])) if np.any(d > 0) else 0.0
    if res <= 0:
        return None
    n = a.size
    fits = []
    for u, turn in TURN.items():
        if (unit is None and u == "grad") or (unit is not None and u != unit):
            continue
        th = a * (360.0 / turn) * sgn
        r = res * 360.0 / turn
        step = 360.0 / n
        i = np.arange(n)
        th0 = float(np.median(th - i * step))
        if np.max(np.abs(th - th0 - i * step)) <= 0.5 * r * (1 + 1e-6) + 1e-9:
            fits.append((u, sgn * (th0 + i * step), r))
    return fits[0] if len(fits) == 1 else None


def angle_reading(
    values: np.ndarray,
    *,
    unit: str | None = None,
    arc: str | None = None,
    where: str = "angle column",
) -> tuple[AngleReading, str]:
    """Decide how to read an angle column, or refuse.

    Parameters
    ----------
    values : ndarray
        The column as written in the file, in sample order.
    unit : {"deg", "rad", "index"}, optional
        The unit, when the file (column name, header) or the user states it.
    arc : {"full", "partial"}, optional
        The span of the layer, when the user states it.
    where : str
        File and column for messages.

    Returns
    -------
    (AngleReading, str)
        The reading and a note on how it was decided.

    Raises
    ------
    BadInputError
        Several readings give different angles, the stated unit gives several turns, or the
        stated unit contradicts the stated arc.
    """
    a = np.asarray(values, dtype=float)
    if unit is not None and unit not in ANGLE_UNITS:
        raise BadInputError(f"angle unit {unit!r} is not known; use deg, rad, index or grad")
    if arc is not None and arc not in ARCS:
        raise BadInputError(f"arc {arc!r} is not known; use full or partial")
    cands = _candidates(a, grad=unit == "grad")
    if unit == "index" and "index" not in cands:
        raise BadInputError(
            f"{where}: the angle unit is 'index' but the values are not the point numbers "
            f"0, 1, 2, ... (or 1, 2, 3, ...): found {a[:3].tolist()} ...; give the right unit "
            f"with {_ANGLE_FLAG}"
        )
    readings = []
    for u, th in cands.items():
        kind, span = _classify(th)
        if kind is not None:
            readings.append(AngleReading(u, th, kind, span))
    if unit is not None:
        chosen = [r for r in readings if r.unit == unit]
        if not chosen:
            th = cands[unit]
            span = angle_span(th)
            raise BadInputError(
                f"{where}: read as {unit}, the angles span {span:.6g} degree ({span / 360:.4g} "
                "turns), not a whole number of turns; check the angle unit "
                f"({_ANGLE_FLAG})"
            )
        r = chosen[0]
        if r.arc == "turns":
            raise BadInputError(
                f"{where}: read as {unit}, the angles cover {r.span_deg / 360:.3g} full turns "
                f"({r.span_deg:.6g} degree); a layer must be at most one turn - split the trace "
                "into one file per turn, or give the right unit with " + _ANGLE_FLAG
            )
        if arc is not None and r.arc != arc:
            raise BadInputError(
                f"{where}: arc={arc!r} was given, but the angles {r.describe()}; check "
                f"{_ANGLE_FLAG} and {_ARC_FLAG}"
            )
        first = "; point 1 is taken at 0 degree" if unit == "index" and a[0] == 1.0 else ""
        return r, f"angle unit {unit} (stated){first}"
    if arc is not None:
        readings = [r for r in readings if r.arc == arc]
    if not readings:
        g_kind, _ = _classify(a * 0.9)
        grad = g_kind in ("full", "partial") and (arc is None or g_kind == arc)
        raise Refusal(
            f"{where}: no reading of the angle column gives "
            f"{'one full turn' if arc == 'full' else 'a partial arc' if arc else 'at most one turn'}"
            f" (values {a.min():.6g} to {a.max():.6g}, {a.size} points); "
            + (
                "read as gradians (400 per turn) they give "
                f"{'one full turn' if g_kind == 'full' else 'a partial arc'}: pass "
                "angle_unit='grad' if they are; otherwise "
                if grad
                else ""
            )
            + f"check the column meaning (columns=... / --columns) and {_ARC_FLAG}",
            ({"angle_unit": "grad"},) if grad else (),
        )
    distinct: list[AngleReading] = []
    for r in readings:
        if not any(
            d.theta_deg.shape == r.theta_deg.shape and np.allclose(d.theta_deg, r.theta_deg)
            for d in distinct
        ):
            distinct.append(r)
    if len(distinct) > 1:
        settle = []
        arcs = {r.arc for r in distinct}
        if len(arcs) == len(distinct) and "turns" not in arcs:
            settle.append(_ARC_FLAG)
        settle.append(_ANGLE_FLAG)
        sugg = [{"angle_unit": r.unit} for r in distinct if r.arc != "turns"]
        if _ARC_FLAG in settle:
            sugg += [{"arc": r.arc} for r in distinct]
        raise Refusal(
            f"{where}: the angle unit is ambiguous (values {a.min():.6g} to {a.max():.6g}, "
            f"{a.size} points, no unit in the column name or header): "
            + "; ".join(r.describe() for r in distinct)
            + ". Say which with "
            + " or ".join(settle),
            tuple(sugg),
        )
    r = distinct[0]
    if r.arc == "turns":
        raise BadInputError(
            f"{where}: the angles cover {r.span_deg / 360:.3g} full turns read as {r.unit}; a "
            "layer must be at most one turn - split the trace, or give the unit with " + _ANGLE_FLAG
        )
    others = [u for u in cands if u != r.unit and not any(x.unit == u for x in readings)]
    why = (
        f"the only reading that gives {r.arc} {'turn' if r.arc == 'full' else 'arc'}"
        + (f" ({', '.join(others)} would give an odd number of turns)" if others else "")
        if len(readings) == 1
        else f"{' and '.join(x.unit for x in readings)} give the same angles"
    )
    if r.unit == "index" and a[0] == 1.0:
        why += "; numbering starts at 1: point 1 is taken at 0 degree"
    return r, f"angle unit {r.unit}: {why}"


def _robust_spread(v: np.ndarray) -> float:
    # twice the interquartile range: about the peak-to-valley of a smooth profile, and blind to
    # up to a quarter of corrupt points
    q25, q75 = np.percentile(v, [25, 75])
    return float(2.0 * (q75 - q25))


def value_kind(
    values: np.ndarray,
    *,
    named: str | None = None,
    stated: str | None = None,
    where: str = "value column",
    line_of: Sequence[int] | np.ndarray | None = None,
    unit_factor: float = 1.0,
) -> tuple[str, str]:
    """Decide whether value columns hold radii or deviations, or refuse.

    Parameters
    ----------
    values : ndarray
        The value column(s) as written in the file (any shape; rows along the first axis).
    named : {"radius", "deviation"}, optional
        The kind the column name states.
    stated : {"radius", "deviation"}, optional
        The kind the user states (wins over the name).
    where : str
        File and column for messages.
    line_of : sequence of int, optional
        1-based file line of each row, for messages.
    unit_factor : float
        File unit to metres (for the magnitude checks).

    Returns
    -------
    (str, str)
        ``radius`` or ``deviation``, and a note on how it was decided.
    """
    v = np.asarray(values, dtype=float)
    flat = v.reshape(v.shape[0], -1) if v.ndim > 1 else v[:, None]
    finite = flat[np.isfinite(flat)]

    def line(row: int) -> str:
        return f" line {int(line_of[row])}" if line_of is not None else f" row {row + 1}"

    if stated is not None and stated not in VALUE_KINDS:
        raise BadInputError(f"value kind {stated!r} is not known; use radius or deviation")
    if finite.size == 0:
        raise BadInputError(f"{where}: no values")
    med = float(np.median(finite))
    spread = _robust_spread(finite)
    ptp = float(np.ptp(finite))
    # what the numbers say on their own: radius-like (positive, spread tiny against the mean),
    # deviation-like (about zero, or an offset comparable to the spread)
    # (a bore of 8 mm with 50 um of set-up eccentricity and form is ~80; a deviation trace
    # offset by a wrong nominal radius ~1..5)
    robust_radius = med > 0 and med > 25 * max(spread, 1e-300)
    robust_dev = abs(med) <= 5 * max(spread, 1e-300)
    rows_bad = np.flatnonzero(np.any(flat <= 0, axis=1)) if robust_radius else np.array([])
    kind = stated or named
    if kind == "radius":
        bad = np.flatnonzero(np.any(flat <= 0, axis=1))
        if bad.size:
            r = int(bad[0])
            raise Refusal(
                f"{where}{line(r)}: radius {flat[r][flat[r] <= 0][0]:g} is not positive "
                f"(the other radii are about {med:g}); a corrupt value? fix or delete the line"
                + (
                    ""
                    if stated
                    else f", or if the column holds deviations say so with {_VALUE_FLAG}"
                ),
                () if stated else ({"value": "deviation"},),
            )
    if kind in VALUE_KINDS:  # named (or stated): unless the numbers clearly say the other
        if kind == "radius":
            other, looks = "deviation", robust_dev and not robust_radius
            seen = f"({finite.min():g} to {finite.max():g}) look like deviations about zero"
        else:
            other, looks = "radius", robust_radius and not robust_dev
            seen = f"(median {med:g}, spread {spread:g}) look like radii"
        if stated is None and looks:
            raise Refusal(
                f"{where}: the column name says {kind} but the values {seen}; say which with "
                f"{_VALUE_FLAG}",
                ({"value": kind}, {"value": other}),
            )
        return kind, ("stated" if stated else "from the column name")
    if robust_radius and rows_bad.size == 0 and ptp < med / 25:
        return "radius", (f"radius: values positive, median {med:g} over 25 x their spread {ptp:g}")
    if robust_dev and not robust_radius:
        return "deviation", (
            f"deviation: median {med:g} within 5 x the spread {spread:g} of the values"
        )
    if robust_radius:
        r = (
            int(rows_bad[0])
            if rows_bad.size
            else int(np.argmax(np.max(np.abs(flat - med), axis=1)))
        )
        raise Refusal(
            f"{where}{line(r)}: the values look like radii (median {med:g}) except "
            f"{flat[r][np.argmax(np.abs(flat[r] - med))]:g} here - a corrupt value would turn "
            "them into deviations; fix or delete the line, or say what the column holds with "
            + _VALUE_FLAG,
            ({"value": "radius"}, {"value": "deviation"}),
        )
    raise Refusal(
        f"{where}: cannot tell radius from deviation (median {med:g}, spread {spread:g}, no "
        f"'radius' or 'deviation' in the column name): as radius the bore would be about "
        f"{med:g} with a form error of {ptp:g}; as deviation the offset from the nominal "
        f"would be {med:g}; say which with {_VALUE_FLAG}",
        ({"value": "radius"}, {"value": "deviation"}),
    )


def absurd_length(
    values: np.ndarray, kind: str, factor: float, where: str, line_of: np.ndarray | None
) -> None:
    """Refuse lengths no bore has (|radius| > 10 m, |deviation| > 0.1 m) naming the line."""
    limit = MAX_DEVIATION if kind == "deviation" else MAX_RADIUS
    v = np.abs(np.asarray(values, dtype=float)) * factor
    v2 = v.reshape(v.shape[0], -1)
    bad = np.flatnonzero(np.any(v2 > limit, axis=1))
    if bad.size:
        r = int(bad[0])
        val = float(np.max(v2[r])) / factor
        ln = f" line {int(line_of[r])}" if line_of is not None else f" row {r + 1}"
        raise BadInputError(
            f"{where}{ln}: {kind} {val:g} ({val * factor:.3g} m) is physically absurd for a bore "
            f"(limit {limit:g} m); a corrupt value or a wrong unit - fix the line or check the "
            "unit"
        )
