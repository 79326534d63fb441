"""The report as a person sees it: rendered by headless Chromium (screenshot and DOM)."""

from __future__ import annotations

import os
import shutil
import subprocess

import numpy as np
import pytest
from test_report_html import EXPECTED_SECTIONS, _Page  # noqa: I001

pytestmark = pytest.mark.browser

FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]


def _chromium() -> str:
    for name in ("chromium", "chromium-browser", "google-chrome", "chrome"):
        path = shutil.which(name)
        if path:
            return path
    message = (
        "headless Chromium is not installed (Debian: apt-get install chromium); the browser "
        "check of the report cannot run"
    )
    if os.environ.get("CI") == "true":
        pytest.fail(message + " - CI must install it (.ci/run)")
    pytest.skip(message)


def _run(args: list[str], tmp_path) -> subprocess.CompletedProcess:
    return subprocess.run(
        [_chromium(), *FLAGS, f"--user-data-dir={tmp_path / 'profile'}", *args],
        capture_output=True,
        timeout=180,
        check=False,
    )


def test_report_renders_in_chromium(report_of_all, tmp_path):
    exe = _chromium()
    assert exe
    html, _ = report_of_all(tmp_path / "report.html", "browser test")
    url = html.resolve().as_uri()
    shot = tmp_path / "shot.png"
    res = _run(["--window-size=1200,2400", f"--screenshot={shot}", url], tmp_path)
    assert shot.exists(), res.stderr.decode(errors="replace")[-2000:]
    from PIL import Image

    img = np.asarray(Image.open(shot).convert("L"), dtype=float)
    assert img.shape == (2400, 1200)
    non_white = np.mean(img < 240)
    assert non_white > 0.03, f"page looks blank ({non_white:.1%} non-white pixels)"
    assert img.std() > 20
    # the coloured decision card (green or red border and verdicts) is drawn
    rgb = np.asarray(Image.open(shot).convert("RGB"), dtype=int)
    saturation = rgb.max(axis=2) - rgb.min(axis=2)
    assert np.mean(saturation > 60) > 0.001

    dom = _run(["--dump-dom", url], tmp_path)
    assert dom.returncode == 0, dom.stderr.decode(errors="replace")[-2000:]
    page = _Page()
    page.feed(dom.stdout.decode("utf-8"))
    assert page.h2 == EXPECTED_SECTIONS
    assert page.tags.get("svg", 0) >= 2
    # the four verdict states as Chromium renders them, with their own classes (colours)
    states = {text: cls for cls, text in page.cells}
    assert states.get("FAIL") == "fail" and states.get("PASS") == "pass"
    assert states.get("NOT ASSESSED") == "not-assessed"
    assert states.get("NOT COMPARABLE") == "not-comparable"
    dom_text = dom.stdout.decode("utf-8")
    assert "NOT VALIDATED: 1 of" in dom_text
    assert "uncompared region hatched" in dom_text
