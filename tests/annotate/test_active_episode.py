"""An active episode walked by a person in a real browser: the same tools a model has, the
views rendered by the same renderer, and the person's steps in the same episode record."""

from __future__ import annotations

import pytest
from served_page import Served, write_study

from povagent.results.episode import read_record
from povagent.results.rows import iter_rows

pytestmark = pytest.mark.slow


def images_shown(page) -> int:
    return page.locator("#strip button").count()


def use_tool(page, key: str, value: str) -> None:
    """Press the tool's key, type its argument, Enter; wait for the view it renders."""
    before = images_shown(page)
    page.keyboard.press(key)
    page.keyboard.type(value)
    page.keyboard.press("Enter")
    page.wait_for_function("(n) => document.querySelectorAll('#strip button').length > n", arg=before, timeout=120_000)


@pytest.fixture(scope="module")
def episode(browser, generated_release, tmp_path_factory):
    """alice goes to frame 1, turns 30 degrees left, and answers with a click in the view she sees."""
    folder = tmp_path_factory.mktemp("active")
    study = write_study(folder, generated_release, strategy="active", parser="active",
                        instances={"houses": ["train_house_00000"], "conditions": ["a"], "limit": 1})  # fmt: skip
    page = browser.new_page(viewport={"width": 1280, "height": 720})
    page.set_default_timeout(120_000)  # a loaded machine: the first question may take a while
    served = Served(study)
    try:
        page.goto(served.url)
        page.wait_for_selector("#tools fieldset")
        tools = page.locator("#tools legend").all_text_contents()
        use_tool(page, str(1 + [t.split(". ", 1)[1] for t in tools].index("go_to_frame")), "1")
        use_tool(page, str(1 + [t.split(". ", 1)[1] for t in tools].index("turn")), "-30")
        page.wait_for_function("() => document.getElementById('view').complete && document.getElementById('view').naturalWidth > 0")
        box = page.locator("#view").bounding_box()
        page.locator("#view").click(position={"x": box["width"] / 2, "y": box["height"] / 2})
        # the mark placed and the page not busy (Enter on a busy page, or before the click took, does nothing)
        page.wait_for_function("() => !document.getElementById('submit').disabled", timeout=120_000)
        page.keyboard.press("Enter")
        served.wait_all_done(page)
        exit_code = served.wait()
    finally:
        served.kill()
        page.close()
    (row,) = iter_rows(folder / "human-alice" / "results.jsonl")
    return row, exit_code, tools


def test_the_page_offers_every_tool_a_model_is_offered(episode):
    from povagent.plugins import get_plugin_host

    _, _, tools = episode
    assert [t.split(". ", 1)[1] for t in tools] == list(get_plugin_host().tools().names)


def test_the_persons_steps_are_the_episode_record_of_the_row(episode):
    row, exit_code, _ = episode
    record = read_record(row.exchanges[-1].raw)
    assert [(s.action, s.valid) for s in record.steps] == [("go_to_frame", True), ("turn", True), ("answer", True)]
    assert record.counts.views == 2
    assert exit_code == 0


def test_the_click_answers_in_the_view_it_was_made_in(episode):
    row, _, _ = episode
    record = read_record(row.exchanges[-1].raw)
    assert record.answer.image == "view 2" and record.answer.camera == record.views[1].camera
    assert row.status == "answered" and row.model == "human:alice"
