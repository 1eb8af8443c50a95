"""The page's server holds nothing for long and says each refusal in one line: a whole-request
deadline, a cap on connections, a 4xx for a body that is not text, and a busy port or a bad
annotator name refused before anything is served."""

from __future__ import annotations

import http.client
import json
import os
import select
import socket
import subprocess
import sys
import textwrap
import threading
import time

import pytest
from console_child import IMPORT

from povagent.annotate.answer_page import AnswerPage
from povagent.annotate.desk import AnswerDesk
from povagent.annotate.server import AnnotateServer

pytestmark = pytest.mark.timeout(120)

DEADLINE_S = 1.5
CAP = 8


@pytest.fixture
def served():
    """A server with a short deadline and a small cap, its log lines kept."""
    lines: list[str] = []
    srv = AnnotateServer(AnswerPage(AnswerDesk("alice"), wait_s=0.0), client_timeout=DEADLINE_S, max_connections=CAP, log=lines.append)
    srv.start()
    try:
        yield srv, lines
    finally:
        srv.close()


def post(server, body: bytes, path: str = "api/judge"):
    conn = http.client.HTTPConnection("127.0.0.1", server.port, timeout=30)
    try:
        conn.request("POST", f"/{server.token}/{path}", body=body,
                     headers={"Host": f"127.0.0.1:{server.port}", "X-Povagent-Token": server.token, "Content-Type": "application/json"})  # fmt: skip
        response = conn.getresponse()
        return response.status, response.read()
    finally:
        conn.close()


def _closed_by_server(sock: socket.socket) -> bool:
    """Whether the server ended the connection: sending one more byte fails, or the socket reads
    (end of file or a reset: the server never answers a request still arriving)."""
    try:
        sock.send(b"x")
    except OSError:
        return True
    ready, _, _ = select.select([sock], [], [], 0)
    return bool(ready)


def test_clients_trickling_a_byte_at_a_time_are_all_dropped_by_the_deadline(served):
    server, _ = served
    threads_before = threading.active_count()
    clients = []
    for _ in range(40):
        s = socket.create_connection(("127.0.0.1", server.port), timeout=5)
        s.sendall(f"POST /{server.token}/api/answer HTTP/1.1\r\nHost: 127.0.0.1:{server.port}\r\n".encode())
        clients.append(s)
    peak = threading.active_count() - threads_before
    start, open_ = time.monotonic(), set(range(len(clients)))
    while open_ and time.monotonic() - start < DEADLINE_S + 8:
        for i in list(open_):
            if _closed_by_server(clients[i]):  # each still-open client sends one more byte
                open_.discard(i)
        peak = max(peak, threading.active_count() - threads_before)
        time.sleep(0.2)
    took = time.monotonic() - start
    for s in clients:
        s.close()
    assert not open_, f"{len(open_)} trickling clients still connected after {took:.1f} s"
    assert took < DEADLINE_S + 5  # dropped at the deadline, not left to a per-read timeout
    assert peak <= CAP + 1  # at most CAP handler threads (one more: the moment a slot frees)


def test_the_server_answers_again_once_the_trickling_clients_are_dropped(served):
    server, _ = served
    holders = [socket.create_connection(("127.0.0.1", server.port), timeout=5) for _ in range(CAP * 2)]
    time.sleep(DEADLINE_S + 1.0)
    status, _ = post(server, b"{}", "api/answer")
    for s in holders:
        s.close()
    assert status == 422  # heard, and refused for what it said (no question open)


def test_a_judge_note_with_a_lone_surrogate_is_a_400_and_one_log_line(served):
    server, lines = served
    status, body = post(server, b'{"question": 0, "verdict": "success", "note": "\\ud800"}')
    assert status == 400 and b"not text" in body
    assert len(lines) == 1 and "400" in lines[0] and "\n" not in lines[0]


def test_a_malformed_request_line_is_a_4xx_and_one_log_line(served):
    server, lines = served
    with socket.create_connection(("127.0.0.1", server.port), timeout=10) as s:
        s.sendall(b"NOT A REQUEST\r\n\r\n")
        reply = s.recv(4096)
    assert reply.startswith(b"HTTP/1.") and b" 400 " in reply.split(b"\r\n")[0]
    assert len(lines) == 1 and lines[0].startswith("povagent annotate: refused")


def test_a_refusal_line_never_holds_the_token_or_the_path(served):
    server, lines = served
    post(server, b"[1]", "api/nothing")
    assert lines and all(server.token not in line and "api/nothing" not in line for line in lines)


def _study(folder, mini_root, annotator: str = "alice", strategy: object = "basic"):
    import yaml

    folder.mkdir()
    path = folder / "study.yaml"
    path.write_text(yaml.safe_dump({"dataset": {"path": str(mini_root)}, "backend": "human", "annotator": annotator, "strategy": strategy,
                                    "parser": "json", "scorers": ["official"], "output": str(folder / "out")}))  # fmt: skip
    return path


# One child runs the console script's ``main`` once per refused command line, each with its own
# argv and its own stdout and stderr files (file descriptors 1 and 2 pointed at them), so each
# command is still the real command in a process of povagent's own, for one interpreter start
# and one import of povagent instead of three. An exception escaping ``main`` is printed as the
# interpreter would print it (a traceback, exit status 1).
ANNOTATE_EACH = IMPORT + textwrap.dedent("""
    import json
    from povagent.cli import main

    cases, folder = json.loads(sys.argv[1]), sys.argv[2]
    codes = [run_as_console(main, ["povagent", "annotate", *args], f"{folder}/{n}.out", f"{folder}/{n}.err") for n, args in enumerate(cases)]
    print(json.dumps(codes))
""")


@pytest.fixture(scope="module")
def refused(tmp_path_factory, mini_root) -> dict[str, tuple[subprocess.CompletedProcess, int]]:
    """Each refused ``povagent annotate`` command line, run in one child while a port is held
    busy: name -> (what it returned and printed, the busy port)."""
    folder = tmp_path_factory.mktemp("refused")
    cases = {
        "busy port": (_study(folder / "busy", mini_root),),
        "annotator": (_study(folder / "annotator", mini_root, annotator="../../etc/x"),),
        "option": (_study(folder / "option", mini_root, strategy={"name": "basic", "options": {"no_such_option": 1}}),),
    }
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen(1)
        port = busy.getsockname()[1]
        argvs = [[str(cases["busy port"][0]), "--port", str(port)], [str(cases["annotator"][0])], [str(cases["option"][0])]]
        child = subprocess.run([sys.executable, "-c", ANNOTATE_EACH, json.dumps(argvs), str(folder)], capture_output=True, text=True,
                               timeout=90, env={**os.environ, "PYTHONUNBUFFERED": "1"})  # fmt: skip
    assert child.returncode == 0, child.stderr[-2000:]
    codes = json.loads(child.stdout.splitlines()[-1])
    return {
        name: (subprocess.CompletedProcess(argv, code, (folder / f"{n}.out").read_text(), (folder / f"{n}.err").read_text()), port)
        for n, (name, argv, code) in enumerate(zip(cases, argvs, codes))
    }


def test_annotate_on_a_busy_port_says_so_in_one_line(refused):
    done, port = refused["busy port"]
    assert done.returncode != 0 and "Traceback" not in done.stderr
    said = [line for line in done.stderr.splitlines() if line.strip()]
    assert len(said) == 1 and f"--port {port}" in said[0] and "another program" in said[0]
    assert "open http" not in done.stdout


def test_an_invalid_annotator_name_is_refused_before_any_address_is_printed(refused):
    done, _ = refused["annotator"]
    assert done.returncode != 0 and "Traceback" not in done.stderr
    assert "annotator" in done.stderr and "not a name" in done.stderr
    assert "http://" not in done.stdout + done.stderr  # no URL, no token was ever shown
    assert json.dumps("../../etc/x")[1:-1] in done.stderr


def test_a_component_option_that_is_refused_is_refused_before_any_address_is_printed(refused):
    done, _ = refused["option"]
    assert done.returncode != 0 and "Traceback" not in done.stderr and "no_such_option" in done.stderr
    assert "http://" not in done.stdout + done.stderr
