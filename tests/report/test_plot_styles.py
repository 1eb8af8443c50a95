"""Twelve systems in one plot: each its own colour-blind-safe colour and marker pair, stable
by system order, and a legend whose entries neither overlap each other nor the plot (measured
in headless Chromium)."""

from __future__ import annotations

import itertools
import json
import re

from test_report_html import rendered  # the Chromium helpers

from povagent.report.plots import DISTINCT_MODEL_STYLES, PALETTE, grouped_bars, histogram, series_styles
from povagent.report.statistics import Estimate

#: Nine models (three families x three strategies, long names) and three baselines.
MODELS = [f"{m} · {s}" for m in ("openai/gpt-4o-2024-08-06", "qwen3-vl-8b-instruct", "gemini-2.5-flash") for s in ("basic", "cot", "spatial-cot")]
SERIES = [(n, [Estimate(0.2 + 0.02 * i, 0.15, 0.3)] * 3, False) for i, n in enumerate(MODELS)] + [
    (b, [Estimate(0.3, 0.25, 0.35)] * 3, True) for b in ("center", "random", "oracle")
]


def test_twelve_systems_get_twelve_distinct_pairs_stable_by_order():
    styles = series_styles(SERIES)
    pairs = [(s.colour, s.marker) for s in styles]
    assert len(set(pairs)) == 12
    # the example of the issue: the first and the eighth model were both blue circles
    assert pairs[0] != pairs[7]
    # models: neighbours differ in colour and in shape; no model looks like a baseline
    models = styles[:9]
    assert all(a.colour != b.colour and a.marker != b.marker for a, b in itertools.pairwise(models))
    assert {s.colour for s in models} <= set(PALETTE)
    # stable: the same order gives the same styles, a system's style depends on its place only
    assert series_styles(SERIES) == styles and series_styles(SERIES[:5])[:5] == styles[:5]


def test_pairs_stay_distinct_up_to_35_models():
    many = [(f"m{i}", [], False) for i in range(DISTINCT_MODEL_STYLES)]
    assert DISTINCT_MODEL_STYLES == 35
    assert len({(s.colour, s.marker) for s in series_styles(many)}) == 35


def test_each_plot_draws_every_pair_in_its_legend():
    for svg in (grouped_bars("t", ["Inferred", "Stated", "Given"], SERIES), histogram("t", [(n, [0.1, 0.5], r) for n, _, r in SERIES])):
        entries = re.findall(r'<g class="legend-entry" data-series="([^"]+)" data-marker="([^"]+)" data-colour="([^"]+)">', svg)
        assert len(entries) == 12 and len({(m, c) for _, m, c in entries}) == 12


def test_the_legend_of_twelve_long_names_is_readable_in_chromium(tmp_path, browser):
    """Entries do not overlap, stay inside the plot's width, and sit above the plotted area;
    the plot keeps its height for the data (the legend's rows add height)."""
    one = grouped_bars("t", ["Inferred", "Stated", "Given"], SERIES[:2])
    svg = grouped_bars("t", ["Inferred", "Stated", "Given"], SERIES)
    h1, h12 = (int(re.search(r'<svg [^>]*height="(\d+)"', x).group(1)) for x in (one, svg))
    assert h12 > h1  # the extra legend rows added height instead of squeezing the bars
    page = tmp_path / "plot.html"
    page.write_text(
        "<!doctype html><html><body>" + svg + "<script>window.addEventListener('load', function () {"
        "var svg = document.querySelector('svg'), boxes = [], gridTop = Infinity;"
        "document.querySelectorAll('.legend-entry').forEach(function (g) { var b = g.getBBox(); boxes.push([b.x, b.y, b.x + b.width, b.y + b.height]); });"
        "document.querySelectorAll('svg > line').forEach(function (l) { gridTop = Math.min(gridTop, l.getBBox().y); });"
        "document.body.setAttribute('data-boxes', JSON.stringify(boxes));"
        "document.body.setAttribute('data-grid-top', String(gridTop));"
        "document.body.setAttribute('data-svg-width', String(svg.viewBox.baseVal.width));"
        "});</script></body></html>",
        encoding="utf-8",
    )
    dom = rendered(browser, page.as_uri(), until="() => document.body.hasAttribute('data-svg-width')")
    boxes = json.loads(re.search(r'data-boxes="([^"]+)"', dom).group(1).replace("&quot;", '"'))
    grid_top = float(re.search(r'data-grid-top="([^"]+)"', dom).group(1))
    width = float(re.search(r'data-svg-width="([^"]+)"', dom).group(1))
    assert len(boxes) == 12
    for i, a in enumerate(boxes):
        assert a[0] >= 0 and a[2] <= width, a  # inside the plot's width
        assert a[3] <= grid_top, (a, grid_top)  # above the bars' area
        for b in boxes[i + 1 :]:
            overlap = min(a[2], b[2]) - max(a[0], b[0]) > 0.5 and min(a[3], b[3]) - max(a[1], b[1]) > 0.5
            assert not overlap, (a, b)
