"""Header claims checked against the numbers.

A header line is a claim about the table under it; a claim the numbers contradict is refused,
naming both and the option that settles it (:class:`~.advice.Refusal`), never silently
believed or silently overridden. Checked here (limits in :data:`~jointwear.metrology.choices.PLAUSIBILITY`,
overridable):

* the length unit against the magnitude of the values: a radius must make a bore of plausible
  size (``radius_min`` .. ``radius_max``), a deviation must stay within a gauge's range
  (``max_deviation``) and within ``deviation_fraction`` of a stated nominal radius, and their
  form (peak-to-valley) within ``form_fraction`` (1 %) of a stated nominal radius;
* the nominal radius against the measured radius (``nominal_tolerance``);
* the points per revolution against the rows of a layer and its angular step;
* a stated Gaussian filter against the spectrum (a profile filtered at k_c UPR holds almost
  nothing above 3 k_c);
* the stated number of layers, z extent and layer spacing against the layers found
  (:func:`check_layers`); a layer spacing that is the only source of z is recorded as
  unconfirmed unless a z extent confirms it, and refused when its key does not say it is
  between layers (``Spacing``, ``Pitch``);
* an inch/mm slip: the 25.4 ratio is named in the refusal of a radius magnitude or a nominal.

A claim the user knows to be wrong is dropped with ``ignore_header=<claim>`` (CLI
``--ignore-header``), and the dropped claim is recorded.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

from jointwear.metrology.readers.advice import Refusal, advise
from jointwear.metrology.readers.units import unit_factor

__all__ = [
    "CLAIMS",
    "ValueUnit",
    "claim",
    "drop_ignored",
    "check_magnitude",
    "check_form",
    "check_points",
    "check_filter",
]

_NUMU = r"[-+]?(?:\d+(?:[.,]\d*)?|[.,]\d+)(?:[eE][-+]?\d+)?"

#: Header claims by name (the names ``ignore_header`` takes) -> pattern of their keys.
CLAIMS: dict[str, re.Pattern] = {
    "units": re.compile(r"^(units?|length[ _]?units?|einheit|unit of measure|scale units?)$", re.I),
    "nominal_radius": re.compile(
        r"^(nominal[ _]?radius|radius|nominal[ _]?diameter|diameter|bore (radius|diameter))$",
        re.I,
    ),
    "points": re.compile(
        r"^(points?( per (rev(olution)?|turn|layer|trace))?|n[ _]?points|number of points|"
        r"no\.? of points|samples( per (rev(olution)?|turn))?|data points|ppr)$",
        re.I,
    ),
    "filter": re.compile(r"^(filter( type)?|filter cut-?off|cut-?off|lpf)$", re.I),
    "layers": re.compile(
        r"^(layers|number of (layers|planes|traces)|n[ _]?layers|planes|no\.? of layers|"
        r"layer count)$",
        re.I,
    ),
    "layer_spacing": re.compile(
        r"^((layer|plane|trace)[ _]?(spacing|pitch|step|distance)|spacing|pitch)$", re.I
    ),
    "z_extent": re.compile(
        r"^((z|height|axial)[ _]?(range|span|extent)|axial length|total height)$",
        re.I,
    ),
    "z": re.compile(
        r"^(z|z[ _]?position|height|level|layer[ _]?height|position|axial position|"
        r"plane height|z \(mm\)|height \(mm\))$",
        re.I,
    ),
}


def drop_ignored(meta: dict[str, str], ignore: tuple[str, ...]) -> dict[str, str]:
    """``meta`` without the header lines of the claims in ``ignore`` (names of :data:`CLAIMS`)."""
    bad = [c for c in ignore if c not in CLAIMS]
    if bad:
        raise Refusal(f"ignore_header={bad[0]!r} is not a header claim; known: {', '.join(CLAIMS)}")
    return {k: v for k, v in meta.items() if not any(CLAIMS[c].match(k.strip()) for c in ignore)}


def claim(meta: dict[str, str], name: str) -> tuple[str, str] | None:
    """(key, value) of the first header line stating claim ``name``, else None."""
    for k, v in meta.items():
        if CLAIMS[name].match(k.strip()) and str(v).strip():
            return k, str(v).strip()
    return None


def _length(text: str, default_unit: str | None) -> float | None:
    m = re.match(rf"^\s*({_NUMU})\s*([A-Za-zµμ\"]+)?", text)
    if not m:
        return None
    unit = m.group(2) or default_unit
    if unit is None:
        return None
    try:
        return float(m.group(1).replace(",", ".")) * unit_factor(unit)
    except Exception:  # a word after the number that is no unit: not a length claim
        return None


def nominal_radius(meta: dict[str, str], file_unit: str | None) -> tuple[str, float] | None:
    """(header key, nominal radius [m]) from a nominal radius/diameter line, else None."""
    c = claim(meta, "nominal_radius")
    if c is None:
        return None
    val = _length(c[1], file_unit)
    if val is None or not val > 0:
        return None
    return c[0], val / 2 if "diam" in c[0].lower() else val


def _units_fix(stated_by_file: bool, unit: str) -> dict:
    return {"ignore_header": ("units",), "units": unit} if stated_by_file else {"units": unit}


def _fmt(v_m: float) -> str:
    a = abs(v_m)
    if a >= 1.0:
        return f"{v_m:.4g} m"
    if a >= 1e-3:
        return f"{v_m * 1e3:.4g} mm"
    if a >= 1e-6:
        return f"{v_m * 1e6:.4g} µm"
    return f"{v_m * 1e9:.4g} nm"


_TRY_UNITS = ("um", "mm", "m", "inch")


def _ratio(unit: str, other: str) -> str:
    """How many times a value in ``other`` is the same number in ``unit``: ``25.4`` and
    ``1/25.4`` (an inch/mm slip) spelled exactly, else to 4 digits."""
    k = unit_factor(other) / unit_factor(unit)
    for exact, text in ((25.4, "25.4"), (1 / 25.4, "1/25.4")):
        if abs(k / exact - 1) < 1e-9:
            return text
    return f"{k:.4g}"


@dataclass(frozen=True)
class ValueUnit:
    """The length unit a table's values are read in, and who stated it.

    Attributes
    ----------
    name : str
        The unit (``"mm"``, ``"um"``, ``"inch"``, ...).
    stated_by_file : bool
        The unit comes from the file's header (a fix must then drop the header's unit), else
        from ``units=``.
    """

    name: str
    stated_by_file: bool

    @property
    def source(self) -> str:
        """Who stated the unit, as the refusals say it."""
        return "stated by the file" if self.stated_by_file else "units= given"


def check_magnitude(
    values: np.ndarray,
    kind: str,
    value_unit: ValueUnit,
    meta: dict[str, str],
    limits: dict[str, float],
    where: str,
    notes: dict[str, str],
) -> None:
    """Refuse a unit the magnitudes contradict, and a nominal radius the radii contradict.

    Parameters
    ----------
    values : ndarray
        The value column(s) as written (file unit).
    kind : {"radius", "deviation"}
    value_unit : ValueUnit
        The unit the values are read in and who stated it.
    meta : dict
        Header metadata (for the nominal radius).
    limits : dict
        Plausibility limits (:data:`~jointwear.metrology.choices.PLAUSIBILITY` with overrides).
    """
    unit, unit_source, stated_by_file = (
        value_unit.name,
        value_unit.source,
        value_unit.stated_by_file,
    )
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return
    f = unit_factor(unit)
    med = float(np.median(v))
    nominal = nominal_radius(meta, unit if stated_by_file else None)
    if kind == "radius":
        r = med * f
        if not limits["radius_min"] <= r <= limits["radius_max"]:
            alts = [
                u
                for u in _TRY_UNITS
                if unit_factor(u) != f
                and limits["radius_min"] <= med * unit_factor(u) <= limits["radius_max"]
                and (nominal is None or _agree(med * unit_factor(u), nominal[1], limits))
            ]
            text, sugg = advise(
                [
                    (
                        _units_fix(stated_by_file, u),
                        f"if the values are in {u}: a radius of {_fmt(med * unit_factor(u))}, "
                        f"{_ratio(unit, u)} x the {unit} reading",
                    )
                    for u in alts
                ]
            )
            raise Refusal(
                f"{where}: the values are read in {unit!r} ({unit_source}), which makes the radii "
                f"about {_fmt(r)} - not a plausible bore (limits {_fmt(limits['radius_min'])} to "
                f"{_fmt(limits['radius_max'])}); "
                + (text + "; " if alts else "")
                + "if the part really is that size, widen the limits with radius_range=<m>",
                sugg,
            )
        if nominal is not None and not _agree(r, nominal[1], limits):
            agree = [
                u
                for u in _TRY_UNITS
                if unit_factor(u) != f and _agree(med * unit_factor(u), nominal[1], limits)
            ]
            alts = _unit_fixes(stated_by_file, agree)
            alts.append(
                ({"ignore_header": ("nominal_radius",)}, f"if the header's {nominal[0]!r} is wrong")
            )
            text, sugg = advise(alts)
            if abs(r / nominal[1] - 2) < limits["nominal_tolerance"]:
                why = f"{r / nominal[1]:.3g} x: is the header's radius a diameter?"
            elif agree:  # name the unit ratio exactly: 25.4 is an inch/mm slip
                why = f"{_ratio(agree[0], unit)} x: values in {agree[0]} read as {unit}?"
            elif _agree(r, nominal[1] * 25.4, limits) or _agree(r, nominal[1] / 25.4, limits):
                k = "25.4" if r > nominal[1] else "1/25.4"
                why = f"{k} x: an inch/mm slip between the nominal and the values?"
            else:
                why = f"{r / nominal[1]:.3g} x"
            raise Refusal(
                f"{where}: the header says {nominal[0]} = {meta[nominal[0]]!r} ({_fmt(nominal[1])} "
                f"radius) but the measured radii are about {_fmt(r)} ({why}), beyond the {limits['nominal_tolerance']:.0%} tolerance "
                f"(nominal_tolerance); {text}",
                sugg,
            )
        if nominal is not None:
            notes["nominal_radius_check"] = (
                f"measured radius {_fmt(r)} agrees with the header's {_fmt(nominal[1])}"
            )
        return
    dmax = float(np.percentile(np.abs(v), 90)) * f  # a unit scales all values, a spike one
    limit = limits["max_deviation"]
    why = f"a gauge's range (max_deviation = {_fmt(limit)})"
    if nominal is not None and limits["deviation_fraction"] * nominal[1] < limit:
        limit = limits["deviation_fraction"] * nominal[1]
        why = (
            f"{limits['deviation_fraction']:.0%} of the header's nominal radius "
            f"{_fmt(nominal[1])} (deviation_fraction)"
        )
    ptp = float(np.ptp(v)) * f
    if 0 < ptp < limits["min_form"]:
        larger = [
            u
            for u in ("um", "mm")
            if unit_factor(u) > f
            and ptp / f * unit_factor(u) >= limits["min_form"]
            and float(np.max(np.abs(v))) * unit_factor(u) <= limit
        ][:1]
        raise _wrong_deviation_unit(
            f"{where}: the values are read in {unit!r} ({unit_source}) as radial deviations "
            f"with a peak-to-valley of {_fmt(ptp)}, below any roundness probe's noise "
            f"(min_form = {_fmt(limits['min_form'])})",
            _unit_fixes(stated_by_file, larger),
            "if the trace really is that flat, lower the limit with min_form=<m>",
        )
    if dmax > limit:
        smaller = [
            u for u in ("mm", "um") if unit_factor(u) < f and dmax / f * unit_factor(u) <= limit
        ][:1]
        raise _wrong_deviation_unit(
            f"{where}: the values are read in {unit!r} ({unit_source}) as radial deviations of "
            f"{_fmt(dmax)} and more (a tenth of them), more than {why}",
            _unit_fixes(stated_by_file, smaller),
            "if the deviations really are that large, raise the limit with max_deviation=<m> "
            "(or pass value='radius' if the column holds radii)",
        )


def layer_form(theta_deg: np.ndarray, value: np.ndarray) -> float:
    """Peak-to-valley [value units] of the 0.5-99.5 % range of a layer's residual from its
    least-squares limaçon (the set-up's eccentricity is no form); NaN points skipped."""
    ok = np.isfinite(value)
    t = np.radians(np.asarray(theta_deg, dtype=float)[ok])
    v = np.asarray(value, dtype=float)[ok]
    if v.size < 4:
        return 0.0
    a = np.column_stack([np.ones_like(t), np.cos(t), np.sin(t)])
    res = v - a @ np.linalg.lstsq(a, v, rcond=None)[0]
    lo, hi = np.percentile(res, [0.5, 99.5])
    return float(hi - lo)


def check_form(
    form: float, value_unit: ValueUnit, meta: dict[str, str], limits: dict[str, float], where: str
) -> None:
    """Refuse deviations whose form ``form`` [m] (the largest :func:`layer_form` of the
    layers) exceeds ``form_fraction`` (1 %) of the header's nominal radius: a precision bore's
    form is far smaller (a sub-micrometre form written in um under ``Units: mm`` reads 1000 x
    too large). Nothing is checked without a stated nominal radius; ``value_unit`` is the unit
    the values are read in (:class:`ValueUnit`)."""
    unit, unit_source, stated_by_file = (
        value_unit.name,
        value_unit.source,
        value_unit.stated_by_file,
    )
    nominal = nominal_radius(meta, unit if stated_by_file else None)
    if nominal is None:
        return
    f = unit_factor(unit)
    limit = limits["form_fraction"] * nominal[1]
    if form <= limit:
        return
    others = [
        u for u in ("um", "mm", "inch") if unit_factor(u) < f and form / f * unit_factor(u) <= limit
    ][:1]
    written = form / f
    sym = {"um": "µm", "inch": "in"}
    readings = "".join(f"; read in {u} it is {written:.4g} {sym.get(u, u)}" for u in others)
    raise _wrong_deviation_unit(
        f"{where}: the values are read in {unit!r} ({unit_source}) as radial deviations with "
        f"a form (peak-to-valley) of {written:.4g} {sym.get(unit, unit)}, "
        f"{form / nominal[1]:.2%} of the header's nominal radius {_fmt(nominal[1])} "
        f"({nominal[0]}), where a precision bore's form stays below "
        f"{limits['form_fraction']:.0%} of its radius (form_fraction){readings}",
        _unit_fixes(stated_by_file, others),
        "if the form really is that large, raise the limit with form_fraction=<value>",
    )


def _unit_fixes(stated_by_file: bool, units: list[str]) -> list[tuple[dict, str]]:
    """The fix that reads the values in each of ``units``, with when it is the right one."""
    return [(_units_fix(stated_by_file, u), f"if the values are in {u}") for u in units]


def _wrong_deviation_unit(finding: str, fixes: list[tuple[dict, str]], keep: str) -> Refusal:
    """Refuse deviations whose magnitude (``finding``) says their unit is wrong: the ``fixes``
    of :func:`_unit_fixes` that would read them plausibly, else ``keep`` (how to accept them)."""
    text, sugg = advise(fixes) if fixes else ("", ())
    return Refusal(f"{finding}: a wrong unit" + (f"? {text}" if fixes else "?") + f"; {keep}", sugg)


def _agree(r: float, nominal: float, limits: dict[str, float]) -> bool:
    return abs(r - nominal) <= limits["nominal_tolerance"] * nominal


def stated_points(meta: dict[str, str], where: str) -> int | None:
    """Points per revolution stated by the header, else None."""
    c = claim(meta, "points")
    if c is None:
        return None
    m = re.match(r"^\s*(\d+)(?:\s|$|[^\d.,])", c[1].replace("'", "").replace(" ", " "))
    if not m:
        raise Refusal(
            f"{where}: header {c[0]} = {c[1]!r} is not a whole number of points; correct the "
            "line, or pass ignore_header='points'",
            ({"ignore_header": ("points",)},),
        )
    return int(m.group(1))


def check_points(
    n_stated: int,
    rows: int,
    angles: dict[str, np.ndarray],
    arc: str | None,
    unit_stated: bool,
    where: str,
    limits: dict[str, float],
) -> None:
    """Refuse a layer whose rows or angular step contradict the stated points per revolution.

    Parameters
    ----------
    n_stated : int
        Points per revolution the header states.
    rows : int
        Points in the layer.
    angles : dict
        The layer's angles [degree] under each possible reading of its angle column (unit ->
        angles; one entry when the unit is stated, none without an angle column).
    arc : {"full", "partial"} or None
        The span the user (or header) states.
    unit_stated : bool
        The angle unit is stated (a fix cannot change it).
    """
    step = 360.0 / n_stated
    tol = limits["points_tolerance"]

    def steps_ok(th: np.ndarray) -> bool:
        d = np.diff(th)
        return th.size > 1 and abs(float(np.median(np.abs(d))) - step) <= tol * step

    matching = [u for u, th in angles.items() if steps_ok(th)]
    if rows == n_stated and (not angles or matching):
        return
    ignore = ({"ignore_header": ("points",)}, "if the header's points per revolution is wrong")
    if rows != n_stated and not angles:
        text, sugg = advise([ignore])
        raise Refusal(
            f"{where}: the header states {n_stated} points per revolution but the layer has "
            f"{rows} rows and no angle column; a truncated or decimated export? re-export it, "
            f"or {text}",
            sugg,
        )
    alts = []
    if rows < n_stated and matching and arc != "full":
        if arc == "partial":
            return  # a partial arc sampled at the stated step: consistent
        u = matching[0]
        partial = {"arc": "partial"} if unit_stated else {"arc": "partial", "angle_unit": u}
        alts.append((partial, f"if it is a partial arc of {rows * step:.4g} degree"))
    if not unit_stated and matching and rows == n_stated:
        alts += [({"angle_unit": u}, f"if the angles are in {u}") for u in matching]
    alts.append(ignore)
    text, sugg = advise(alts)
    got = ", ".join(
        f"as {u}: a step of {float(np.median(np.abs(np.diff(th)))):.6g} degree"
        for u, th in angles.items()
        if th.size > 1
    )
    raise Refusal(
        f"{where}: the header states {n_stated} points per revolution (a step of {step:.6g} "
        f"degree) but the layer has {rows} rows ({got}); "
        + ("a truncated trace (re-export it) or " if rows < n_stated else "")
        + text,
        sugg,
    )


def stated_filter(meta: dict[str, str]) -> tuple[str, str, float | None] | None:
    """(key, value, cut-off in UPR or None for 'no filter' / a filter that cannot be checked)."""
    c = claim(meta, "filter")
    if c is None:
        return None
    v = c[1].lower()
    if re.search(r"\b(none|off|no|unfiltered|raw)\b", v):
        return c[0], c[1], None
    if re.search(r"2\s*rc|\brc\b|analog", v):
        return c[0], c[1], None  # 2RC passes 37 % at 3 k_c: the spectrum cannot test it
    nums = [float(x) for x in re.findall(r"\d+(?:\.\d+)?", v)]
    return (c[0], c[1], max(nums)) if nums else (c[0], c[1], None)


def check_filter(
    values: np.ndarray, stated: tuple[str, str, float | None], where: str, limits: dict
) -> str:
    """Refuse a layer that holds what a stated Gaussian filter removes; returns a note.

    A Gaussian filter of cut-off k_c UPR (ISO 16610-21) passes exp(-pi (alpha k / k_c)^2) of
    each harmonic: 2^-9 of the amplitude at 3 k_c, less above, so a filtered profile keeps at
    most 2^-18 (3.8e-6) of the energy that was above 3 k_c. The test is the energy above 3 k_c
    against the energy of every harmonic from 2 on (the first is centring), after subtracting
    the most the export's rounding can put there (errors of at most q/2 at the resolution q
    seen in the values: at most n^2 q^2 / 8 in the FFT's units, whatever their spectrum). An
    excess above ``filter_energy`` (1e-4: the filtered input would have needed 26 x more energy
    above 3 k_c than below) contradicts the claim. One-sided: an unfiltered profile whose high
    band is that weak passes.
    """
    key, text, kc = stated
    if kc is None:
        return f"header {key} = {text!r} (not checked against the data)"
    v = np.asarray(values, dtype=float)
    n = v.size
    if not np.all(np.isfinite(v)) or n < 8 * kc or kc < 2:
        return f"header {key} = {text!r} (too few points to check it)"
    power = np.abs(np.fft.rfft(v - v.mean())) ** 2
    hi = float(power[int(3 * kc) + 1 :].sum())
    total = float(power[2:].sum())
    steps = np.diff(np.unique(v))
    q = float(steps.min()) if steps.size else 0.0
    floor = n * n * q * q / 8
    if total <= 0:
        return f"header {key} = {text!r} (a flat trace: nothing to check)"
    excess = max(hi - floor, 0.0) / total
    if excess > limits["filter_energy"]:
        msg, sugg = advise(
            [({"ignore_header": ("filter",)}, "if the header's filter line is wrong")]
        )
        raise Refusal(
            f"{where}: the header says {key} = {text!r} (a {kc:g} UPR low-pass) but the trace "
            f"holds {excess:.2g} of its energy (harmonics 2 and up) above {3 * kc:g} UPR, "
            f"beyond what the export's rounding can put there, where such a filter leaves "
            f"less than 3.8e-6 of what was there (limit filter_energy = "
            f"{limits['filter_energy']:g}): the data are not filtered as stated; {msg}",
            sugg,
        )
    return (
        f"header {key} = {text!r}: consistent with the spectrum (energy above {3 * kc:g} UPR "
        f"{excess:.2g} of the total beyond the rounding floor)"
    )


def _z_extent(meta: dict[str, str], z_unit: str | None) -> tuple[str, str, float] | None:
    """(key, value, stated z extent [m]) from a ``Z range: 0 - 4 mm`` / ``Total height: 4 mm``
    line, else None (also when it gives no unit and the file states none for z)."""
    c = claim(meta, "z_extent")
    if c is None:
        return None
    m = re.match(
        rf"^\s*({_NUMU})(?:\s*(?:-|–|to|\.\.|…)\s*({_NUMU}))?\s*([A-Za-zµμ\"]+)?\s*$", c[1]
    )
    unit = (m.group(3) if m else None) or z_unit
    if m is None or unit is None:
        return None
    a = float(m.group(1).replace(",", "."))
    b = float(m.group(2).replace(",", ".")) if m.group(2) else 0.0
    try:
        return c[0], c[1], abs(b - a) * unit_factor(unit)
    except Exception:  # not a length unit: not a z extent
        return None


def check_layers(layers, meta: dict[str, str], zsrc: str, limits: dict, where: str) -> str | None:
    """Refuse a stated number of layers, layer spacing or z extent that the layers found
    contradict.

    Returns
    -------
    str or None
        A note when z rests on the header's layer spacing alone (nothing in the file confirms
        it: no z column, per-layer heights or stated z extent); the reader records it in the
        ``z_unconfirmed`` attribute and the import summary prints it.
    """
    c = claim(meta, "layers")
    if c is not None:
        m = re.match(r"^\s*(\d+)\s*$", c[1])
        if m and int(m.group(1)) != len(layers):
            _refuse_claim(
                where,
                c,
                f"but {len(layers)} layer(s) were found; a missing or extra layer file/block? "
                "restore it, or",
                "layers",
                "count",
            )
    if len(layers) < 2:
        return None
    zs = np.sort([lay.z for lay in layers])
    ext = _z_extent(meta, None)
    if (
        ext is not None
        and abs((zs[-1] - zs[0]) - ext[2]) > limits["spacing_tolerance"] * ext[2] + 1e-9
    ):
        sp = claim(meta, "layer_spacing")
        also = (
            [
                (
                    {"ignore_header": ("layer_spacing",), "layer_spacing": "<m>"},
                    f"if the header's {sp[0]!r} is wrong",
                )
            ]
            if sp is not None and "header" in zsrc and sp[0] in zsrc
            else []
        )
        _refuse_claim(
            where,
            ext[:2],
            f"but the layers span {_fmt(zs[-1] - zs[0])} (z from the {zsrc});",
            "z_extent",
            "z extent",
            also,
        )
    c = claim(meta, "layer_spacing")
    stated = None if c is None else _length(c[1], None)
    if c is None or stated is None:
        return None
    if "header" in zsrc and c[0] in zsrc:  # the header's spacing is the source of z
        return _sole_spacing(c, ext, len(layers), where)
    found = float(np.median(np.diff(zs)))
    if abs(found - stated) > limits["spacing_tolerance"] * stated:
        _refuse_claim(
            where,
            c,
            f"({_fmt(stated)}) but the layers are {_fmt(found)} apart (z from the {zsrc});",
            "layer_spacing",
            "spacing",
        )
    return None


def _refuse_claim(
    where: str, c: tuple[str, str], found: str, name: str, what: str, also: list = ()
) -> None:
    """Refuse header line ``c`` (claim ``name``) that ``found`` contradicts (``found`` ends
    with the separator before "pass ignore_header=..."; ``also``: further fixes)."""
    text, sugg = advise([({"ignore_header": (name,)}, f"if the header's {what} is wrong"), *also])
    raise Refusal(f"{where}: the header says {c[0]} = {c[1]!r} {found} {text}", sugg)


def _sole_spacing(c: tuple[str, str], ext, n_layers: int, where: str) -> str:
    """The header's layer spacing gives z alone: refuse a key that does not say it is between
    layers (``Spacing``, ``Pitch``: the sampling step of the trace as much as the layers'),
    else say what confirms it, or that nothing does."""
    if not re.match(r"^(layer|plane|trace)", c[0].strip(), re.I):
        text, sugg = advise(
            [
                ({"layer_spacing": "<m>"}, f"if {c[0].strip()!r} is the distance between layers"),
                (
                    {"ignore_header": ("layer_spacing",), "layer_spacing": "<m>"},
                    f"the distance between layers, if {c[0].strip()!r} is another spacing",
                ),
            ]
        )
        raise Refusal(
            f"{where}: z would come from the header's {c[0]} = {c[1]!r} alone, and "
            f"{c[0].strip()!r} does not say it is the distance between layers (a sampling "
            f"step along the trace is written the same way); {text}",
            sugg,
        )
    if ext is not None:
        return ""  # the stated z extent agrees (checked above)
    return (
        f"z from the header's {c[0]} = {c[1]!r} alone over {n_layers} layers: nothing in the "
        "file confirms it (no z column, per-layer heights or z range); check it, or pass "
        "layer_spacing=<m> (--layer-spacing-mm)"
    )
