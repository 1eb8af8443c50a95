"""A client that hangs up mid-request leaves no traceback on stderr; a real handler error
still does (socketserver's report), for every server povagent starts."""

from __future__ import annotations

import json
import socket
import struct
import threading
import time

import pytest

from povagent.testing.loopback_server import LoopbackServer, Reply

BODY = json.dumps({"model": "m", "messages": [{"role": "user", "content": "hi"}]}).encode()


def post_and(server: LoopbackServer, *, hang_up: bool) -> bytes:
    """POST a chat request; with ``hang_up`` reset the connection at once, else read the answer."""
    sock = socket.create_connection(("127.0.0.1", server.port), timeout=10)
    sock.sendall(b"POST /v1/chat/completions HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n"
                 + f"Content-Length: {len(BODY)}\r\n\r\n".encode() + BODY)  # fmt: skip
    if hang_up:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))  # close with a reset
        sock.close()
        return b""
    try:
        return sock.recv(65536)
    finally:
        sock.close()


def wait_for_handlers(before: set[threading.Thread], timeout: float = 10.0) -> None:
    """Until every request thread started since ``before`` (this test's server's) has finished."""
    end = time.monotonic() + timeout
    while time.monotonic() < end and any("process_request_thread" in t.name for t in set(threading.enumerate()) - before):
        time.sleep(0.02)


def test_a_client_hanging_up_before_the_answer_prints_nothing(capfd):
    before = set(threading.enumerate())
    with LoopbackServer(reply=Reply('{"x": 1, "y": 2}', delay_s=0.4), max_lifetime_s=30) as server:
        for _ in range(3):
            post_and(server, hang_up=True)
        while server.request_count < 3:
            time.sleep(0.02)
        time.sleep(0.5)  # the delayed answers are written to the closed connections
        wait_for_handlers(before)
        assert server.request_count == 3
    err = capfd.readouterr().err
    assert "Exception occurred" not in err and "Traceback" not in err, err


def test_a_real_error_in_a_handler_is_still_printed(capfd):
    def broken(_request):
        raise RuntimeError("the reply function is broken")

    before = set(threading.enumerate())
    with LoopbackServer(reply=broken, max_lifetime_s=30) as server:
        assert post_and(server, hang_up=False) == b""  # the connection is closed, no answer
        wait_for_handlers(before)
    err = capfd.readouterr().err
    assert "Exception occurred during processing of request" in err
    assert "RuntimeError: the reply function is broken" in err


@pytest.mark.parametrize("error", [BrokenPipeError, ConnectionResetError, ConnectionAbortedError, TimeoutError])
def test_every_kind_of_disconnect_is_quiet_and_others_are_not(error, capfd):
    from povagent.exchange.disconnects import QuietDisconnects

    class Base:
        def handle_error(self, request, client_address):
            print("Exception occurred during processing of request from", client_address, file=__import__("sys").stderr)

    class Server(QuietDisconnects, Base):
        pass

    for raised, printed in ((error("gone"), False), (ValueError("bad"), True)):
        try:
            raise raised
        except Exception:
            Server().handle_error(None, ("127.0.0.1", 1))
        assert ("Exception occurred" in capfd.readouterr().err) is printed, raised
