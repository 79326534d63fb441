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
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

import xarray as xr

from jointwear import io
from jointwear._version import __version__
from jointwear.compare import DEFAULT_AXES, Comparison, Criteria, compare
from jointwear.errors import BadInputError
from jointwear.params import to_jsonable
from jointwear.provenance import command_line, sha256_file, software_versions
from jointwear.reports._sections import (
    _alignment,
    _budget,
    _coverage,
    _cycles,
    _metrics_rows,
    _sensitivity_rows,
    _uncertainty_sources,
    _verdict,
    format_value,
)
from jointwear.reports.power import power_paragraph

__all__ = [
    "ReportInput",
    "build_report",
    "render_html",
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


@dataclass(frozen=True)
class _Page:
    """What a report shows beside the comparison (see :func:`build_report`)."""

    inputs: Sequence[ReportInput] = ()
    verification: Sequence[xr.Dataset] = ()
    missing: Sequence[str] = ()
    notes: Sequence[str] = ()
    title: str = DEFAULT_TITLE
    command: str | None = None
    parameters: dict[str, Any] | None = None


def _template(name: str) -> str:
    return (resources.files("jointwear.reports") / "templates" / name).read_text(encoding="utf-8")


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


def _context(c: Comparison, page: _Page) -> dict[str, Any]:
    import jointwear.compare.verdicts as vd
    from jointwear.reports import figures

    missing, notes, verification = page.missing, page.notes, page.verification

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
        "title": page.title,
        "css": _template("report.css"),
        "passed": c.passed,
        "card_class": verdict_class,
        "verdict": verdict,
        "summary": c.summary(),
        "resolution": c.resolution(),
        "power": power_paragraph(c, notes),
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
    records, as_of = _input_records(page.inputs)
    ctx["inputs"] = records
    ctx["as_of"] = as_of
    ctx["software"] = sorted(software_versions().items())
    params = {"criteria": to_jsonable(c.criteria), **(page.parameters or {})}
    ctx["parameters"] = json.dumps(to_jsonable(params), indent=2, sort_keys=True)
    ctx["command"] = page.command if page.command is not None else command_line()
    return ctx


def render_html(comparison: Comparison, **page: Any) -> str:
    """The report as an HTML string.

    ``page``: the keywords of :func:`build_report` but ``pdf`` (``inputs``, ``verification``,
    ``missing``, ``notes``, ``title``, ``command``, ``parameters``).
    """
    return _render(comparison, _Page(**page))


def _render(comparison: Comparison, page: _Page) -> str:
    import jinja2
    import matplotlib

    env = jinja2.Environment(
        loader=jinja2.FunctionLoader(_template),
        autoescape=jinja2.select_autoescape(default=True, default_for_string=True),
        undefined=jinja2.StrictUndefined,
        keep_trailing_newline=True,
    )
    with matplotlib.rc_context({"svg.hashsalt": "jointwear-report"}):
        ctx = _context(comparison, page)
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

    Examples
    --------
    The self-contained HTML report of a simulated wear map compared with itself, labelled as
    synthetic measurement data:

    >>> import tempfile
    >>> from pathlib import Path
    >>> from jointwear.compare import compare
    >>> from jointwear.reports import build_report
    >>> from jointwear.sim import BearingGrid, WearSettings, WinklerContact, simulate_wear
    >>> run = {"contact": WinklerContact(BearingGrid(4, 36)), "snapshots": [1000, 2000]}
    >>> sim = simulate_wear(cycles=2000, settings=WearSettings(scheme="fixed", dn=500), **run)
    >>> meas = sim.isel(cycles=-1, drop=True)[["wear_depth"]]
    >>> comparison = compare(sim, meas.assign_attrs(data_origin="synthetic", cycles=2000))
    >>> page = build_report(comparison, Path(tempfile.mkdtemp()) / "report.html")
    >>> page.name, "maximum wear depth" in page.read_text(encoding="utf-8")
    ('report.html', True)
    """
    page = _Page(inputs, verification, missing, notes, title, command, parameters)
    return _write(comparison, Path(out), page, pdf)


def _write(comparison: Comparison, out: Path, page: _Page, pdf: str | Path | None) -> Path:
    """Write the HTML report to ``out`` (atomically, readable by all) and the PDF to ``pdf``."""
    html = _render(comparison, page)
    with io.atomic_path(out) as tmp:
        tmp.write_text(html, encoding="utf-8")
        tmp.chmod(0o644)  # a report is meant to be shared (mkstemp creates 0600)
    if pdf is not None:
        from jointwear.reports.pdf import pdf_of_page

        pdf_of_page(comparison, pdf, page)
    return out


def report_from_files(
    out: str | Path,
    *,
    sim: Sequence[str | Path] = (),
    metrology: Sequence[str | Path] = (),
    dic: Sequence[str | Path] = (),
    comparison: str | Path | None = None,
    verification: Sequence[str | Path] = (),
    criteria: Criteria | str | Path | None = None,
    title: str | None = DEFAULT_TITLE,
    pdf: str | Path | None = None,
    command: str | None = None,
    cycles: float | None = None,
    period_s: float | None = None,
    variables: Sequence[str] | None = None,
    ensemble: Sequence[str | Path] = (),
    axes: Sequence[str] | None = DEFAULT_AXES,
    warn: Callable[[str], None] | None = None,
    reported: Sequence[str | Path] = (),
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
    reported : sequence of path
        Reported measurements (``jointwear import reported``), judged beside or instead of the
        metrology and DIC files (:mod:`jointwear.compare.reported`).
    warn : callable, optional
        Receives the warning text for a file from another tool (the CLI prints it on stderr);
        by default it is a :class:`UserWarning` (see
        :func:`jointwear.external.load_for_comparison`).
    criteria : Criteria or path, optional
        Validation criteria, or a TOML file of them (:func:`jointwear.compare.load_criteria`).
    title, pdf, command
        See :func:`build_report` (``title=None``: the default title).
    cycles, period_s : float, optional
        Passed to :func:`jointwear.compare.compare`.
    variables : sequence of str, optional
        Motion variables to compare (default: see :data:`jointwear.compare.MOTION_VARIABLES`).

    Returns
    -------
    (Path, Comparison)
    """
    from jointwear.compare import as_ensemble, load_comparison, load_criteria

    io.check_writable(out, what="report")
    if not isinstance(criteria, Criteria):
        criteria = load_criteria(criteria)
    title = title or DEFAULT_TITLE
    inputs: list[ReportInput] = []
    missing: list[str] = []
    vers = [io.load(p, validate=False) for p in verification]
    ens_ds = [io.load(p) for p in ensemble]
    if comparison is not None:
        if sim or metrology or dic or ensemble or reported:
            raise BadInputError(
                "give either --comparison or --sim/--metrology/--dic/--reported/--ensemble, "
                "not both"
            )
        ds = io.load(comparison)
        result = load_comparison(ds)
        inputs.append(ReportInput("comparison", Path(comparison), ds))
    else:
        if not sim:
            raise BadInputError("no simulation given: pass --sim FILE.nc (wear map and/or motion)")
        if not metrology and not dic and not reported:
            raise BadInputError(
                "no measurement given: pass --metrology FILE.nc (wear map), --dic FILE.nc "
                "and/or --reported FILE.nc (reported values)"
            )
        from jointwear.external import load_for_comparison

        sims = [load_for_comparison(p, role="simulated", warn=warn) for p in sim]
        metros = [load_for_comparison(p, role="measured", warn=warn) for p in metrology]
        dics = [load_for_comparison(p, role="measured", warn=warn) for p in dic]
        reps = [io.load(p) for p in reported]
        inputs += [ReportInput("simulation", Path(p), d) for p, d in zip(sim, sims, strict=True)]
        inputs += [
            ReportInput("metrology", Path(p), d) for p, d in zip(metrology, metros, strict=True)
        ]
        inputs += [ReportInput("DIC", Path(p), d) for p, d in zip(dic, dics, strict=True)]
        inputs += [ReportInput("reported", Path(p), d) for p, d in zip(reported, reps, strict=True)]
        if not metrology:
            missing.append("wear maps: no metrology file was given (--metrology)")
        if not dic:
            missing.append("motion: no DIC file was given (--dic)")
        result = compare(
            sims,
            [*metros, *dics, *reps],
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
    page = _Page(inputs, vers, missing, title=title, command=command)
    if Path(out).suffix.lower() == ".pdf":  # PDF only (no browser at hand)
        from jointwear.reports.pdf import pdf_of_page

        return pdf_of_page(result, out, page), result
    return _write(result, Path(out), page, pdf), result
