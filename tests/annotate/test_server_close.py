"""Closing the page's server at the end of a session: the open page hears that it is over."""

from __future__ import annotations

import http.client
import json
import threading
import time

import pytest

from povagent.annotate.answer_page import AnswerPage
from povagent.annotate.desk import AnswerDesk
from povagent.annotate.server import AnnotateServer

pytestmark = pytest.mark.timeout(60)


def get_state(server: AnnotateServer) -> tuple[int, dict]:
    conn = http.client.HTTPConnection("127.0.0.1", server.port, timeout=10)
    try:
        conn.request("GET", f"/{server.token}/api/state", headers={"Host": f"127.0.0.1:{server.port}", "X-Povagent-Token": server.token})
        response = conn.getresponse()
        return response.status, json.loads(response.read())
    finally:
        conn.close()


def closing(server: AnnotateServer, **kwargs) -> tuple[threading.Thread, list[float]]:
    """server.close(**kwargs) in a thread, as the command's last step; how long it took."""
    took: list[float] = []

    def close() -> None:
        t0 = time.monotonic()
        server.close(**kwargs)
        took.append(time.monotonic() - t0)

    thread = threading.Thread(target=close)
    thread.start()
    return thread, took


def test_a_page_polling_after_the_session_ended_is_told_it_is_over():
    """The page polls every fraction of a second: its poll after the last answer arrives when
    the session has already ended, and finds the server still there to say so."""
    desk = AnswerDesk("alice")
    page = AnswerPage(desk, wait_s=0.0)
    server = AnnotateServer(page, 0)
    server.start()
    desk.finish()
    thread, took = closing(server, grace_s=20.0, told=page.told_finished)
    time.sleep(0.5)
    status, state = get_state(server)
    thread.join(timeout=20)
    assert (status, state["finished"], state["question"]) == (200, True, None)
    assert not thread.is_alive() and took[0] < 10.0  # closed once told, not at the end of the grace


def test_closing_waits_no_longer_than_the_grace_when_no_page_polls():
    desk = AnswerDesk("alice")
    page = AnswerPage(desk, wait_s=0.0)
    server = AnnotateServer(page, 0)
    server.start()
    desk.finish()
    thread, took = closing(server, grace_s=0.3, told=page.told_finished)
    thread.join(timeout=20)
    assert not thread.is_alive() and took[0] < 5.0
    with pytest.raises(OSError):
        get_state(server)
