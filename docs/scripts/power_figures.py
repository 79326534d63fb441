"""The power figure and table of docs/compare-report.md, from benchmarks/results/validation_power.json.

Usage: ``python docs/scripts/power_figures.py`` writes ``docs/img/validation-power.png``
(detection probability against the size of the wear-coefficient error per criterion on the
reference truth, and every other candidate's detection by criterion) and rewrites the table
between ``<!-- power-table begin -->`` and ``<!-- power-table end -->`` in docs/compare-report.md,
each figure with its marker (``docs/scripts/quoted_figures.py`` checks them).
"""

from __future__ import annotations

import json
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
RESULTS = ROOT / "benchmarks" / "results" / "validation_power.json"
DOC = ROOT / "docs" / "compare-report.md"
IMG = ROOT / "docs" / "img" / "validation-power.png"

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


def main() -> None:
    fig = json.loads(RESULTS.read_text())["figures"]
    figure(fig)
    text = DOC.read_text()
    begin, end = "<!-- power-table begin -->", "<!-- power-table end -->"
    pattern = re.compile(re.escape(begin) + ".*?" + re.escape(end), re.S)
    if not pattern.search(text):
        raise SystemExit(f"{DOC}: no {begin} … {end} block to rewrite")
    DOC.write_text(pattern.sub(lambda _m: f"{begin}\n{table(fig)}\n{end}", text))
    print(DOC)


if __name__ == "__main__":
    main()
