"""The HTML report: structure (parsed with html.parser), self-containment, determinism, CLI."""

from __future__ import annotations

from html.parser import HTMLParser

import _jw_synth as syn
import pytest

from jointwear.cli import main
from jointwear.compare import Criteria
from jointwear.reports import report_from_files

#: the old strict coverage rule, so that a narrow scan leaves criteria not comparable
STRICT = Criteria(strict_coverage=True)

EXPECTED_SECTIONS = [
    "Decision",
    "Metrics",
    "Alignment",
    "Wear maps",
    "Motion",
    "Uncertainty budget",
    "Verification",
    "Provenance",
]


class _Page(HTMLParser):
    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.stack: list[str] = []
        self.h2: list[str] = []
        self.tags: dict[str, int] = {}
        self.urls: list[str] = []
        self.cells: list[tuple[str, str]] = []  # (class, text) of <td>
        self._cell: list[str] | None = None
        self._cls = ""
        self._h2: list[str] | None = None

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        self.tags[tag] = self.tags.get(tag, 0) + 1
        for key, value in a.items():
            if value is not None and (key.endswith("href") or key == "src"):
                self.urls.append(value)
        if tag == "h2":
            self._h2 = []
        if tag == "td":
            self._cell, self._cls = [], a.get("class") or ""

    def handle_endtag(self, tag):
        if tag == "h2" and self._h2 is not None:
            self.h2.append("".join(self._h2).strip())
            self._h2 = None
        if tag == "td" and self._cell is not None:
            self.cells.append((self._cls, "".join(self._cell).strip()))
            self._cell = None

    def handle_data(self, data):
        if self._h2 is not None:
            self._h2.append(data)
        if self._cell is not None:
            self._cell.append(data)


def parse(path) -> _Page:
    page = _Page()
    page.feed(path.read_text(encoding="utf-8"))
    return page


@pytest.fixture(scope="module")
def built(report_of_all, tmp_path_factory):
    out = tmp_path_factory.mktemp("report") / "report.html"
    return report_of_all(out, "jointwear report (test)")


def test_report_structure(built):
    path, result = built
    page = parse(path)
    assert page.h2 == EXPECTED_SECTIONS
    # decision card: one PASS/FAIL cell per decision, matching the comparison
    from jointwear.compare.verdicts import LABELS

    verdicts = [
        text
        for cls, text in page.cells
        if cls in ("pass", "fail", "not-assessed", "not-comparable") and text in LABELS.values()
    ]
    assert verdicts[: len(result.decisions)] == [LABELS[s] for s in result.decisions.state]
    # all four states occur in this comparison (no uncertainty stated for the model, a scan
    # narrower than the simulated worn zone with the strict coverage rule, a rotated and a
    # scaled measurement)
    assert set(result.decisions.state) == {"pass", "fail", "not_assessed", "not_comparable"}
    # the rotated measurement: angle error of the maximum is -40 degree, shown in the card
    assert any("-40.0 degree" in text for _, text in page.cells)
    # figures inline: the wear maps as PNG, polar plots and motion as SVG
    assert page.tags.get("svg", 0) >= 2 and page.tags.get("img", 0) == 1
    assert page.tags.get("script", 0) == 0
    for url in page.urls:  # nothing fetched from elsewhere
        assert url.startswith(("#", "data:image/png;base64,")), url
    html = path.read_text(encoding="utf-8")
    assert "<style>" in html and "<metadata>" not in html
    assert "jointwear report (test)" in html
    # the power of this comparison: each decided criterion's resolution, and what a pass means
    decided = result.decisions[result.decisions.state.isin(["pass", "fail"])]
    power = html.split("Power of this comparison.</strong>")[1].split("</p>")[0]
    for r in decided[decided.resolution != ""].itertuples():
        assert r.quantity in power
    assert "passes whether the model is right or not" in power


def test_report_lists_inputs_with_sha256(built, report_files):
    from jointwear.provenance import sha256_file

    html = built[0].read_text(encoding="utf-8")
    for p in report_files.values():
        assert sha256_file(p) in html
        assert str(p) in html


def test_report_is_byte_identical(report_of_all, built, tmp_path):
    again, _ = report_of_all(tmp_path / "again.html", "jointwear report (test)")
    assert again.read_bytes() == built[0].read_bytes()


def test_report_states_missing_parts(report_files, tmp_path):
    f = report_files
    path, result = report_from_files(
        tmp_path / "wear-only.html", sim=[f["sim_wear"]], metrology=[f["metrology"]], command="t"
    )
    assert result.motion is None
    html = path.read_text(encoding="utf-8")
    assert "Not covered:</strong> motion: no DIC file was given (--dic)" in html
    page = parse(path)
    assert page.h2 == EXPECTED_SECTIONS


def test_report_cli_html_pdf_and_comparison(report_files, tmp_path, capsys):
    f = report_files
    out = tmp_path / "r.html"
    pdf = tmp_path / "r.pdf"
    argv = ["report", "--sim", str(f["sim_wear"]), "--sim", str(f["sim_motion"])]
    argv += ["--metrology", str(f["metrology"]), "--dic", str(f["dic"])]
    # a failed criterion exits 1 - after writing the report and the PDF
    assert main([*argv, "--out", str(out), "--pdf", str(pdf)]) == 1
    assert f"report: {out}" in capsys.readouterr().out
    assert pdf.read_bytes().startswith(b"%PDF") and pdf.stat().st_size > 10_000
    # from a saved comparison
    metrics = tmp_path / "m.nc"
    assert main(["compare", str(f["sim_wear"]), str(f["metrology"]), "-o", str(metrics)]) == 1
    out2 = tmp_path / "r2.html"
    assert main(["report", "--comparison", str(metrics), "--out", str(out2)]) == 1
    assert parse(out2).h2 == EXPECTED_SECTIONS
    # a .pdf name writes the PDF version only
    out3 = tmp_path / "only.pdf"
    assert main(["report", "--comparison", str(metrics), "--out", str(out3)]) == 1
    assert out3.read_bytes().startswith(b"%PDF")
    # usage errors
    assert main(["report", "--out", str(out2), "--overwrite"]) == 3
    assert "no simulation given" in capsys.readouterr().err


def test_verification_figures_and_pdf_determinism(built, tmp_path):
    import numpy as np
    import xarray as xr

    from jointwear.reports import build_report, render_html, write_pdf

    _, result = built
    # a convergence study: error ~ h^2 over four grid sizes
    h = np.array([4.0, 2.0, 1.0, 0.5])
    conv = xr.Dataset(
        {
            "wear_error": (
                "grid_step",
                1e-6 * h**2,
                {"units": "m", "long_name": "error of max depth"},
            )
        },
        coords={"grid_step": ("grid_step", h, {"units": "degree"})},
    )
    page = _Page()
    page.feed(render_html(result, verification=[conv], command="t"))
    assert page.h2 == EXPECTED_SECTIONS
    # polar plots, motion and the verification figure
    assert page.tags.get("svg", 0) == 3
    a = write_pdf(result, tmp_path / "a.pdf", verification=[conv], notes=["made by a test"])
    b = write_pdf(result, tmp_path / "b.pdf", verification=[conv], notes=["made by a test"])
    assert a.read_bytes() == b.read_bytes() and a.read_bytes().startswith(b"%PDF")
    # build_report's PDF is write_pdf's with the same page, notes included (they were dropped)
    plain = write_pdf(result, tmp_path / "plain.pdf", verification=[conv])
    assert plain.read_bytes() != a.read_bytes()
    build_report(
        result,
        tmp_path / "r.html",
        verification=[conv],
        notes=["made by a test"],
        pdf=tmp_path / "r.pdf",
    )
    assert (tmp_path / "r.pdf").read_bytes() == a.read_bytes()


def test_generated_scan_stays_synthetic_into_the_decision_card(tmp_path):
    """Instrument files from the generator -> importer -> wear map -> compare -> card."""
    import re

    from jointwear.compare import compare
    from jointwear.datasets import instruments
    from jointwear.metrology import wear_map
    from jointwear.metrology.readers import read_talyrond
    from jointwear.reports import render_html

    conv = ("+y", "counterclockwise")
    kw = {"n_layers": 13, "n_points": 720, "convention": conv, "seed": 5}
    instruments.write(instruments.generate(**kw), tmp_path / "worn", layout="folder")
    instruments.write(
        instruments.generate(wear=None, noise_seed=9, **kw), tmp_path / "before", layout="folder"
    )
    first = next((tmp_path / "worn").glob("*.txt")).read_text(encoding="utf-8")
    assert "Data origin: synthetic" in first
    worn = read_talyrond(tmp_path / "worn", convention=conv)
    assert worn.attrs["data_origin"] == "synthetic"
    assert not worn.attrs["source"].startswith("measurement")
    wm = wear_map(worn, read_talyrond(tmp_path / "before", convention=conv))
    assert wm.attrs["data_origin"] == "synthetic"
    wm.attrs["cycles"] = 4e5
    sim = syn.sim_wear()
    sim.attrs["data_origin"] = "simulated"
    c = compare(sim, wm)
    html = render_html(c, command="t")
    card = html[html.index('id="decision"') : html.index('id="metrics"')]
    assert re.search(r"measurement: <strong[^>]*>synthetic</strong>", card)
    assert "Synthetic data:" in card and "SYNTHETIC measurement data" in card
    # and an export without the line is a measurement
    plain = tmp_path / "plain"
    instruments.write(instruments.generate(**kw), plain, layout="folder", header=False)
    assert read_talyrond(plain, convention=conv).attrs["data_origin"] == "measured"


def test_a_sim_verify_study_is_plotted(built):
    from test_compare_study import study

    from jointwear.reports import render_html

    _, result = built
    page = _Page()
    page.feed(render_html(result, verification=[study()], command="t"))
    # polar plots, motion and the study's level means against ΔN
    assert page.tags.get("svg", 0) == 3
