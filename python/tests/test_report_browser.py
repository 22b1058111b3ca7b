"""report.html as a reader sees it: the built-in design's report opened by headless Chromium (Debian's
``chromium``, installed by validation/setup_browser.sh) through the DevTools protocol.

Checked: no console error, uncaught exception or failed load; every figure an inline SVG rendered
at a nonzero size with shapes of nonzero extent; the check table is the first table and comes
before any figure. The same probe fails on a copy of the report whose figure was removed (the
renderer's "figure … not found" note in its place) or drawn at zero size: the test can fail.
"""

from __future__ import annotations

import os
import re
import sys
from pathlib import Path
import pytest

import vibrofem as vf

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import browser  # noqa: E402

pytestmark = pytest.mark.skipif(
    browser.find_chromium() is None and os.environ.get("VIBROFEM_REQUIRE_BROWSER") != "1",
    reason="chromium not installed (bash validation/setup_browser.sh)",
)


def test_the_design_report_renders_completely(design_report: vf.AppReport) -> None:
    page = browser.open_report(design_report.html)
    assert page.problems() == [], page.problems()
    assert page.tables[0] == "checks" and page.checks_rows >= 1
    svgs = sorted(p.name for p in design_report.out.glob("*.svg"))
    assert len(page.figures) >= 1 and len(svgs) >= 1
    print(f"{len(page.figures)} figures, {page.checks_rows} checks, {len(svgs)} SVG files")


def test_a_missing_figure_fails_the_check(design_report: vf.AppReport, tmp_path: Path) -> None:
    html = design_report.html.read_text()
    figures = re.findall(r'<figure id="([^"]+)">', html)
    assert figures
    # The figure's SVG deleted: what the renderer writes when the file is not beside the report.
    gone = re.sub(
        r'<figure id="' + re.escape(figures[0]) + r'">.*?</figure>',
        f"<p class=fail>figure {figures[0]}.svg not found beside the report</p>",
        html,
        count=1,
        flags=re.S,
    )
    (tmp_path / "report.html").write_text(gone)
    page = browser.open_report(tmp_path / "report.html")
    assert any(figures[0] in p for p in page.problems()), page.problems()
    # The figure present but drawn at zero size.
    flat = html.replace(f'<figure id="{figures[-1]}"><svg', f'<figure id="{figures[-1]}"><svg style="width:0;height:0"', 1)
    (tmp_path / "report.html").write_text(flat)
    page = browser.open_report(tmp_path / "report.html")
    assert any(figures[-1] in p and "0 × 0" in p for p in page.problems()), page.problems()
    # A script error on the page.
    (tmp_path / "report.html").write_text(html.replace("</body>", "<script>undefinedFunction()</script></body>"))
    page = browser.open_report(tmp_path / "report.html")
    assert any("undefinedFunction" in p for p in page.problems()), page.problems()
