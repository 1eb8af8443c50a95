"""The page's server refuses what is not its own page's: no token, another origin or host, any other path."""

from __future__ import annotations

import http.client
import json

import pytest

from povagent.annotate.answer_page import AnswerPage
from povagent.annotate.desk import AnswerDesk
from povagent.annotate.server import AnnotateServer


@pytest.fixture(scope="module")
def server():
    srv = AnnotateServer(AnswerPage(AnswerDesk("alice"), wait_s=0.0), client_timeout=1.0)
    srv.start()
    try:
        yield srv
    finally:
        srv.close()


def request(server, method, path, headers=None, body=None):
    conn = http.client.HTTPConnection("127.0.0.1", server.port, timeout=30)
    try:
        conn.request(method, path, body=body, headers={"Host": f"127.0.0.1:{server.port}", **(headers or {})})
        response = conn.getresponse()
        return response.status, dict(response.getheaders()), response.read()
    finally:
        conn.close()


def test_it_listens_on_loopback_only(server):
    assert server.httpd.server_address[0] == "127.0.0.1"
    assert server.url == f"http://127.0.0.1:{server.port}/{server.token}/"


def test_the_page_below_its_token_is_served_with_a_strict_policy_and_no_cookie(server):
    status, headers, body = request(server, "GET", f"/{server.token}/")
    assert status == 200 and b"annotate.js" in body
    assert "default-src 'none'" in headers["Content-Security-Policy"] and "script-src 'self'" in headers["Content-Security-Policy"]
    assert headers["Referrer-Policy"] == "no-referrer"
    assert "Set-Cookie" not in headers  # a cookie would go to every port of 127.0.0.1


def test_the_page_names_no_other_host_and_no_path_outside_its_token(server):
    for path in ("", "annotate.js", "annotate.css"):
        _, _, body = request(server, "GET", f"/{server.token}/{path}")
        assert b"http://" not in body and b"https://" not in body and b"//cdn" not in body, path
        assert b"innerHTML" not in body, path
        assert not any(f'{q}/{name}'.encode() in body for q in "\"'" for name in ("api", "annotate")), path  # relative: below the token


@pytest.mark.parametrize("path", ["/", "/api/state", "/annotate.js", "/api/image/1/0", "/?token=x"])
def test_a_request_without_the_token_is_refused(server, path):
    status, _, body = request(server, "GET", path)
    assert status == 401 and b"annotate" not in body


def test_a_wrong_token_is_refused(server):
    status, _, _ = request(server, "GET", f"/{server.token[:-1]}x/api/state")
    assert status == 401
    status, _, _ = request(server, "GET", "/api/state", {"X-Povagent-Token": server.token})  # the header alone opens nothing
    assert status == 401


def test_the_token_in_the_path_lets_the_pages_images_and_state_load(server):
    status, _, _ = request(server, "GET", f"/{server.token}/api/state")
    assert status == 200


def test_an_answer_without_the_token_header_is_refused_even_below_the_token(server):
    status, _, _ = request(server, "POST", f"/{server.token}/api/answer", {"Content-Type": "application/json"}, b"{}")
    assert status == 401


def test_a_request_from_another_origin_is_refused(server):
    status, _, _ = request(server, "POST", f"/{server.token}/api/answer", {"X-Povagent-Token": server.token, "Origin": "http://evil.example"}, b"{}")
    assert status == 403
    status, _, _ = request(server, "GET", f"/{server.token}/api/state", {"Sec-Fetch-Site": "cross-site"})
    assert status == 403


def test_a_request_from_another_local_port_is_refused(server):
    status, _, _ = request(server, "GET", f"/{server.token}/api/state", {"Origin": f"http://127.0.0.1:{server.port + 1}"})
    assert status == 403
    status, _, _ = request(server, "GET", f"/{server.token}/api/state", {"Sec-Fetch-Site": "same-site"})
    assert status == 403


def test_a_request_for_another_host_name_is_refused(server):
    # a DNS-rebound name reaching the loopback port
    status, _, _ = request(server, "GET", f"/{server.token}/", {"Host": f"evil.example:{server.port}"})
    assert status == 403


@pytest.mark.parametrize("path", [
    "/../../etc/passwd", "/%2e%2e/%2e%2e/etc/passwd", "/api/image/1/../../../etc/passwd", "/meta.json",
    "/assets/annotate.js", "/api/image/-1/0", "/api/image/1/0", "/TOKEN/../../etc/passwd",
])
def test_a_path_outside_the_page_is_not_found(server, path):
    status, _, body = request(server, "GET", f"/{server.token}{path}".replace("TOKEN", server.token), {"X-Povagent-Token": server.token})
    assert status == 404
    assert b"root:" not in body


def test_an_oversized_answer_is_refused_unread(server):
    status, _, _ = request(server, "POST", f"/{server.token}/api/answer", {"X-Povagent-Token": server.token, "Content-Length": str(10**9)}, b"")
    assert status == 413


def test_an_answer_to_no_open_question_is_refused_with_its_reason(server):
    status, _, body = request(server, "POST", f"/{server.token}/api/answer", {"X-Povagent-Token": server.token},
                              json.dumps({"question": 7, "choice": "A"}).encode())  # fmt: skip
    assert status == 422 and b"not open" in body


def test_a_body_promised_and_never_sent_is_given_up_on(server):
    import socket
    import time

    with socket.create_connection(("127.0.0.1", server.port), timeout=30) as sock:
        sock.sendall(f"POST /{server.token}/api/answer HTTP/1.1\r\nHost: 127.0.0.1:{server.port}\r\nX-Povagent-Token: {server.token}\r\n"
                     "Content-Length: 100\r\n\r\n".encode())
        t0 = time.monotonic()
        assert sock.recv(1024) == b""  # the server closed the connection instead of waiting on
        assert time.monotonic() - t0 < 20


@pytest.mark.parametrize("body", [{"question": 1, "choice": ["A"]}, {"question": True}, [1, 2], "x"])
def test_an_answer_of_the_wrong_shape_is_refused_not_a_crash(server, body):
    status, _, _ = request(server, "POST", f"/{server.token}/api/answer", {"X-Povagent-Token": server.token}, json.dumps(body).encode())
    assert status in (400, 422)
