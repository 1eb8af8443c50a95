"""The HTML report, opened in headless Chromium: tables, plots and gallery images render.

Chromium is required (CI installs Debian's ``chromium``): without it these tests fail with
a message saying so, they do not skip. Every page is opened in the session's one Chromium
(tests/conftest.py's ``browser``), each load a fresh document in the module's one page.
"""

from __future__ import annotations

import json
import re

import numpy as np
import pytest
from PIL import Image
from session_browser import KEPT_IN_STORAGE, kept_page

from povagent.report.build import write_report

#: The window headless Chromium opens when none is given (its command line's default).
WINDOW = (800, 600)
#: The report's script ran to its end: it sets ``data-render-ms`` on the body last.
SCRIPT_RAN = "() => document.body.hasAttribute('data-render-ms')"
#: An opened card has settled: its raw answer is no longer loading (or the page said its answers
#: file could not be read) and its images are complete.
VIEWER_SETTLED = (
    "() => { var b = document.body; return b.hasAttribute('data-render-ms')"
    " && (!document.querySelector('#viewer-panel pre.loading') || b.hasAttribute('data-data-error') || b.hasAttribute('data-answers-failed'))"
    " && Array.prototype.every.call(document.querySelectorAll('#viewer-panel img'), function (i) { return i.complete; }); }"
)
#: The opened card's frame has loaded (what a screenshot of it needs).
VIEWER_IMAGE_LOADED = "() => document.body.getAttribute('data-viewer-image') === 'loaded'"


def rendered(browser, url: str, *, window: tuple[int, int] = WINDOW, until: str | None = SCRIPT_RAN, shot=None) -> str:
    """The DOM of ``url`` in the session's Chromium once it loaded (every image, script and
    answers file the page asked for while loading has arrived or failed, and its events ran)
    and the JavaScript predicate ``until`` holds; with ``shot``, a screenshot of the ``window``
    is written there.

    Each load is a new document in the module's kept page (tests/session_browser.py's
    ``kept_page``: nothing kept from another load); that the page left nothing in the
    browser's storage for the next load is checked here."""
    page = kept_page(browser, window)
    page.goto(url, wait_until="load", timeout=90_000)
    if until is not None:
        page.wait_for_function(until, timeout=90_000)
    if shot is not None:
        page.screenshot(path=str(shot))
    assert page.evaluate(KEPT_IN_STORAGE) == 0, "the page wrote to the browser's storage: the next load would see it"
    return page.content()


def dump(browser, page, state: str = "", **options) -> str:
    """The DOM of the report ``page`` (with an optional gallery state, e.g. ``cond=c&open=0``)."""
    return rendered(browser, page.as_uri() + (f"#{state}" if state else ""), **options)


def gallery_data(report) -> dict:
    html = report.page.read_text(encoding="utf-8")
    return json.loads(re.search(r'<script type="application/json" id="gallery-data">(.*?)</script>', html, re.S).group(1))


def cards(dom: str) -> list[dict[str, str]]:
    """The rendered gallery cards' data attributes."""
    grid = dom.split('<div id="gallery">', 1)[1].split("<script", 1)[0]  # not the script's own text
    return [dict(re.findall(r'data-(\w+)="([^"]*)"', m)) for m in re.findall(r'<div class="card" ([^>]*)>', grid)]


@pytest.fixture(scope="module")
def report(sweep_dir, tmp_path_factory):
    return write_report(sweep_dir, tmp_path_factory.mktemp("report") / "out", n_boot=200)


@pytest.fixture(scope="module")
def dom(report, browser):
    return dump(browser, report.page)


def body_attr(dom: str, name: str) -> int:
    m = re.search(rf'<body[^>]*\b{name}="(\d+)"', dom)
    assert m, f"body has no {name}"
    return int(m.group(1))


def test_tables_render_with_a_row_per_system_and_the_center_baseline(dom):
    main = re.search(r'<table class="results" id="table-main".*?</table>', dom, re.S).group(0)
    for label in ("mock-a · basic", "mock-a · cot", "mock-b · basic", "mock-b · cot", "Center baseline (computed)"):
        assert f'<th scope="row">{label}</th>' in main
    assert '<span class="best">' in main


def test_plots_render_as_inline_svg(dom):
    for fig in ("error_by_condition", "error_by_direction", "error_by_condition_direction", "error_distribution"):
        assert re.search(rf'<figure id="fig-{fig}"><svg', dom)
    assert 'id="fig-scatter_x_' in dom


def test_gallery_cards_render_and_their_images_load_in_the_browser(dom, report):
    assert body_attr(dom, "data-gallery-count") == report.gallery.entries
    assert body_attr(dom, "data-gallery-rendered") > 0
    assert body_attr(dom, "data-images-loaded") >= 1  # counted by onload with naturalWidth > 0
    assert body_attr(dom, "data-images-failed") == 0
    assert body_attr(dom, "data-render-ms") >= 0  # set last: the page script ran to its end
    assert re.search(r'<div class="card" data-i="\d+"[^>]*><div class="imgs"><img alt="[^"]+" src="images/[0-9a-f]{64}\.t\.jpg">', dom)


def test_screenshot_shows_a_rendered_page_not_a_blank_one(report, browser, tmp_path):
    shot = tmp_path / "shot.png"
    dump(browser, report.page, shot=shot, window=(1400, 2000))
    assert shot.exists()
    pixels = np.asarray(Image.open(shot).convert("L"), dtype=float)
    assert pixels.std() > 20  # text, rules and bars: far from a uniform page
    assert (pixels < 80).mean() > 0.005  # dark text is present


def test_gallery_references_images_by_hash_and_inlines_no_image_data(report):
    html = report.page.read_text(encoding="utf-8")
    assert "data:image" not in html and "base64" not in html
    data = gallery_data(report)
    keys = {e["img"] for e in data["entries"] if e["img"]}
    assert keys
    for k in keys:
        assert re.fullmatch(r"[0-9a-f]{64}", k)
        assert (report.out / "images" / f"{k}.jpg").stat().st_size > 0
        assert Image.open(report.out / "images" / f"{k}.t.jpg").size == (256, 256)


def test_rerunning_the_report_reuses_every_gallery_image(report, sweep_dir):
    again = write_report(sweep_dir, report.out, n_boot=0)
    assert again.gallery.drawn == 0
    assert again.gallery.cached == report.gallery.drawn + report.gallery.cached


def test_report_writes_tables_in_markdown_csv_and_latex(report):
    for key in ("main", "ablation", "per_direction", "response_rates", "metric_variants", "paired"):
        for ext in ("md", "csv", "tex"):
            assert (report.out / "tables" / f"{key}.{ext}").stat().st_size > 0
    assert "\\toprule" in (report.out / "tables.tex").read_text()


def test_raw_answers_live_in_hashed_files_outside_the_page(report):
    html = report.page.read_text(encoding="utf-8")
    assert "Thinking about the observer" not in html  # every answered row of the fixture says it
    data = gallery_data(report)
    assert all("a" not in e and len(e["ac"]) == 2 for e in data["entries"])
    for name in data["answers"]:
        text = (report.out / "answers" / f"{name}.js").read_text(encoding="utf-8")
        assert re.fullmatch(r"[0-9a-f]{64}", name) and text.startswith(f'povAnswers("{name}",')


def test_filters_from_the_url_show_exactly_the_matching_predictions(report, browser):
    entries = gallery_data(report)["entries"]
    # system 0 (mock-a · basic): CoT's Given rows are outside the paper's protocol, left out
    dom = dump(browser, report.page, "cond=c&sys=0")
    expected = [e for e in entries if e["c"] == "c" and e["s"] == 0]
    assert 0 < len(expected) < len(entries)
    assert body_attr(dom, "data-gallery-shown") == len(expected)
    shown = cards(dom)
    assert len(shown) == len(expected) and all(c["c"] == "c" and c["s"] == "0" for c in shown)


def test_parse_status_filter_keeps_only_unanswered_predictions(report, browser):
    entries = gallery_data(report)["entries"]
    dom = dump(browser, report.page, "status=unanswered")
    unanswered = [e for e in entries if e["e"] is None]
    assert unanswered and body_attr(dom, "data-gallery-shown") == len(unanswered)
    assert {c["answered"] for c in cards(dom)} == {"0"}


def test_error_filter_and_worst_first_sort(report, browser):
    entries = gallery_data(report)["entries"]
    dom = dump(browser, report.page, "min=0.1&sort=err-desc")
    kept = sorted((e for e in entries if e["e"] is not None and e["e"] >= 0.1), key=lambda e: -e["e"])
    assert body_attr(dom, "data-gallery-shown") == len(kept)
    first = re.search(r'<div class="card" [^>]*>.*?<div class="id">([^<]*) · run', dom, re.S).group(1)
    assert first == kept[0]["id"]


def test_opening_a_card_shows_the_full_frame_and_the_raw_answer(report, browser, sweep_dir):
    entries = gallery_data(report)["entries"]
    dom = dump(browser, report.page, "status=answered&cond=a&open=0", until=VIEWER_SETTLED)
    viewed = re.search(r'<body[^>]*data-viewer="([^"]+)"', dom).group(1)
    assert any(e["id"] == viewed and e["c"] == "a" for e in entries)
    assert re.search(r'<body[^>]*data-viewer-image="loaded"', dom)
    raw = re.search(r'<pre class="raw">(.*?)</pre>', dom, re.S).group(1)
    assert "Thinking about the observer." in raw and '"selected_image"' in raw.replace("&quot;", '"')


def test_screenshot_of_an_opened_card_shows_the_frame_with_both_markers(report, browser, tmp_path):
    shot = tmp_path / "viewer.png"
    dump(browser, report.page, "status=answered&cond=c&open=0", shot=shot, window=(1300, 900), until=VIEWER_IMAGE_LOADED)
    assert shot.exists()
    px = np.asarray(Image.open(shot).convert("RGB"), dtype=int)
    r, g, b = px[..., 0], px[..., 1], px[..., 2]
    # the overlay dims the page, so saturated marker colours can only come from the drawn frame
    green = (g > 150) & (r < 90) & (b < 140)
    red = (r > 200) & (g < 90) & (b < 90)
    assert green.sum() > 150, "no ground-truth ring visible"
    assert red.sum() > 60, "no predicted cross visible"


def test_page_loads_nothing_from_the_network(report):
    html = report.page.read_text(encoding="utf-8")
    assert not re.search(r'(?:src|href)\s*=\s*["\']?(?:https?:)?//', html, re.I)
    assert "@import" not in html and "url(http" not in html
