"""The gallery card of a multiple-choice row, as a reader sees it in headless Chromium: the
question, its images, every option, the chosen and the gold option marked, and the reply.

Real runs: the ViewSpatial-Bench fixture (gold A, B, A, C; question 2 shows two images) answered
"A" every time, and povagent's ``task: relation`` on a generated release in conditions A and B.
"""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml
from session_browser import KEPT_IN_STORAGE, kept_page

from povagent.config.pipeline import load_pipeline
from povagent.report.build import write_report
from povagent.run.runner import run_pipeline

#: The page error listener of the last :func:`_open`, and the page it listens to.
_listening: dict[str, tuple] = {}


def _open(browser, page_path: Path, query: str = ""):
    """The gallery ``page_path`` loaded as a new document into the module's kept page
    (tests/session_browser.py), and the list its script errors are appended to from now on."""
    page = kept_page(browser, (1300, 1000))
    if "last" in _listening:  # the last load's listener no longer counts
        earlier_page, listener = _listening.pop("last")
        if not earlier_page.is_closed():
            earlier_page.remove_listener("pageerror", listener)
    errors: list[str] = []
    listener = lambda exc: errors.append(str(exc))  # noqa: E731 (the same object is removed later)
    page.on("pageerror", listener)
    _listening["last"] = (page, listener)
    page.goto(page_path.as_uri() + query)
    page.wait_for_function("document.body.getAttribute('data-gallery-rendered') !== '0'")
    assert page.evaluate(KEPT_IN_STORAGE) == 0, "the gallery wrote to the browser's storage: the next load would see it"
    return page, errors


@pytest.fixture
def viewspatial_report(tmp_path, choice_pipeline):
    path = choice_pipeline("viewspatial", backend="test-center", reply="A")
    data = yaml.safe_load(path.read_text()) | {"label": "always-a"}
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    result = run_pipeline(load_pipeline(path))
    return write_report(result.run_dir, tmp_path / "report", n_boot=50)


def test_the_set_of_a_choice_run_is_loaded_with_its_format(viewspatial_report):
    assert viewspatial_report.dataset_note is None
    assert not any("not loadable" in note for note in viewspatial_report.analysis.notes)


def test_a_choice_card_shows_the_question_every_option_and_the_chosen_and_gold_marked(browser, viewspatial_report):
    page, errors = _open(browser, viewspatial_report.page)
    card = page.locator('.card[data-gold="B"]')  # question 2: gold B, "A" chosen
    assert card.count() == 1
    assert "Standing at the fridge facing the table" in card.inner_text()
    options = card.locator("li.opt")
    assert [options.nth(i).get_attribute("data-label") for i in range(options.count())] == ["A", "B", "C", "D"]
    assert card.locator("li.opt.chosen").get_attribute("data-label") == "A"
    assert card.locator("li.opt.gold").get_attribute("data-label") == "B"
    text = card.inner_text()
    assert "wrong" in text and "no frame selected" not in text and "undefined" not in text and "error --" not in text
    # its two images: the first on the card, both in its strip
    assert card.locator(".imgs img").count() == 1 and card.locator(".strip .tile").count() == 2
    page.wait_for_function("Number(document.body.getAttribute('data-images-loaded')) >= 4")
    page.screenshot(path=str(viewspatial_report.out / "choice-gallery.png"))
    assert errors == []


def test_a_right_answer_is_marked_chosen_and_gold_on_one_option(browser, viewspatial_report):
    page, _ = _open(browser, viewspatial_report.page)
    card = page.locator('.card[data-gold="A"]').first
    both = card.locator("li.opt.chosen.gold")
    assert both.count() == 1 and both.get_attribute("data-label") == "A" and "right" in card.inner_text()


def test_the_opened_card_shows_the_options_and_the_reply(browser, viewspatial_report):
    page, errors = _open(browser, viewspatial_report.page)
    page.locator('.card[data-gold="C"]').click()
    page.wait_for_function("!document.querySelector('#viewer pre.loading')")
    viewer = page.locator("#viewer-panel")
    assert viewer.locator("li.opt.gold").get_attribute("data-label") == "C"
    assert viewer.locator("li.opt.chosen").get_attribute("data-label") == "A"
    assert viewer.locator("pre.raw").inner_text().strip() == "A"
    assert "Selected frame" not in viewer.inner_text() and "Error (official)" not in viewer.inner_text()
    page.screenshot(path=str(viewspatial_report.out / "choice-card-open.png"))
    assert errors == []


def test_a_set_without_conditions_shows_no_condition_or_direction_filter(browser, viewspatial_report):
    page, _ = _open(browser, viewspatial_report.page)
    assert not page.locator("#f-cond").is_visible() and not page.locator("#f-dir").is_visible()
    page.select_option("#f-ok", "miss")
    assert page.locator(".card").count() == 2  # gold B and C: "A" is wrong


def test_a_relation_card_in_conditions_a_and_b_shows_its_options_and_frames(browser, tmp_path, generated_release, offline_plugin_file):
    config = tmp_path / "relation.yaml"
    config.write_text(yaml.safe_dump({
        "plugins": [str(offline_plugin_file)], "dataset": {"path": str(generated_release)}, "task": "relation",
        "backend": {"name": "test-center", "options": {"reply": "A"}}, "strategy": "choice", "scorers": ["choice"],
        "instances": {"conditions": ["a", "b"], "sample": 4, "seed": 1}, "runs": 1, "concurrency": 2, "timeout": 5, "output": str(tmp_path / "relation-run"),
    }))  # fmt: skip
    result = run_pipeline(load_pipeline(config))
    report = write_report(result.run_dir, tmp_path / "report", n_boot=50)
    page, errors = _open(browser, report.page)
    cards = page.locator(".card.choice")
    assert cards.count() == 4
    for i in range(cards.count()):
        card = cards.nth(i)
        assert card.locator("li.opt.gold").count() == 1 and card.locator("li.opt").count() >= 2
        assert card.get_attribute("data-c") in ("a", "b") and card.locator(".strip .tile").count() == 12
        assert "no frame selected" not in card.inner_text() and "undefined" not in card.inner_text()
    cards.first.scroll_into_view_if_needed()
    page.screenshot(path=str(report.out / "relation-gallery.png"))
    assert errors == []
