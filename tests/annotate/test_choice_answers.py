"""A multiple-choice question in a real browser: the options are buttons, chosen with a key."""

from __future__ import annotations

import asyncio
import concurrent.futures
import dataclasses
import threading

import pytest

from povagent.annotate.answer_page import AnswerPage
from povagent.annotate.desk import AnswerDesk, serving
from povagent.annotate.server import AnnotateServer
from povagent.answers.choice_question import ChoiceQuestion
from povagent.exchange.images import ImageStore
from povagent.plugins import get_plugin_host

pytestmark = pytest.mark.slow

QUESTION = ChoiceQuestion(
    question="From where the speaker stood, where is the <b>target</b> relative to the anchor?",
    options=(("A", "left"), ("B", "right"), ("C", "front"), ("D", "<img src=x>behind")),
    gold="C",
)


@pytest.fixture
def asked(mini_dataset):
    """The choice strategy's request for a Given instance, waiting on a served desk for the
    person's answer (the row's durability is acknowledged as the runner's journal would)."""
    base = next(i for i in mini_dataset.instances() if not i.condition.uses_exploration_frames)
    instance = dataclasses.replace(base, question=QUESTION)
    host = get_plugin_host()
    images = ImageStore()
    request = host.strategy("choice", {}).build(instance, images)
    desk = AnswerDesk("alice", total=1)
    server = AnnotateServer(AnswerPage(desk, wait_s=1.0))
    server.start()
    answered: concurrent.futures.Future = concurrent.futures.Future()

    async def person() -> None:
        with serving(desk):
            response = await host.backend("human", {"annotator": "alice"}).complete(request, images)
        desk.row_saved()
        desk.finish()
        answered.set_result(response)

    thread = threading.Thread(target=lambda: asyncio.run(person()), daemon=True)
    thread.start()
    try:
        yield server, answered
    finally:
        desk.finish()
        server.close()


def test_a_key_chooses_an_option_and_enter_answers_with_its_bare_label(browser, asked):
    server, answered = asked
    page = browser.new_page(viewport={"width": 1280, "height": 720})
    page.set_default_timeout(120_000)  # a loaded machine: the first question may take a while
    page.goto(server.url)
    page.wait_for_selector("#choices button")
    page.keyboard.press("3")
    assert page.locator("#choices button[aria-pressed=true]").text_content() == "C. front"
    page.keyboard.press("Enter")
    assert answered.result(timeout=60).text == "C"
    page.close()


def test_dataset_text_is_shown_as_text_never_as_markup(browser, asked):
    server, answered = asked
    page = browser.new_page(viewport={"width": 820, "height": 1180})  # a tablet, upright
    page.goto(server.url)
    page.wait_for_selector("#choices button")
    assert page.locator("#choices button").nth(3).text_content() == "D. <img src=x>behind"
    assert page.locator("#choices img, #prompt b, #prompt img").count() == 0
    assert "<b>target</b>" in page.locator("#prompt").text_content()
    page.locator("#choices button").nth(1).click()
    page.locator("#submit").click()
    assert answered.result(timeout=60).text == "B"
    page.close()


def test_an_options_letter_chooses_it(browser, asked):
    server, answered = asked
    page = browser.new_page(viewport={"width": 1280, "height": 720})
    page.set_default_timeout(120_000)
    page.goto(server.url)
    page.wait_for_selector("#choices button")
    page.keyboard.press("d")
    page.keyboard.press("Enter")
    assert answered.result(timeout=60).text == "D"
    page.close()
