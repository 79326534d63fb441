"""The validation report: one self-contained HTML file (and a PDF fallback) from a comparison.

The HTML is rendered from Jinja2 templates shipped as package data
(``jointwear/reports/templates/report.html`` and ``report.css``); CSS and figures are inline
(SVG for line plots, PNG for the dense maps), nothing is fetched from the network and no
JavaScript is needed. The same inputs give the same bytes: no clock is read (dates come from the
inputs' own provenance), figures are rendered deterministically (:mod:`.figures`) and every
mapping is written in sorted order.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from jointwear import io
from jointwear._version import __version__
from jointwear.compare import Comparison, Criteria, compare
from jointwear.errors import BadInputError
from jointwear.params import to_jsonable
from jointwear.provenance import command_line, sha256_file, software_versions

__all__ = [
    "ReportInput",
    "build_report",
    "render_html",
    "write_pdf",
    "report_from_files",
    "format_value",
]

DEFAULT_TITLE = "Wear simulation validation report"


@dataclass(frozen=True)
class ReportInput:
    """One input of the report, listed in its provenance section.

    Attributes
    ----------
    role : str
        What the file is: ``"simulation"``, ``"metrology"``, ``"DIC"``, ``"verification"``,
        ``"comparison"``.
    path : Path or None
        The file (hashed with sha256), if the data came from one.
    dataset : Dataset or None
        Its content (for the embedded provenance: source, history, command).
    """

    role: str
    path: Path | None = None
    dataset: xr.Dataset | None = None


def format_value(value: float, units: str, *, digits: int = 4) -> tuple[str, str]:
    """A number and its unit for display: lengths in µm, volumes in mm³, others as given."""
    if value is None or not np.isfinite(value):
        return "n/a", units
    scale = {"m": (1e6, "µm"), "m3": (1e9, "mm³"), "m s-1": (1.0, "m/s"), "1": (1.0, "")}
    factor, shown = scale.get(units, (1.0, units))
    v = value * factor
    if v == 0:
        return "0", shown
    if abs(v) >= 1e-3 and abs(v) < 1e5:
        return f"{v:.{digits}g}", shown
    return f"{v:.{digits - 1}e}", shown


def _template(name: str) -> str:
    return (resources.files("jointwear.reports") / "templates" / name).read_text(encoding="utf-8")


def _cycles(value: Any) -> str:
    try:
        v = float(value)
    except (TypeError, ValueError):
        return "(not stated)"
    return f"{v:.4g}" if np.isfinite(v) else "(not stated)"


def _alignment(c: Comparison) -> list[tuple[str, str]]:
    out: list[tuple[str, str]] = []
    if c.wear is not None:
        a = c.wear.attrs
        out.append(("wear maps", str(a.get("interpolation", ""))))
        if "z_overlap_m" in a:
            lo, hi = (float(v) for v in np.ravel(a["z_overlap_m"]))
            out.append(("axial range compared", f"z from {lo * 1e3:+.2f} mm to {hi * 1e3:+.2f} mm"))
        for key, label in (
            ("angle_convention_sim", "simulation"),
            ("angle_convention_meas", "measurement"),
        ):
            if key in a:
                out.append(
                    (
                        f"angle convention of the {label}",
                        f"{a[key]}; converted to the canonical convention (0 along −x, clockwise)",
                    )
                )
        if "cycles_selection" in a:
            cs, cm = _cycles(a.get("cycles_sim")), _cycles(a.get("cycles_meas"))
            out.append(
                (
                    "crank cycles",
                    f"simulation {cs}, measurement {cm} ({a['cycles_selection']})",
                )
            )
    if c.motion is not None:
        a = c.motion.attrs
        out.append(("motion time base", str(a.get("interpolation", ""))))
        out.append(("phase alignment", str(a.get("alignment", a.get("alignment_method", "")))))
        if "time_shift_s" in a:
            out.append(
                (
                    "time shift",
                    f"{float(a['time_shift_s']) * 1e3:+.2f} ms = {float(a.get('time_shift_deg', np.nan)):+.1f}"
                    f" degree of crank angle (simulation time = measurement time − shift, "
                    f"period {float(a.get('period_s', np.nan)):.4g} s)",
                )
            )
    return out


def _metrics_rows(c: Comparison) -> list[dict[str, str]]:
    rows = []
    budget_only = {"u_num", "u_input", "u_D", "u_val", "U_val"}
    for r in c.metrics.itertuples():
        if r.metric in budget_only:  # shown in the uncertainty budget
            continue
        value, units = format_value(float(r.value), str(r.units))
        rows.append(
            {
                "quantity": str(r.quantity),
                "long_name": str(r.long_name),
                "value": value,
                "units": units,
                "definition": str(r.definition),
            }
        )
    return rows


_BUDGET_KEYS = ("value_sim", "value_meas", "E", "u_num", "u_input", "u_D", "u_val", "U_val")


def _budget(c: Comparison) -> tuple[list[dict[str, Any]], list[str]]:
    """Rows of the V&V 20 budget (every compared scalar) and the sources of each uncertainty."""
    import jointwear.compare.verdicts as vd

    m = c.metrics
    budget, sources = [], []
    vv = {
        str(r.key): (str(r.quantity), str(r.state))
        for r in c.decisions.itertuples()
        if r.basis == "V&V 20"
    }
    for q in [q for q in dict.fromkeys(m.quantity) if str(q) in vv]:
        label, state = vv[str(q)]
        sub = m[m.quantity == q].set_index("metric")
        units = str(sub.loc["value_sim", "units"])
        cells = []
        for key in _BUDGET_KEYS:
            if key not in sub.index or not np.isfinite(float(sub.loc[key, "value"])):
                cells.append("not assessed" if key.startswith("u_") else "–")
                continue
            v, u = format_value(float(sub.loc[key, "value"]), units, digits=3)
            cells.append(f"{v} {u}".strip())
        budget.append(
            {"quantity": label, "cells": cells, "state": state, "label": vd.LABELS[state]}
        )
        for key in ("u_num", "u_input", "u_D"):
            if key in sub.index:
                sources.append(
                    {"quantity": label, "component": key, "basis": str(sub.loc[key, "basis"])}
                )
    return budget, sources


def _uncertainty_sources(crit: Criteria) -> list[tuple[str, str]]:
    def stated(name: str) -> str:
        v = getattr(crit, name)
        return "not stated" if v is None else f"user-stated {v:.3g}·|S|"

    return [
        (
            "u_D (measurement)",
            "the measurement's stated standard uncertainty (<name>_u): at the location of the "
            "maximum for the maximum wear depth; its surface integral for the worn volume (fully "
            "correlated, conservative); √2·RMS for the cylindricity (peak-to-valley of two "
            "points); its RMS for the RMS motion. None stated: not assessed.",
        ),
        (
            "u_num (numerical)",
            "the simulation's stated standard uncertainty (<name>_u), else a verification study "
            "(GCI, Roache; only for monotone convergence), else a fraction stated in the criteria "
            f"(wear: {stated('wear_u_num_rel')}; motion: {stated('motion_u_num_rel')}); "
            "otherwise not assessed.",
        ),
        (
            "u_input (model inputs)",
            "the standard deviation of the quantity over an ensemble of simulations (--ensemble), "
            "else a fraction stated in the criteria (wear: "
            f"{stated('wear_u_input_rel')}; motion: {stated('motion_u_input_rel')}); otherwise "
            "not assessed - never zero.",
        ),
    ]


def _input_records(inputs: Sequence[ReportInput]) -> tuple[list[dict[str, str]], str | None]:
    records = []
    created = []
    for item in inputs:
        rec = {
            "role": item.role,
            "path": str(item.path) if item.path is not None else "(in memory)",
            "name": f"{item.role}: {Path(item.path).name if item.path else 'in-memory data'}",
            "sha256": sha256_file(item.path)
            if item.path is not None and Path(item.path).exists()
            else "–",
            "source": "",
            "history": "",
            "command": "",
            "created": "",
        }
        if item.dataset is not None:
            ds = item.dataset
            rec["source"] = str(ds.attrs.get("source", ds.attrs.get("title", "")))
            rec["history"] = str(ds.attrs.get("history", ""))
            prov = io.parse_provenance(ds)
            rec["command"] = str(prov.get("command", ""))
            rec["created"] = str(prov.get("created", ""))
            if rec["created"]:
                created.append(rec["created"])
        records.append(rec)
    return records, (max(created) if created else None)


def _verdict(c: Comparison, counts: dict[str, int]) -> tuple[str, str]:
    """Headline of the decision card and its CSS class."""
    import jointwear.compare.verdicts as vd

    n = sum(counts.values())
    synthetic = (
        " (against SYNTHETIC measurement data)"
        if c.data_origin.get("measurement") == "synthetic"
        else ""
    )
    if n == 0:
        return "NO DECISION: nothing was compared", "undecided"
    if counts[vd.FAIL]:
        return f"NOT VALIDATED: {counts[vd.FAIL]} of {n} criteria failed{synthetic}", "fail"
    undecided = counts[vd.NOT_ASSESSED] + counts[vd.NOT_COMPARABLE]
    if undecided or c.partial:
        what = []
        if counts[vd.NOT_ASSESSED]:
            what.append(f"{counts[vd.NOT_ASSESSED]} not assessed")
        if counts[vd.NOT_COMPARABLE]:
            what.append(f"{counts[vd.NOT_COMPARABLE]} not comparable")
        if c.partial:
            what.append("parts not compared")
        return (
            f"INCOMPLETE: no criterion failed, but {', '.join(what)}{synthetic}",
            "undecided",
        )
    return f"VALIDATED: every criterion is met{synthetic}", "pass"


def _coverage(c: Comparison) -> list[str]:
    """What the wear comparison covers (the compared fraction of the simulated volume)."""
    if c.wear is None or "volume_fraction_compared" not in c.wear.attrs:
        return []
    a = c.wear.attrs
    lo, hi = (float(v) for v in np.ravel(a["z_overlap_m"]))
    zs = [float(v) for v in np.ravel(a.get("z_range_sim_m", [np.nan, np.nan]))]
    frac = float(a["volume_fraction_compared"])
    arc = float(a.get("theta_fraction_measured", 1.0))
    out = []
    if arc < 1.0:
        out.append(
            f"The measurement covers {arc:.0%} of the circumference; the rest is not compared "
            "(blank on the maps), never interpolated across."
        )
    out += [
        f"Compared axial range z = {lo * 1e3:+.2f} to {hi * 1e3:+.2f} mm of the simulated "
        f"{zs[0] * 1e3:+.2f} to {zs[1] * 1e3:+.2f} mm: {frac:.0%} of the simulated worn volume "
        "is compared (uncompared region hatched on the wear maps)."
    ]
    if not int(a.get("sim_max_inside", 1)):
        out.append(
            f"The simulated maximum ({float(a['sim_max_value_m']) * 1e6:.3g} µm at z = "
            f"{float(a['sim_max_z_m']) * 1e3:+.2f} mm) lies outside the measured range."
        )
    return out


def _sensitivity_rows(c: Comparison) -> list[dict[str, str]]:
    rows = []
    for r in c.sensitivity.itertuples():
        rows.append(
            {
                "quantity": str(r.quantity),
                "parameter": str(r.parameter),
                "S1": f"{float(r.S1):.2f}" if np.isfinite(float(r.S1)) else "–",
                "ST": f"{float(r.ST):.2f}" if np.isfinite(float(r.ST)) else "–",
                "method": str(r.method),
            }
        )
    return rows


def _context(
    c: Comparison,
    *,
    inputs: Sequence[ReportInput],
    verification: Sequence[xr.Dataset],
    missing: Sequence[str],
    notes: Sequence[str],
    title: str,
    command: str | None,
    parameters: dict[str, Any] | None,
) -> dict[str, Any]:
    import jointwear.compare.verdicts as vd
    from jointwear.reports import figures

    n = len(c.decisions)
    counts = vd.counts(c.states)
    n_pass = counts[vd.PASS]
    # the comparison's own notes ("motion not compared: ...") unless the caller already said why
    covered = {m.split(":", 1)[0].split()[0].lower() for m in missing if m.strip()}
    gaps = list(c.partial)
    missing = [*missing, *(n for n in gaps if n.split()[0].lower() not in covered)]
    notes = [*notes, *(n for n in c.notes if n not in gaps)]
    verdict, verdict_class = _verdict(c, counts)
    origin = dict(c.data_origin)
    ctx: dict[str, Any] = {
        "version": __version__,
        "title": title,
        "css": _template("report.css"),
        "passed": c.passed,
        "card_class": verdict_class,
        "verdict": verdict,
        "summary": c.summary(),
        "n_passed": n_pass,
        "n_decisions": n,
        "failed": list(dict.fromkeys(c.failed())),
        "undecided": [
            (vd.LABELS[st].lower(), list(dict.fromkeys(c.quantities(st))))
            for st in (vd.NOT_ASSESSED, vd.NOT_COMPARABLE)
            if c.quantities(st)
        ],
        "decisions": [
            {**r._asdict(), "label": vd.LABELS[r.state], "cls": r.state.replace("_", "-")}
            for r in c.decisions.itertuples(index=False)
        ],
        "origin_sim": origin.get("simulation", "not stated"),
        "origin_meas": origin.get("measurement", "not stated"),
        "synthetic": "synthetic" in origin.values(),
        "coverage": _coverage(c),
        "missing": missing,
        "notes": list(notes),
        "metrics": _metrics_rows(c),
        "alignment": _alignment(c),
        "k": f"{c.criteria.k:g}",
        "uncertainty_sources": _uncertainty_sources(c.criteria),
        "sensitivity": _sensitivity_rows(c),
    }
    parts = [p for p, d in (("wear maps", c.wear), ("motion", c.motion)) if d is not None]
    ctx["subtitle"] = (
        f"Simulation ({ctx['origin_sim']}) against measurement ({ctx['origin_meas']}): "
        + (" and ".join(parts) if parts else "nothing compared")
        + f". {c.summary()}."
    )
    ctx["toc"] = [
        ("decision", "Decision"),
        ("metrics", "Metrics"),
        ("alignment", "Alignment"),
        ("wear", "Wear maps"),
        ("motion", "Motion"),
        ("uncertainty", "Uncertainty"),
        ("verification", "Verification"),
        ("provenance", "Provenance"),
    ]
    if c.wear is not None:
        fig = figures.wear_maps_figure(c.wear)
        ctx["wear_png"] = figures.png_data_uri(fig, "wear-maps")
        ctx["polar_svg"] = figures.svg_markup(figures.polar_layers_figure(c.wear), "polar-layers")
        a = c.wear.attrs
        ctx["wear_caption"] = (
            f"{c.wear.sizes['z']} layers × {c.wear.sizes['theta']} angles, canonical angle "
            f"convention; simulation after {_cycles(a.get('cycles_sim'))} cycles, "
            f"measurement after {_cycles(a.get('cycles_meas'))} cycles"
        )
    else:
        ctx["wear_png"] = None
        ctx["wear_missing"] = next(
            (m for m in missing if "wear" in m.lower()),
            "Wear maps were not compared: no simulated and measured wear map were given.",
        )
    if c.motion is not None:
        ctx["motion_svg"] = figures.svg_markup(
            figures.motion_figure(c.motion, k=c.criteria.k), "motion"
        )
        has_u = any(str(v).endswith("_meas_u") for v in c.motion.data_vars)
        ctx["motion_caption"] = (
            "Measured (red"
            + (
                f", band ± {c.criteria.k:g} standard uncertainties"
                if has_u
                else ", no uncertainty stated"
            )
            + ") and simulated (blue) motion on the measurement's time base after phase alignment."
        )
    else:
        ctx["motion_svg"] = None
        ctx["motion_missing"] = next(
            (m for m in missing if "motion" in m.lower() or "dic" in m.lower()),
            "Motion was not compared: no simulated and measured motion record were given.",
        )
    budget, sources = _budget(c)
    ctx["budget"] = budget
    ctx["budget_sources"] = sources
    vfig = figures.verification_figure(verification) if verification else None
    ctx["verification_svg"] = figures.svg_markup(vfig, "verification") if vfig is not None else None
    ctx["verification_missing"] = next(
        (m for m in missing if m.lower().startswith("verification")),
        "No verification data (convergence study) was supplied with the simulation.",
    )
    records, as_of = _input_records(inputs)
    ctx["inputs"] = records
    ctx["as_of"] = as_of
    ctx["software"] = sorted(software_versions().items())
    params = {"criteria": to_jsonable(c.criteria), **(parameters or {})}
    ctx["parameters"] = json.dumps(to_jsonable(params), indent=2, sort_keys=True)
    ctx["command"] = command if command is not None else command_line()
    return ctx


def render_html(
    comparison: Comparison,
    *,
    inputs: Sequence[ReportInput] = (),
    verification: Sequence[xr.Dataset] = (),
    missing: Sequence[str] = (),
    notes: Sequence[str] = (),
    title: str = DEFAULT_TITLE,
    command: str | None = None,
    parameters: dict[str, Any] | None = None,
) -> str:
    """The report as an HTML string (see :func:`build_report` for the parameters)."""
    import jinja2
    import matplotlib

    env = jinja2.Environment(
        loader=jinja2.FunctionLoader(_template),
        autoescape=jinja2.select_autoescape(default=True, default_for_string=True),
        undefined=jinja2.StrictUndefined,
        keep_trailing_newline=True,
    )
    with matplotlib.rc_context({"svg.hashsalt": "jointwear-report"}):
        ctx = _context(
            comparison,
            inputs=inputs,
            verification=verification,
            missing=missing,
            notes=notes,
            title=title,
            command=command,
            parameters=parameters,
        )
    for key in ("polar_svg", "motion_svg", "verification_svg"):
        if ctx.get(key):
            ctx[key] = jinja2.utils.markupsafe.Markup(ctx[key])
    return env.get_template("report.html").render(**ctx)


def build_report(
    comparison: Comparison,
    out: str | Path,
    *,
    inputs: Sequence[ReportInput] = (),
    verification: Sequence[xr.Dataset] = (),
    missing: Sequence[str] = (),
    notes: Sequence[str] = (),
    title: str = DEFAULT_TITLE,
    command: str | None = None,
    parameters: dict[str, Any] | None = None,
    pdf: str | Path | None = None,
) -> Path:
    """Write the self-contained HTML validation report (and optionally a PDF).

    Parameters
    ----------
    comparison : Comparison
        Result of :func:`jointwear.compare.compare` (or :func:`jointwear.compare.load_comparison`).
    out : path
        HTML file to write (atomically).
    inputs : sequence of ReportInput
        Input files, listed with sha256 and their own provenance.
    verification : sequence of Dataset
        Verification data (e.g. convergence studies) to plot.
    missing : sequence of str
        Parts of the chain that were not available, stated plainly in the decision card.
    notes : sequence of str
        Further statements for the reader (e.g. how the data were made), shown with the card.
    title : str
        Report title.
    command : str, optional
        Command line recorded in the provenance section (default ``sys.argv``).
    parameters : dict, optional
        Further parameters to record.
    pdf : path, optional
        Also write a PDF version (matplotlib only; for readers without a browser).

    Returns
    -------
    Path
        The HTML file.
    """
    html = render_html(
        comparison,
        inputs=inputs,
        verification=verification,
        missing=missing,
        notes=notes,
        title=title,
        command=command,
        parameters=parameters,
    )
    out = Path(out)
    with io.atomic_path(out) as tmp:
        tmp.write_text(html, encoding="utf-8")
        tmp.chmod(0o644)  # a report is meant to be shared (mkstemp creates 0600)
    if pdf is not None:
        write_pdf(
            comparison, pdf, inputs=inputs, verification=verification, missing=missing, title=title
        )
    return out


def _text_page(pdf: Any, title: str, lines: Sequence[str]) -> None:
    from matplotlib.figure import Figure

    per_page = 52
    chunks = [lines[i : i + per_page] for i in range(0, max(1, len(lines)), per_page)] or [[]]
    for k, chunk in enumerate(chunks):
        fig = Figure(figsize=(8.27, 11.69))
        fig.text(
            0.06, 0.96, title + (f" (continued {k + 1})" if k else ""), fontsize=13, weight="bold"
        )
        fig.text(0.06, 0.93, "\n".join(chunk), fontsize=7.2, va="top", family="DejaVu Sans Mono")
        pdf.savefig(fig)


def write_pdf(
    comparison: Comparison,
    path: str | Path,
    *,
    inputs: Sequence[ReportInput] = (),
    verification: Sequence[xr.Dataset] = (),
    missing: Sequence[str] = (),
    notes: Sequence[str] = (),
    title: str = DEFAULT_TITLE,
) -> Path:
    """Write the report as a PDF with matplotlib only (no browser needed). Deterministic."""
    import matplotlib
    from matplotlib.backends.backend_pdf import PdfPages

    from jointwear.reports import figures

    c = comparison
    path = Path(path)
    from textwrap import wrap

    import jointwear.compare.verdicts as vd

    verdict, _ = _verdict(c, vd.counts(c.states))
    lines = [
        verdict,
        f"data origin: simulation {c.data_origin.get('simulation', 'not stated')}, "
        f"measurement {c.data_origin.get('measurement', 'not stated')}",
        c.summary(),
        *_coverage(c),
        "",
    ]
    for r in c.decisions.itertuples():
        lines.append(f"{vd.LABELS[r.state]:<14s}  {r.quantity}")
        lines += wrap(
            f"{r.value}   [{r.criterion}; {r.basis}]",
            100,
            initial_indent=" " * 6,
            subsequent_indent=" " * 6,
        )
        if r.reason:
            lines += wrap(
                f"why: {r.reason}", 100, initial_indent=" " * 6, subsequent_indent=" " * 6
            )
    lines = [piece for line in lines for piece in (wrap(line, 110) or [""])]
    for m in [*missing, *c.notes]:
        lines += ["", f"Not covered: {m}"]
    for m in notes:
        lines += ["", f"Note: {m}"]
    metric_lines = []
    for r in c.metrics.itertuples():
        value, units = format_value(float(r.value), str(r.units))
        metric_lines.append(
            f"{str(r.quantity)[:28]:28s} {str(r.metric)[:24]:24s} {value:>12s} {units}"
        )
    prov = []
    records, _ = _input_records(inputs)
    for rec in records:
        prov += [f"{rec['role']}: {rec['path']}", f"    sha256 {rec['sha256']}"]
    prov += ["", "software:"] + [f"    {k} {v}" for k, v in sorted(software_versions().items())]
    with matplotlib.rc_context(figures._rc("pdf")), io.atomic_path(path) as tmp:
        with PdfPages(
            tmp,
            metadata={"Title": title, "Creator": f"jointwear {__version__}", "CreationDate": None},
        ) as pdf:
            _text_page(pdf, title, lines)
            _text_page(pdf, "Metrics", metric_lines)
            if c.wear is not None:
                pdf.savefig(figures.wear_maps_figure(c.wear))
                pdf.savefig(figures.polar_layers_figure(c.wear))
            if c.motion is not None:
                pdf.savefig(figures.motion_figure(c.motion, k=c.criteria.k))
            vfig = figures.verification_figure(verification) if verification else None
            if vfig is not None:
                pdf.savefig(vfig)
            _text_page(pdf, "Provenance", prov)
        tmp.chmod(0o644)
    return path


def report_from_files(
    out: str | Path,
    *,
    sim: Sequence[str | Path] = (),
    metrology: Sequence[str | Path] = (),
    dic: Sequence[str | Path] = (),
    comparison: str | Path | None = None,
    verification: Sequence[str | Path] = (),
    criteria: Criteria | None = None,
    title: str = DEFAULT_TITLE,
    pdf: str | Path | None = None,
    command: str | None = None,
    cycles: float | None = None,
    period_s: float | None = None,
    variables: Sequence[str] | None = None,
    ensemble: Sequence[str | Path] = (),
    axes: Sequence[str] | None = ("x", "y"),
) -> tuple[Path, Comparison]:
    """Build a report from files: simulation, metrology and DIC netCDF, or a saved comparison.

    Parameters
    ----------
    out : path
        HTML report to write (a ``.pdf`` name writes the PDF version only).
    sim, metrology, dic : sequence of path
        Simulated wear map / motion files, measured wear map files (``jointwear metrology``),
        measured motion files (``jointwear dic``).
    comparison : path, optional
        A file written by ``jointwear compare`` (instead of sim/metrology/dic).
    verification : sequence of path
        Verification (convergence) data files: plotted, and their GCI is the numerical
        uncertainty of the compared quantities (:mod:`jointwear.compare.verification`).
    ensemble : sequence of path
        Ensembles of simulations (``run`` dimension) whose spread is the input uncertainty.
    axes : sequence of str or None
        Motion components to compare (default in-plane x, y).
    criteria : Criteria, optional
        Validation criteria.
    title, pdf, command
        See :func:`build_report`.
    cycles, period_s : float, optional
        Passed to :func:`jointwear.compare.compare`.
    variables : sequence of str, optional
        Motion variables to compare (default: see :data:`jointwear.compare.MOTION_VARIABLES`).

    Returns
    -------
    (Path, Comparison)
    """
    from jointwear.compare import as_ensemble, load_comparison

    inputs: list[ReportInput] = []
    missing: list[str] = []
    vers = [io.load(p, validate=False) for p in verification]
    ens_ds = [io.load(p) for p in ensemble]
    if comparison is not None:
        if sim or metrology or dic or ensemble:
            raise BadInputError(
                "give either --comparison or --sim/--metrology/--dic/--ensemble, not both"
            )
        ds = io.load(comparison)
        result = load_comparison(ds)
        inputs.append(ReportInput("comparison", Path(comparison), ds))
    else:
        if not sim:
            raise BadInputError("no simulation given: pass --sim FILE.nc (wear map and/or motion)")
        if not metrology and not dic:
            raise BadInputError(
                "no measurement given: pass --metrology FILE.nc (wear map) and/or --dic FILE.nc"
            )
        sims = [io.load(p) for p in sim]
        metros = [io.load(p) for p in metrology]
        dics = [io.load(p) for p in dic]
        inputs += [ReportInput("simulation", Path(p), d) for p, d in zip(sim, sims, strict=True)]
        inputs += [
            ReportInput("metrology", Path(p), d) for p, d in zip(metrology, metros, strict=True)
        ]
        inputs += [ReportInput("DIC", Path(p), d) for p, d in zip(dic, dics, strict=True)]
        if not metrology:
            missing.append("wear maps: no metrology file was given (--metrology)")
        if not dic:
            missing.append("motion: no DIC file was given (--dic)")
        result = compare(
            sims,
            [*metros, *dics],
            criteria=criteria,
            cycles=cycles,
            period_s=period_s,
            variables=variables,
            axes=axes,
            ensemble=as_ensemble(ens_ds, [Path(p).name for p in ensemble]) if ens_ds else None,
            verification=vers or None,
        )
        inputs += [
            ReportInput("ensemble", Path(p), d) for p, d in zip(ensemble, ens_ds, strict=True)
        ]
    inputs += [
        ReportInput("verification", Path(p), d) for p, d in zip(verification, vers, strict=True)
    ]
    if Path(out).suffix.lower() == ".pdf":  # PDF only (no browser at hand)
        path = write_pdf(
            result, out, inputs=inputs, verification=vers, missing=missing, title=title
        )
        return path, result
    path = build_report(
        result,
        out,
        inputs=inputs,
        verification=vers,
        missing=missing,
        title=title,
        command=command,
        pdf=pdf,
    )
    return path, result
