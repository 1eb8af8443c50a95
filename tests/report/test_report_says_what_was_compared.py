"""A report says what was compared (issue 17, items 4 to 6), checked in headless Chromium.

Two reports are built once for the module: the quickstart's (the offline baselines center,
random and oracle, through the real quickstart on the hand-made dataset) and a strategy sweep
(one model x five strategies, the shape of ``examples/sweeps/paper_ablation.yaml``). Each is
read as a reader would: the header, the tables' row labels and captions, the plot legends, the
gallery cards and their frame strips, the filters in the page address; and screenshotted.
"""

from __future__ import annotations

import re
import urllib.parse
from pathlib import Path

import numpy as np
import pytest
from PIL import Image
from test_report_html import body_attr, cards, dump, gallery_data, rendered  # the Chromium helpers

from povagent.report.build import write_report
from povagent.report.gallery import Drawing, ground_truth_views, write_drawing
from povagent.report.plots import grouped_bars, histogram, series_styles
from povagent.report.statistics import Estimate
from povagent.scoring.normalized_l2 import project_ground_truth

STRATEGIES = ("basic", "o-plot", "oa-plot", "cot", "spatial-cot")
#: The quickstart link the README shows (proposed in the README text of this change): the random
#: baseline's Inferred answers, worst first, the first one opened.
# the example link the first-evaluation tutorial gives, read from it so the two cannot drift
README_LINK_STATE = re.search(
    r"`report\.html#([^`]+)`", (Path(__file__).parents[2] / "docs" / "tutorials" / "first-evaluation.md").read_text(encoding="utf-8")
).group(1)
WINDOW = (1300, 900)
#: Every strip image on the page (a CSS background each, counted by the page's probe) has loaded
#: or failed, and an opened card's frame has loaded.
STRIPS_SETTLED = (
    "() => { var b = document.body, keys = new Set(Array.from(document.querySelectorAll('.strip .tile'), function (t) { return t.style.backgroundImage; }));"
    " return (+b.getAttribute('data-strips-loaded') || 0) + (+b.getAttribute('data-strips-failed') || 0) >= keys.size"
    " && (!b.hasAttribute('data-viewer') || b.getAttribute('data-viewer-image') === 'loaded'); }"
)


@pytest.fixture(scope="module")
def quickstart(tmp_path_factory, mini_root):
    """The quickstart's report, made by the real quickstart on the hand-made dataset."""
    from povagent.report.quickstart import run_quickstart

    done = run_quickstart(tmp_path_factory.mktemp("quickstart") / "qs", dataset=mini_root, quiet=True, say=lambda _text: None)
    return write_report(done.sweep, done.report.parent, n_boot=100)


@pytest.fixture(scope="module")
def strategy_sweep(tmp_path_factory, mini_dataset, sweep_writer):
    """A report of one model under five strategies (no baseline cell: the center is computed)."""
    cells = [{"model": "mock-a", "strategy": s, "seed": i, "noise": 30.0 + 10 * i} for i, s in enumerate(STRATEGIES)]
    folder = sweep_writer(tmp_path_factory.mktemp("strategies") / "sweep", mini_dataset, cells)
    return write_report(folder, tmp_path_factory.mktemp("strategies_report") / "out", n_boot=100)


@pytest.fixture(scope="module")
def quickstart_dom(quickstart, browser):
    return dump(browser, quickstart.page)


@pytest.fixture(scope="module")
def sweep_dom(strategy_sweep, browser):
    return dump(browser, strategy_sweep.page)


def header(dom: str) -> str:
    return re.search(r'<div class="meta">(.*?)</div>', dom, re.S).group(1)


def table(dom: str, key: str) -> str:
    return re.search(rf'<table class="results" id="table-{key}".*?</table>', dom, re.S).group(0)


def row_labels(dom: str, key: str) -> list[str]:
    return re.findall(r'<th scope="row">([^<]*)</th>', table(dom, key))


def legend_entries(svg: str) -> list[dict[str, str]]:
    return [dict(re.findall(r'data-(\w+)="([^"]*)"', m)) for m in re.findall(r'<g class="legend-entry" ([^>]*)>', svg)]


# -- item 4: model x strategy -------------------------------------------------------------------------
def test_the_header_counts_models_times_strategies_and_names_the_baselines(sweep_dom, quickstart_dom):
    assert "1 model x 5 strategies · 1 baseline: Center baseline (computed)" in header(sweep_dom)
    assert "3 baselines: center, random, oracle" in header(quickstart_dom)
    for dom in (sweep_dom, quickstart_dom):
        assert "model(s)" not in header(dom) and "baseline(s)" not in header(dom)


def test_a_grid_of_two_models_and_two_strategies_reads_as_a_product(sweep_dir, make_sweep):
    from povagent.report.analysis import analyze, what_was_compared
    from povagent.report.collect import collect

    assert what_was_compared(analyze(collect(sweep_dir), n_boot=0)) == "2 models x 2 strategies"
    partial = make_sweep([
        {"model": "mock-a", "strategy": "basic"}, {"model": "mock-a", "strategy": "cot"}, {"model": "mock-b", "strategy": "basic"},
    ])
    assert what_was_compared(analyze(collect(partial), n_boot=0)) == "3 systems (2 models, 2 strategies)"


def test_every_table_row_names_the_model_and_the_strategy(sweep_dom):
    wanted = [f"mock-a · {s}" for s in STRATEGIES]
    for key in ("main", "ablation", "per_direction", "per_condition_direction", "response_rates"):
        assert row_labels(sweep_dom, key)[:5] == wanted, key
    assert {label.rsplit(" / ", 1)[0] for label in row_labels(sweep_dom, "metric_variants")} >= set(wanted)


def test_every_plot_legend_names_the_model_and_the_strategy(sweep_dom):
    figures = re.findall(r'<figure id="fig-(error_by_[a-z_]+|error_distribution)">(.*?)</figure>', sweep_dom, re.S)
    assert len(figures) == 4
    for name, svg in figures:
        series = [e["series"] for e in legend_entries(svg)]
        assert series[:5] == [f"mock-a · {s}" for s in STRATEGIES], name


def test_every_gallery_card_names_the_model_and_the_strategy(sweep_dom, strategy_sweep):
    shown = cards(sweep_dom)
    assert shown and all(re.fullmatch(r"mock-a · [a-z-]+", c["system"]) for c in shown)
    grid = sweep_dom.split('<div id="gallery">', 1)[1].split("<script", 1)[0]
    badges = re.findall(r'<span class="badge system">([^<]*)</span>', grid)
    assert len(badges) == len(shown) and set(badges) <= {f"mock-a · {s}" for s in STRATEGIES}


def test_the_system_filter_takes_a_name_in_the_address(strategy_sweep, browser):
    data = gallery_data(strategy_sweep)
    cot = data["systems"].index("mock-a · cot")
    expected = [e for e in data["entries"] if e["s"] == cot]
    dom = dump(browser, strategy_sweep.page, "system=" + urllib.parse.quote("mock-a/cot", safe=""))
    assert 0 < body_attr(dom, "data-gallery-shown") == len(expected) < len(data["entries"])
    assert {c["system"] for c in cards(dom)} == {"mock-a · cot"}
    # the select offers names, and the help text says how to write one in the address
    assert '<option value="mock-a · cot">mock-a · cot</option>' in dom
    assert "system=mock-a%2Fo-plot" in re.search(r'<div class="help" id="address-help">.*?</div>', dom, re.S).group(0)


def test_a_query_in_the_address_filters_too(strategy_sweep, browser):
    data = gallery_data(strategy_sweep)
    basic = data["systems"].index("mock-a · basic")
    url = strategy_sweep.page.as_uri() + "?system=mock-a%2Fbasic&cond=b"
    done = rendered(browser, url)
    expected = [e for e in data["entries"] if e["s"] == basic and e["c"] == "b"]
    assert body_attr(done, "data-gallery-shown") == len(expected) > 0


# -- item 5: captions that fit ------------------------------------------------------------------------
def test_with_only_baselines_no_caption_promises_a_best_model_in_bold(quickstart_dom):
    for key in ("main", "per_direction", "response_rates"):
        t = table(quickstart_dom, key)
        assert "best model per column is in bold" not in t
        assert "Only baselines ran, no model: nothing is bolded" in t
        assert '<span class="best">' not in t
    assert row_labels(quickstart_dom, "main") == ["center", "random", "oracle"]
    assert "<th>Baseline</th>" in table(quickstart_dom, "main")


def test_with_several_models_the_caption_says_what_bold_means_and_bold_is_there(sweep_dom):
    t = table(sweep_dom, "main")
    assert "The best model per column is in bold." in t and '<span class="best">' in t
    assert "Baselines are in italics below the models, for reference, never bolded: Center baseline (computed)." in t


def test_an_empty_filter_result_says_so_and_its_clear_link_shows_everything(quickstart, browser):
    dom = dump(browser, quickstart.page, "system=oracle&min=1.4")
    assert body_attr(dom, "data-gallery-shown") == 0
    assert re.search(r'<div id="empty" style="display: block;">No prediction matches: <a id="clear-filters" href="([^"]+)">clear filters</a>', dom)
    href = re.search(r'<a id="clear-filters" href="([^"]+)"', dom).group(1)
    cleared = rendered(browser, urllib.parse.urljoin(quickstart.page.as_uri() + "#system=oracle&min=1.4", href))
    assert body_attr(cleared, "data-gallery-shown") == body_attr(cleared, "data-gallery-count") > 0
    assert 'id="empty" style="display: none;"' in cleared


def test_a_heading_reached_by_an_anchor_sits_below_the_sticky_menu(quickstart, browser):
    for anchor in ("tables", "plots"):
        # the page measures where the heading landed once loaded, in a timer: waited for
        dom = dump(browser, quickstart.page, anchor, until="() => document.body.hasAttribute('data-anchor-top')")
        assert body_attr(dom, "data-anchor-top") >= body_attr(dom, "data-menu-bottom") > 0, anchor


def test_the_readme_link_shows_a_prediction_on_the_quickstart_report(quickstart, browser):
    dom = dump(browser, quickstart.page, README_LINK_STATE)
    assert body_attr(dom, "data-gallery-shown") > 0
    assert re.search(r'<body[^>]*data-viewer="[^"]+/a"', dom)  # an Inferred card, opened


def test_each_baseline_has_its_own_colour_and_marker_in_every_plot(quickstart_dom):
    figures = re.findall(r'<figure id="fig-([a-z_]+)">(.*?)</figure>', quickstart_dom, re.S)
    assert {name for name, _ in figures} == {"error_by_condition", "error_by_direction", "error_by_condition_direction", "error_distribution"}
    for name, svg in figures:
        entries = legend_entries(svg)
        assert [e["series"] for e in entries] == ["center", "random", "oracle"], name
        assert len({e["colour"] for e in entries}) == 3 and len({e["marker"] for e in entries}) == 3, name
        # the marker is drawn on the data, not only in the legend: a zero bar (the oracle) shows
        assert svg.count('class="marker"') > len(entries), name


def test_plot_styles_keep_baselines_apart_from_models_and_from_each_other():
    series = [("m1", [], False), ("m2", [], False), ("center", [], True), ("random", [], True), ("oracle", [], True)]
    styles = series_styles(series)
    assert len({s.colour for s in styles}) == 5 and len({s.marker for s in styles[2:]}) == 3
    assert [s.reference for s in styles] == [False, False, True, True, True]
    bars = grouped_bars("t", ["Inferred"], [(n, [Estimate(0.0, 0.0, 0.0)], r) for n, _, r in series])
    assert bars.count("<pattern ") == 3  # baselines hatched, models solid
    hist = histogram("t", [(n, [0.1, 0.2], r) for n, _, r in series])
    assert hist.count('stroke-dasharray="5 3"') == 3  # baselines dashed


def test_the_off_frame_arrow_is_readable_on_a_thumbnail(mini_dataset, tmp_path):
    frame = mini_dataset.instances()[0].frames[0]
    w, h = frame.camera.width, frame.camera.height
    write_drawing(Drawing(frame.file, (-0.3 * w, 0.5 * h), "out", None), tmp_path, "k")
    thumb = np.asarray(Image.open(tmp_path / "k.t.jpg").convert("RGB"), dtype=int)
    r, g, b = thumb[..., 0], thumb[..., 1], thumb[..., 2]
    green = (g > 150) & (r < 90) & (b < 140)
    dark = (r < 50) & (g < 50) & (b < 50)
    left = np.zeros_like(green)
    left[:, : thumb.shape[1] // 4] = True
    assert (green & left).sum() >= 150  # a thick shaft and head (the 2 px line it replaced: 37 px)
    assert (dark & left).sum() >= 60  # its black outline


# -- item 6: the frame strip --------------------------------------------------------------------------
def strips_in(dom: str) -> list[tuple[dict[str, str], str]]:
    grid = dom.split('<div id="gallery">', 1)[1].split("<script", 1)[0]
    out = []
    for card in re.findall(r'<div class="card" (.*?)<div class="sent">', grid, re.S):
        attrs = dict(re.findall(r'data-(\w+)="([^"]*)"', card.split(">", 1)[0]))
        m = re.search(r'<div class="strip" (.*?)</div></div>', card, re.S)
        out.append((attrs, m.group(0) if m else ""))
    return out


@pytest.mark.parametrize("which", ["quickstart_dom", "sweep_dom"])
def test_inferred_and_stated_cards_show_the_houses_frames_with_the_pick_outlined(which, request):
    dom = request.getfixturevalue(which)
    seen = 0
    for attrs, strip in strips_in(dom):
        if attrs["c"] == "c":
            assert not strip  # Given shows the observer view: no frames to pick from
            continue
        assert strip, attrs
        n = int(re.search(r'data-frames="(\d+)"', strip).group(1))
        tiles = re.findall(r'<div class="tile([^"]*)" data-frame="(\d+)"', strip)
        assert [int(k) for _, k in tiles] == list(range(n))
        picked = [int(k) for cls, k in tiles if " sel" in cls]
        ticked = [int(k) for cls, k in tiles if " gt" in cls]
        assert len(ticked) == int(re.search(r'data-gt-frames="(\d+)"', strip).group(1))
        if attrs["answered"] == "1":
            assert len(picked) == 1
            seen += 1
    assert seen > 0


def test_the_strip_marks_exactly_the_frames_the_scorer_would_find_the_gt_in(quickstart, mini_dataset):
    data = gallery_data(quickstart)
    checked = 0
    for e in data["entries"]:
        if "fs" not in e:
            continue
        inst = mini_dataset.instance(e["id"])
        within = {i for i, f in enumerate(inst.frames) if project_ground_truth(inst.target, f.camera).in_frame}
        seen, hidden = data["views"][e["fw"]]
        assert set(seen) | set(hidden) == within
        if e["k"] is not None and e["f"] is not None:
            # the scorer's stored "GT in the selected frame" agrees with the strip's marks
            assert (e["k"] in within) == e["f"]
            checked += 1
    assert checked > 0


def test_a_frame_whose_log_saw_other_objects_but_not_the_anchor_is_marked_maybe_hidden(mini_dataset):
    from dataclasses import replace

    inst = next(i for i in mini_dataset.instances() if i.condition.uses_exploration_frames and ground_truth_views(i)[0])
    k = ground_truth_views(inst)[0][0]
    anchor = inst.anchor_object.objectId
    for hits, expect in ((frozenset({anchor, "Sofa|1"}), "seen"), (frozenset({"Sofa|1"}), "hidden"), (frozenset(), "seen")):
        frames = tuple(replace(f, in_frame_hits=hits) if f.index == k else f for f in inst.frames)
        seen, hidden = ground_truth_views(replace(inst, frames=frames))
        assert (k in seen, k in hidden) == (expect == "seen", expect == "hidden"), hits


def test_the_strip_is_drawn_in_the_browser(quickstart, browser, tmp_path):
    """The opened card's strip, screenshotted: its frames' pixels are drawn, the pick is outlined
    in red and the frames that show the GT are ticked in green."""
    data = gallery_data(quickstart)
    state = "cond=a&status=answered&open=0"
    dom = dump(browser, quickstart.page, state, until=STRIPS_SETTLED)
    assert body_attr(dom, "data-strips-loaded") >= 1 and "data-strips-failed" not in dom.split(">", 1)[0]
    opened = re.search(r'<body[^>]*data-viewer="([^"]+)"', dom).group(1)
    entry = next(e for e in data["entries"] if e["id"] == opened)
    seen = data["views"][entry["fw"]][0]
    assert seen, "pick a card whose strip has a tick"
    shot = tmp_path / "viewer.png"
    dump(browser, quickstart.page, state, shot=shot, window=WINDOW, until=STRIPS_SETTLED)
    assert shot.exists()
    px = np.asarray(Image.open(shot).convert("RGB"), dtype=int)
    tick = (px[..., 0] == 0) & (px[..., 1] == 168) & (px[..., 2] == 68)  # #00a844, drawn by CSS
    outline = (px[..., 0] == 255) & (px[..., 1] == 45) & (px[..., 2] == 45)  # #ff2d2d
    assert tick.sum() >= 30 * len(seen)
    assert outline.sum() >= 150
    ys, xs = np.nonzero(tick)
    strip = px[max(0, ys.min() - 60) : ys.max() + 1, xs.min() - 5 : xs.max() + 5]
    plain = ~(((strip[..., 0] == 0) & (strip[..., 1] == 168)) | ((strip[..., 0] == 68) & (strip[..., 1] == 68)))
    assert strip[plain].std() > 20  # frames, not empty grey tiles


def test_the_strip_images_stay_small(quickstart):
    strips = list((quickstart.out / "images").glob("*.s.jpg"))
    assert 1 <= len(strips) == len(gallery_data(quickstart)["strips"])
    frames = sum(s["n"] for s in gallery_data(quickstart)["strips"])
    assert sum(p.stat().st_size for p in strips) / frames < 2500  # bytes per frame
    # the marks are stored once per target (house, pair, direction), not once per card
    data = gallery_data(quickstart)
    targets = {e["id"].rsplit("/", 1)[0] for e in data["entries"] if "fw" in e}
    assert len(data["views"]) <= len(targets) < len([e for e in data["entries"] if "fw" in e])


def test_a_compare_page_carries_the_strips_of_run_a(strategy_sweep, tmp_path, mini_dataset):
    from povagent.report.compare import compare_runs, write_comparison_html

    sweep = strategy_sweep.analysis.source
    page = write_comparison_html(compare_runs(sweep / "cell_00", sweep / "cell_03", n_boot=0), tmp_path, mini_dataset)
    html = page.read_text(encoding="utf-8")
    data = __import__("json").loads(re.search(r'id="gallery-data">(.*?)</script>', html, re.S).group(1))
    assert data["strips"] and all(("fs" in e) == (e["c"] != "c") for e in data["entries"])
