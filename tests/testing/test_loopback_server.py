"""The loopback OpenAI-compatible server (povagent/testing/loopback_server.py), driven with urllib."""

from __future__ import annotations

import hashlib
import http.client
import json
import threading
import time
import urllib.error
import urllib.request

import pytest

from povagent.testing.loopback_server import Fault, LoopbackServer, Reply

pytestmark = pytest.mark.timeout(20)

BODY = {"model": "m", "messages": [{"role": "user", "content": [{"type": "text", "text": "hi"}]}], "max_tokens": 9}


def post(server: LoopbackServer, body=BODY, timeout: float = 5.0):
    req = urllib.request.Request(
        server.url + "/chat/completions",
        data=json.dumps(body).encode(),
        headers={"Content-Type": "application/json", "Authorization": "Bearer k"},
    )
    with urllib.request.urlopen(req, timeout=timeout) as resp:
        return resp.status, dict(resp.headers), json.loads(resp.read())


def test_answers_an_openai_chat_completion():
    with LoopbackServer(reply="hello") as server:
        status, _, doc = post(server)
    assert status == 200
    assert doc["choices"][0]["message"] == {"role": "assistant", "content": "hello"}
    assert doc["usage"]["total_tokens"] == doc["usage"]["prompt_tokens"] + doc["usage"]["completion_tokens"]


def test_listens_on_loopback_with_an_ephemeral_port():
    with LoopbackServer() as server:
        assert server.url.startswith("http://127.0.0.1:") and server.port > 0


def test_records_every_request_body_and_headers():
    with LoopbackServer() as server:
        post(server)
        post(server, {**BODY, "temperature": 0.5})
    assert [r.body.get("temperature") for r in server.requests] == [None, 0.5]
    assert server.requests[0].headers["authorization"] == "Bearer k"
    assert server.requests[0].user_parts() == [{"type": "text", "text": "hi"}]


def test_counts_each_body_by_the_sha256_of_its_bytes():
    same = json.dumps(BODY).encode()
    with LoopbackServer(count_bodies=True) as server:
        post(server)
        post(server)
        post(server, {**BODY, "max_tokens": 10})
    assert server.body_digests[hashlib.sha256(same).hexdigest()] == 2
    assert sorted(server.body_digests.values()) == [1, 2]


def test_reply_callable_sees_the_request():
    with LoopbackServer(reply=lambda r: f"max={r.body['max_tokens']}") as server:
        _, _, doc = post(server)
    assert doc["choices"][0]["message"]["content"] == "max=9"


def test_scripted_outcomes_come_first_then_the_reply():
    with LoopbackServer(reply="default") as server:
        server.script("one", Reply("two", completion_tokens=2))
        texts = [post(server)[2]["choices"][0]["message"]["content"] for _ in range(3)]
    assert texts == ["one", "two", "default"]


def test_injects_429_with_retry_after():
    with LoopbackServer() as server:
        server.script(Fault(429, retry_after=3))
        with pytest.raises(urllib.error.HTTPError) as err:
            post(server)
    assert err.value.code == 429 and err.value.headers["Retry-After"] == "3"
    assert json.loads(err.value.read())["error"]["type"] == "rate_limit_error"


@pytest.mark.parametrize("status", [400, 401, 500])
def test_injects_status_codes(status):
    with LoopbackServer() as server:
        server.script(Fault(status))
        with pytest.raises(urllib.error.HTTPError) as err:
            post(server)
    assert err.value.code == status


def test_dropped_connection_sends_no_response():
    with LoopbackServer() as server:
        server.script(Fault(drop=True))
        with pytest.raises((http.client.RemoteDisconnected, ConnectionError, urllib.error.URLError)):
            post(server)


def test_delay_holds_the_answer_back():
    with LoopbackServer() as server:
        server.script(Reply("slow", delay_s=0.3))
        started = time.monotonic()
        post(server)
    assert time.monotonic() - started >= 0.3


def test_stop_cuts_a_pending_delay_short():
    server = LoopbackServer().start()
    server.script(Fault(delay_s=30, status=500))
    errors: list[BaseException] = []

    def call():
        try:
            post(server, timeout=10)
        except BaseException as exc:  # the test wants whatever the client saw
            errors.append(exc)

    t = threading.Thread(target=call)
    t.start()
    time.sleep(0.2)
    started = time.monotonic()
    server.stop()
    t.join(5)
    assert not t.is_alive() and time.monotonic() - started < 5 and errors


def test_stops_by_itself_after_its_lifetime():
    server = LoopbackServer(max_lifetime_s=0.3).start()
    time.sleep(0.8)
    with pytest.raises((urllib.error.URLError, ConnectionError)):
        post(server, timeout=2)


def test_unknown_path_is_404():
    with LoopbackServer() as server:
        req = urllib.request.Request(server.url + "/embeddings", data=b"{}", headers={"Content-Type": "application/json"})
        with pytest.raises(urllib.error.HTTPError) as err:
            urllib.request.urlopen(req, timeout=5)
    assert err.value.code == 404
