"""The power figure and table of docs/compare-report.md, from benchmarks/results/validation_power.json.

Usage: ``python docs/scripts/power_figures.py`` writes ``docs/img/validation-power.png``
(detection probability against the size of the wear-coefficient error per criterion on the
reference truth, and every other candidate's detection by criterion) and rewrites the table
between ``<!-- power-table begin -->`` and ``<!-- power-table end -->`` in docs/compare-report.md,
each figure with its marker (``docs/scripts/quoted_figures.py`` checks them). From
``validation_power_calibrated.json`` (when it exists) it draws
``docs/img/validation-power-calibrated.png`` and writes the with/without-calibration table
between ``<!-- power-calibrated-table begin -->`` and ``<!-- power-calibrated-table end -->``.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
RESULTS = ROOT / "benchmarks" / "results" / "validation_power.json"
DOC = ROOT / "docs" / "compare-report.md"
IMG = ROOT / "docs" / "img" / "validation-power.png"
CAL_RESULTS = ROOT / "benchmarks" / "results" / "validation_power_calibrated.json"
CAL_IMG = ROOT / "docs" / "img" / "validation-power-calibrated.png"
#: with/without-calibration table columns: header -> criterion in the JSON
CAL_COLUMNS = {
    "max depth": "maximum wear depth",
    "volume": "worn volume",
    "cylindricity": "cylindricity of the wear (LSCY)",
    "field": "wear field",
    "axial distribution": "axial distribution of the wear",
}

#: table columns: header -> criterion name in the JSON (None: any criterion)
COLUMNS = {
    "any": None,
    "max depth": "maximum wear depth",
    "volume": "worn volume",
    "cylindricity": "cylindricity of the wear (LSCY)",
    "shape": "wear map shape",
    "angle": "angle of maximum wear",
    "field": "wear field",
    "axial distribution": "axial distribution of the wear",
}
KW = {"kw x 0.7": 0.7, "kw x 0.85": 0.85, "kw x 1.2": 1.2, "kw x 1.35": 1.35, "kw x 1.5": 1.5,
      "kw x 2": 2.0}  # fmt: skip


def _rate(entry: dict, criterion: str | None) -> float:
    return entry["any_fail"] if criterion is None else entry["fail_rate"].get(criterion, 0.0)


def _cell(truth: str, who: str, header: str, value: float) -> str:
    path = f"figures/truths/{truth}/{who}/" + (
        "any_fail" if COLUMNS[header] is None else f"fail_rate/{COLUMNS[header]}"
    )
    return f"{value * 100:.0f} <!-- fig: validation_power.json:{path} *100 -->"


def table(fig: dict) -> str:
    """The markdown table of fail rates [%] per truth, candidate and criterion."""
    lines = [
        "| truth | candidate | " + " | ".join(COLUMNS) + " |",
        "|---|---|" + "---|" * len(COLUMNS),
    ]
    for truth, res in fig["truths"].items():
        n = res["right"]["replicates"]
        rows = [("right model", "right", res["right"])]
        rows += [(w, f"wrong/{w}", e) for w, e in res["wrong"].items()]
        for name, who, entry in rows:
            cells = [_cell(truth, who, h, _rate(entry, c)) for h, c in COLUMNS.items()]
            lines.append(f"| {truth} ({n}) | {name} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def figure(fig: dict) -> None:
    """Detection probability against the kw error (reference truth) and by candidate."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    crit = {h: c for h, c in COLUMNS.items() if h not in ("angle",)}
    f, (ax, bx) = plt.subplots(1, 2, figsize=(11, 4.2), gridspec_kw={"width_ratios": [1, 1.3]})
    ref = fig["truths"].get("default")
    if ref is not None:
        for i, (header, c) in enumerate(crit.items()):
            pts = [(1.0, _rate(ref["right"], c))]
            pts += [(k, _rate(ref["wrong"][w], c)) for w, k in KW.items() if w in ref["wrong"]]
            pts.sort()
            off = 0.015 * (i - len(crit) / 2)  # drawn apart so that equal curves all show
            ax.plot([p[0] for p in pts], [p[1] + off for p in pts], marker="o", label=header,
                    lw=2.5 if c is None else 1.2, ms=4)  # fmt: skip
        ax.axvline(1.0, color="0.6", lw=0.8)
        ax.set_xlabel("wear coefficient of the model / the truth's (1: the right model)")
        ax.set_ylabel("share of replicates failed (curves offset ±0.05 to show)")
        ax.set_title("reference truth: detection of a kw error", fontsize=10)
        ax.set_ylim(-0.08, 1.08)
        ax.legend(fontsize=7, loc="center", bbox_to_anchor=(0.6, 0.5))
    labels, any_rate, field_rate, axial_rate = [], [], [], []
    for truth, res in fig["truths"].items():
        short = {"default": "ref", "tilt stiffness 1000": "tilt", "clearance 0.7 mm": "cl 0.7"}
        items = [("right", res["right"])] + [
            (w, e) for w, e in res["wrong"].items() if not (truth == "default" and w in KW)
        ]
        for w, e in items:
            labels.append(f"{short.get(truth, truth)}: {w}")
            any_rate.append(_rate(e, None))
            field_rate.append(_rate(e, "wear field"))
            axial_rate.append(_rate(e, "axial distribution of the wear"))
    y = range(len(labels))
    bx.barh([i - 0.27 for i in y], any_rate, height=0.27, label="any criterion")
    bx.barh(list(y), field_rate, height=0.27, label="wear field")
    bx.barh([i + 0.27 for i in y], axial_rate, height=0.27, label="axial distribution")
    bx.set_yticks(list(y), labels, fontsize=7)
    bx.invert_yaxis()
    bx.set_xlim(0, 1.0)
    bx.set_xlabel("share of replicates failed (right: the false-fail rate)")
    bx.set_title("every other candidate", fontsize=10)
    bx.legend(fontsize=7, loc="lower right")
    f.tight_layout()
    f.savefig(IMG, dpi=110)
    print(IMG)


def _cal_cell(prefix: str, path: str, value: float | None, factor: float = 100) -> str:
    if value is None:
        return "—"
    fmt = f"{value * factor:.0f}" if factor == 100 else f"{value:.2f}"
    scale = " *100" if factor == 100 else ""
    return f"{fmt} <!-- fig: validation_power_calibrated.json:{prefix}/{path}{scale} -->"


def _cal_rows(fig: dict) -> list[tuple[str, str, str, dict]]:
    """(truth, candidate label, JSON path of its entry, entry): the candidates, then the prior
    variants."""
    rows = []
    for truth, res in fig["truths"].items():
        for cand, e in sorted(res["candidates"].items(), key=lambda t: (t[0] != "right", t[0])):
            label = "right model" if cand == "right" else cand
            rows.append((truth, label, f"figures/truths/{truth}/candidates/{cand}", e))
    for variant, truths in fig.get("prior_variants", {}).items():
        for truth, cands in truths.items():
            for cand, e in cands.items():
                path = f"figures/prior_variants/{variant}/{truth}/{cand}"
                rows.append((truth, f"{cand}, {variant}", path, e))
    return rows


def cal_table(fig: dict) -> str:
    """Per candidate: fail rates [%] without → with calibration, the refused-at-calibration and
    detection rates, U_val/|D| of the maximum depth both ways, kw's posterior mean / truth."""
    heads = ["truth", "candidate", "any: without", "with", "refused at calibration",
             "not decided", "detected with"]  # fmt: skip
    heads += [f"{h}: without \\| with" for h in CAL_COLUMNS]
    heads += ["U_val/D max depth: without \\| with", "posterior kw / truth (median)"]
    lines = ["| " + " | ".join(heads) + " |", "|" + "---|" * len(heads)]
    for truth, label, pre, e in _cal_rows(fig):
        w, wo = e["with_calibration"], e["without_calibration"]
        cells = [truth, f"{label} ({w['replicates']})"]
        cells.append(_cal_cell(pre, "without_calibration/any_fail", wo["any_fail"]))
        for key in ("any_fail", "refused_at_calibration", "not_decided", "detected"):
            cells.append(_cal_cell(pre, f"with_calibration/{key}", w[key]))
        for c in CAL_COLUMNS.values():
            a = _cal_cell(pre, f"without_calibration/fail_rate/{c}", wo["fail_rate"].get(c))
            b = _cal_cell(pre, f"with_calibration/fail_rate/{c}",
                          w["fail_rate"].get(c) if w["validated"] else None)  # fmt: skip
            cells.append(f"{a} \\| {b}")
        key = "u_val_over_d_max_depth_median"
        a = _cal_cell(pre, f"without_calibration/{key}", wo.get(key), 1)
        b = _cal_cell(pre, f"with_calibration/{key}", w.get(key), 1)
        cells.append(f"{a} \\| {b}")
        kw = w.get("kw_over_truth_median")
        cells.append(_cal_cell(pre, "with_calibration/kw_over_truth_median", kw, 1))
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def cal_figure(fig: dict) -> None:
    """Per candidate: detection without and with calibration (failed, refused at calibration),
    and the wear field's and axial distribution's fail rates both ways."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    labels, rows = [], []
    for truth, label, _pre, e in _cal_rows(fig):
        labels.append(f"{truth}: {label} ({e['with_calibration']['replicates']})")
        rows.append((e["without_calibration"], e["with_calibration"]))
    f, axes = plt.subplots(1, 3, figsize=(12, 0.45 * len(labels) + 1.6), sharey=True)
    y = list(range(len(labels)))
    h = 0.38
    ax = axes[0]
    ax.barh([i - h / 2 for i in y], [wo["any_fail"] for wo, _ in rows], h, label="without")
    ax.barh([i + h / 2 for i in y], [w["any_fail"] for _, w in rows], h, label="with: failed")
    ax.barh([i + h / 2 for i in y], [w["refused_at_calibration"] for _, w in rows], h,
            left=[w["any_fail"] for _, w in rows], label="with: refused at calibration",
            hatch="//", color="tab:red", alpha=0.6)  # fmt: skip
    ax.set_title("any criterion (detection)", fontsize=10)
    for ax, crit in zip(axes[1:], ("wear field", "axial distribution of the wear"), strict=True):
        ax.barh([i - h / 2 for i in y], [wo["fail_rate"].get(crit, 0) for wo, _ in rows], h,
                label="without")  # fmt: skip
        ax.barh([i + h / 2 for i in y], [w["fail_rate"].get(crit, 0) for _, w in rows], h,
                label="with calibration")  # fmt: skip
        ax.set_title(crit, fontsize=10)
    for ax in axes:
        ax.set_xlim(0, 1.0)
        ax.set_xlabel("share of replicates")
        ax.legend(fontsize=7, loc="upper right")
    axes[0].set_yticks(y, labels, fontsize=8)
    axes[0].invert_yaxis()
    f.suptitle("per truth: kw calibrated on the earlier snapshot, validated at the later; "
               "right model = false-fail rate", fontsize=10)  # fmt: skip
    f.tight_layout()
    f.savefig(CAL_IMG, dpi=110)
    print(CAL_IMG)


def _rewrite(text: str, begin: str, end: str, body: str) -> str:
    pattern = re.compile(re.escape(begin) + ".*?" + re.escape(end), re.S)
    if not pattern.search(text):
        raise SystemExit(f"{DOC}: no {begin} … {end} block to rewrite")
    return pattern.sub(lambda _m: f"{begin}\n{body}\n{end}", text)


def main() -> None:
    fig = json.loads(RESULTS.read_text())["figures"]
    figure(fig)
    text = _rewrite(DOC.read_text(), "<!-- power-table begin -->", "<!-- power-table end -->",
                    table(fig))  # fmt: skip
    if CAL_RESULTS.exists():
        cal = json.loads(CAL_RESULTS.read_text())["figures"]
        cal_figure(cal)
        text = _rewrite(text, "<!-- power-calibrated-table begin -->",
                        "<!-- power-calibrated-table end -->", cal_table(cal))  # fmt: skip
    DOC.write_text(text)
    print(DOC)


if __name__ == "__main__":
    main()
