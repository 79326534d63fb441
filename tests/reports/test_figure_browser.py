"""The report's figures as Chromium lays them out (#37): no two text boxes of a figure overlap
(tick labels, titles, legends), measured on the page by the browser itself."""

from __future__ import annotations

import re

import pytest
from test_report_browser import _run

pytestmark = pytest.mark.browser

#: Run after the page loaded: every pair of overlapping text boxes within each inline SVG figure.
_PROBE = """
<script>
const found = [];
let texts = 0;
document.querySelectorAll("svg.figure").forEach((svg) => {
  const boxes = [...svg.querySelectorAll("text")]
    .filter((t) => t.textContent.trim())
    .map((t) => [t.textContent.trim(), t.getBoundingClientRect()]);
  texts += boxes.length;
  for (let i = 0; i < boxes.length; i++) {
    for (let j = i + 1; j < boxes.length; j++) {
      const a = boxes[i][1], b = boxes[j][1];
      const w = Math.min(a.right, b.right) - Math.max(a.left, b.left);
      const h = Math.min(a.bottom, b.bottom) - Math.max(a.top, b.top);
      if (w > 1 && h > 1) {
        found.push(svg.getAttribute("aria-label") + ": " + boxes[i][0] + " / " + boxes[j][0]);
      }
    }
  }
});
const pre = document.createElement("pre");
pre.textContent = "TEXTS[" + texts + "] OVERLAPS[" + found.join(" ; ") + "]";
document.body.appendChild(pre);
</script>
"""


def test_no_text_of_a_figure_overlaps_another_in_chromium(report_of_all, tmp_path):
    html, _ = report_of_all(tmp_path / "report.html", "browser layout test")
    page = html.read_text(encoding="utf-8").replace("</body>", _PROBE + "</body>")
    probed = tmp_path / "probed.html"
    probed.write_text(page, encoding="utf-8")
    dom = _run(["--window-size=1200,2400", "--dump-dom", probed.resolve().as_uri()], tmp_path)
    assert dom.returncode == 0, dom.stderr.decode(errors="replace")[-2000:]
    text = dom.stdout.decode("utf-8")
    m = re.search(r"TEXTS\[(\d+)\] OVERLAPS\[(.*?)\]</pre>", text, re.S)
    assert m, "the probe did not run"
    assert int(m.group(1)) > 50  # the figures' labels were measured (polar plots, motion)
    assert m.group(2) == "", m.group(2)
