"""The token is bound to its server, in a real browser: two sessions side by side in one browser
both work, and a page served from another local port never receives the token nor answers."""

from __future__ import annotations

import asyncio
import concurrent.futures
import dataclasses
import threading
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer

import pytest

from povagent.annotate.answer_page import AnswerPage
from povagent.annotate.desk import AnswerDesk, serving
from povagent.annotate.server import AnnotateServer
from povagent.answers.choice_question import ChoiceQuestion
from povagent.exchange.images import ImageStore
from povagent.plugins import get_plugin_host

pytestmark = [pytest.mark.slow, pytest.mark.timeout(300)]

QUESTION = ChoiceQuestion(question="Where is the target?", options=(("A", "left"), ("B", "right"), ("C", "front")), gold="C")


class Session:
    """A served desk with one multiple-choice question waiting for a person's answer."""

    def __init__(self, instance, annotator: str) -> None:
        host = get_plugin_host()
        images = ImageStore()
        request = host.strategy("choice", {}).build(instance, images)
        self.desk = AnswerDesk(annotator, total=1)
        self.server = AnnotateServer(AnswerPage(self.desk, wait_s=1.0), log=lambda line: None)
        self.server.start()
        self.answered: concurrent.futures.Future = concurrent.futures.Future()

        async def person() -> None:
            try:
                with serving(self.desk):
                    response = await host.backend("human", {"annotator": annotator}).complete(request, images)
            except asyncio.CancelledError:
                return  # the session closed before an answer came (the desk cancels the question)
            self.desk.row_saved()
            self.desk.finish()
            self.answered.set_result(response)

        self.person = threading.Thread(target=lambda: asyncio.run(person()), daemon=True)
        self.person.start()

    def close(self) -> None:
        self.desk.finish()
        self.server.close()
        # the person's thread leaves the desk it served (a desk left served would be the one a
        # later run's human backend answers through)
        self.person.join(timeout=30)
        assert not self.person.is_alive()


class Neighbour:
    """Another local server (any program on 127.0.0.1): it records every request it receives,
    and its page tries to reach the annotation server from its own port."""

    def __init__(self, target_port: int) -> None:
        self.seen: list[bytes] = []
        neighbour = self
        page = f"""<!doctype html><title>neighbour</title><body>
<img id="a" src="http://127.0.0.1:{target_port}/api/image/1/0">
<img id="b" src="/probe.png">
<script>
  const tries = [
    fetch("http://127.0.0.1:{target_port}/api/state", {{credentials: "include", mode: "no-cors"}}),
    fetch("http://127.0.0.1:{target_port}/api/answer", {{method: "POST", credentials: "include", mode: "no-cors",
          headers: {{"Content-Type": "text/plain"}}, body: JSON.stringify({{question: 1, choice: "A"}})}}),
    fetch("/probe", {{credentials: "include"}}),
  ];
  Promise.allSettled(tries).then(() => {{ document.title = "tried"; }});
</script></body>""".encode()

        class Handler(BaseHTTPRequestHandler):
            def log_message(self, *args) -> None:
                pass

            def do_GET(self) -> None:
                neighbour.seen.append(f"{self.requestline}\n{self.headers}".encode())
                body = page if self.path == "/" else b""
                self.send_response(200 if self.path == "/" else 404)
                self.send_header("Content-Type", "text/html")
                self.send_header("Content-Length", str(len(body)))
                self.end_headers()
                self.wfile.write(body)

        self.httpd = ThreadingHTTPServer(("127.0.0.1", 0), Handler)
        self.url = f"http://127.0.0.1:{self.httpd.server_address[1]}/"
        threading.Thread(target=self.httpd.serve_forever, daemon=True).start()

    def close(self) -> None:
        self.httpd.shutdown()
        self.httpd.server_close()


@pytest.fixture
def two_sessions(mini_dataset):
    base = next(i for i in mini_dataset.instances() if not i.condition.uses_exploration_frames)
    instance = dataclasses.replace(base, question=QUESTION)
    sessions = [Session(instance, "alice"), Session(instance, "bob")]
    try:
        yield sessions
    finally:
        for s in sessions:
            s.close()


def _image_shown(page) -> None:
    page.wait_for_function("() => { const v = document.getElementById('view'); return v && v.complete && v.naturalWidth > 0; }")


def test_two_sessions_side_by_side_in_one_browser_both_show_their_images_and_take_answers(browser, two_sessions):
    context = browser.new_context(viewport={"width": 1280, "height": 720})
    try:
        first, second = context.new_page(), context.new_page()
        for page, session in ((first, two_sessions[0]), (second, two_sessions[1])):
            page.set_default_timeout(120_000)
            page.goto(session.server.url)
            page.wait_for_selector("#choices button")
        for page in (first, second):  # the first tab's images still load once the second is open
            page.evaluate("() => { const v = document.getElementById('view'); v.src = v.src.split('?')[0] + '?again'; }")
            _image_shown(page)
        for page, key in ((first, "1"), (second, "3")):
            page.keyboard.press(key)
            page.keyboard.press("Enter")
        assert two_sessions[0].answered.result(timeout=60).text == "A"
        assert two_sessions[1].answered.result(timeout=60).text == "C"
    finally:
        context.close()


def test_a_page_from_another_local_port_never_receives_the_token_nor_answers(browser, two_sessions):
    session = two_sessions[0]
    neighbour = Neighbour(session.server.port)
    context = browser.new_context()
    try:
        page = context.new_page()
        page.set_default_timeout(120_000)
        page.goto(session.server.url)
        page.wait_for_selector("#choices button")
        _image_shown(page)
        other = context.new_page()
        other.goto(neighbour.url)
        other.wait_for_function("() => document.title === 'tried'")
        other.reload()  # a second visit: whatever the browser keeps for 127.0.0.1 goes along
        other.wait_for_function("() => document.title === 'tried'")
        seen = b"\n".join(neighbour.seen)
        assert b"GET / " in seen and b"/probe" in seen  # the neighbour's page did run and call home
        assert session.server.token.encode() not in seen
        assert not session.answered.done()  # nothing the neighbour's page sent was taken as an answer
    finally:
        context.close()
        neighbour.close()
