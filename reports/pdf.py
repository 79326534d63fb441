"""The report as a PDF made with matplotlib only (for readers without a browser)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

from jointwear import io
from jointwear._version import __version__
from jointwear.compare import Comparison
from jointwear.provenance import software_versions
from jointwear.reports._sections import _coverage, _verdict, format_value
from jointwear.reports.builder import _input_records, _Page

__all__ = ["write_pdf"]


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


def write_pdf(comparison: Comparison, path: str | Path, **page: Any) -> Path:
    """Write the report as a PDF with matplotlib only (no browser needed). Deterministic.

    ``page``: the keywords of :func:`~jointwear.reports.build_report` but ``pdf``
    (``inputs``, ``verification``, ``missing``, ``notes``, ``title``; the PDF does not show
    ``command`` and ``parameters``).
    """
    return pdf_of_page(comparison, path, _Page(**page))


def pdf_of_page(comparison: Comparison, path: str | Path, page: _Page) -> Path:
    """:func:`write_pdf` of a report's page (what it shows beside the comparison)."""
    import matplotlib
    from matplotlib.backends.backend_pdf import PdfPages

    from jointwear.reports import figures

    inputs, verification, title = page.inputs, page.verification, page.title

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
    for m in [*page.missing, *c.notes]:
        lines += ["", f"Not covered: {m}"]
    for m in page.notes:
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
