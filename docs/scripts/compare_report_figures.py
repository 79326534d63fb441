"""Regenerate the figures of docs/compare-report.md from a full ``jointwear demo`` folder.

Usage: ``python docs/scripts/compare_report_figures.py DEMO_FOLDER`` (the folder ``jointwear
demo --out`` wrote). Writes ``docs/img/compare-wear-maps.png`` (the aligned wear maps of
``metrics.nc``) and ``docs/img/report-decision-card.png`` (the top of ``report.html`` in headless
Chromium, when it is installed).
"""

from __future__ import annotations

import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

IMG = Path(__file__).resolve().parents[1] / "img"


def main(folder: Path) -> None:
    from jointwear.compare import load_comparison
    from jointwear.reports.figures import wear_maps_figure

    c = load_comparison(folder / "metrics.nc")
    fig = wear_maps_figure(c.wear)
    fig.savefig(IMG / "compare-wear-maps.png", dpi=110)
    print(IMG / "compare-wear-maps.png")
    exe = shutil.which("chromium") or shutil.which("chromium-browser")
    if exe is None:
        print("headless Chromium not installed: the decision-card screenshot is not regenerated")
        return
    with tempfile.TemporaryDirectory() as tmp:
        shot = IMG / "report-decision-card.png"
        flags = ["--headless", "--no-sandbox", "--disable-gpu", "--no-first-run"]
        subprocess.run(
            [
                exe,
                *flags,
                f"--user-data-dir={tmp}",
                "--window-size=1100,900",
                f"--screenshot={shot}",
                (folder / "report.html").resolve().as_uri(),
            ],
            check=True,
            capture_output=True,
            timeout=180,
        )
    print(shot)


if __name__ == "__main__":
    main(Path(sys.argv[1]))
