"""The report's building blocks render in real headless Chromium without console errors."""

from __future__ import annotations

import re

import cv2
import numpy as np

from browser import dump_dom, screenshot
from vidstyle.report import svg
from vidstyle.report.page import Page


def test_svg_page_renders_in_chromium(tmp_path):
    page = Page("Test report", "subtitle")
    page.add("Heatmap", svg.heatmap(np.array([[0.9, 0.1], [0.2, 0.8]]), ["a", "b"], ["a", "b"], title="confusion"))
    page.add("Timeline", svg.timeline({"truth": ["a"] * 10 + ["b"] * 5, "pred": ["a"] * 8 + ["b"] * 7}, ["a", "b"], 5))
    html_path = tmp_path / "r.html"
    html_path.write_text(page.render())
    dom = dump_dom(html_path)
    assert 'data-rendered="ok"' in dom
    assert "data-errors" not in dom
    png = screenshot(html_path, tmp_path / "r.png", size=(900, 700))
    img = cv2.imread(str(png))
    assert img is not None and img.shape[:2] == (700, 900)
    # the heatmap's dark-blue cell (0.9) is on screen
    dark_blue = np.all(np.abs(img.astype(int) - [148, 69, 8]) < 40, axis=-1)  # BGR of #084594-ish
    assert dark_blue.sum() > 200


def test_page_reports_script_errors(tmp_path):
    page = Page("Broken")
    page.add("bad", "<script>undefinedFunction()</script>")
    html_path = tmp_path / "b.html"
    html_path.write_text(page.render())
    dom = dump_dom(html_path)
    assert re.search(r'data-errors="[^"]*undefinedFunction', dom)
