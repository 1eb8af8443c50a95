"""What ``--cluster`` connects to: only a Dask scheduler gets a client, anything else is one line
within the stated wait; ``local:N`` listens on 127.0.0.1 only. Real servers on loopback (a port
that accepts and never answers, a web server, one answering other bytes), a real LocalCluster."""

from __future__ import annotations

import http.server
import os
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from povagent.cluster.client import CONNECT_TIMEOUT_ENV, CONNECT_TIMEOUT_S, cluster_client, connect_timeout
from povagent.errors import ClusterError

pytest.importorskip("distributed", reason="the cluster tests need the test extra (distributed)")

#: The wait the tests ask for instead of the default 20 s.
SHORT_S = 1.5


class _Server:
    """A TCP server on 127.0.0.1 whose every connection is handed to ``serve`` in a thread."""

    def __init__(self, serve: Callable[[socket.socket], None]) -> None:
        self.sock = socket.create_server(("127.0.0.1", 0))
        self.port = self.sock.getsockname()[1]
        self._serve = serve
        self._held: list[socket.socket] = []
        threading.Thread(target=self._accept, daemon=True).start()

    def _accept(self) -> None:
        while True:
            try:
                conn, _ = self.sock.accept()
            except OSError:
                return
            self._held.append(conn)
            threading.Thread(target=self._serve, args=(conn,), daemon=True).start()

    def close(self) -> None:
        self.sock.close()
        for conn in self._held:
            conn.close()


def _silent(conn: socket.socket) -> None:
    """Accept and never answer (the connection is held open until the test ends)."""


def _other_bytes(conn: socket.socket) -> None:
    try:
        conn.sendall(b"\x00" * 8 + b"these are not the bytes of a Dask handshake " * 50)
        conn.recv(65536)
    except OSError:
        pass
    conn.close()


@pytest.fixture
def web_server() -> Iterator[str]:
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), http.server.SimpleHTTPRequestHandler)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    try:
        yield f"tcp://127.0.0.1:{server.server_address[1]}"
    finally:
        server.shutdown()
        server.server_close()


@pytest.fixture
def tcp_server() -> Iterator[Callable[[Callable[[socket.socket], None]], str]]:
    started: list[_Server] = []

    def start(serve: Callable[[socket.socket], None]) -> str:
        started.append(_Server(serve))
        return f"tcp://127.0.0.1:{started[-1].port}"

    try:
        yield start
    finally:
        for server in started:
            server.close()


def _refused_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


def test_the_wait_for_a_scheduler_is_20_s_unless_the_environment_says_otherwise(monkeypatch) -> None:
    assert CONNECT_TIMEOUT_S == 20
    monkeypatch.delenv(CONNECT_TIMEOUT_ENV, raising=False)
    assert connect_timeout() == 20
    monkeypatch.setenv(CONNECT_TIMEOUT_ENV, "0.5")
    assert connect_timeout() == 0.5
    for bad in ("soon", "-1", "0", "inf", "nan"):
        monkeypatch.setenv(CONNECT_TIMEOUT_ENV, bad)
        assert connect_timeout() == 20, bad


@pytest.mark.parametrize("peer", ["accepts-and-never-answers", "a-web-server", "other-bytes", "nothing-listening", "tls", "ucx", "inproc"])
def test_an_address_that_is_no_scheduler_is_one_line_within_the_wait(peer, tcp_server, web_server, monkeypatch) -> None:
    address = {
        "accepts-and-never-answers": lambda: tcp_server(_silent),
        "a-web-server": lambda: web_server,
        "other-bytes": lambda: tcp_server(_other_bytes),
        "nothing-listening": lambda: f"tcp://127.0.0.1:{_refused_port()}",
        "tls": lambda: tcp_server(_silent).replace("tcp://", "tls://"),
        "ucx": lambda: f"ucx://127.0.0.1:{_refused_port()}",
        "inproc": lambda: "inproc://nobody",
    }[peer]()
    monkeypatch.setenv(CONNECT_TIMEOUT_ENV, str(SHORT_S))
    t0 = time.monotonic()
    with pytest.raises(ClusterError) as info, cluster_client(address):
        pytest.fail("a client was made for something that is not a scheduler")
    took = time.monotonic() - t0
    message = str(info.value)
    assert "\n" not in message and address in message, message
    assert took < SHORT_S + 3, f"{peer}: {took:.1f} s"


def test_the_command_line_says_it_in_one_line_and_exits_non_zero(tcp_server, tmp_path: Path) -> None:
    address = tcp_server(_silent)
    env = {**os.environ, CONNECT_TIMEOUT_ENV: str(SHORT_S)}
    t0 = time.monotonic()
    proc = subprocess.run(
        [sys.executable, "-m", "povagent.cli", "generate", "--out", str(tmp_path / "d"), "--houses", "1", "--frames", "1", "--cluster", address],
        capture_output=True, text=True, env=env, timeout=120,
    )  # fmt: skip
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.strip().splitlines() == [f"error: no Dask scheduler answered at {address} within {SHORT_S:g} s: is it the scheduler's address and port?"]
    assert time.monotonic() - t0 < SHORT_S + 30  # the interpreter's start-up on a loaded machine, plus the wait


def _listening(pids: list[int]) -> list[tuple[int, str, int]]:
    """``(pid, address, port)`` of every TCP socket the processes ``pids`` listen on (psutil when
    installed; else /proc/net/tcp and tcp6, matched to the processes' socket inodes)."""
    try:
        import psutil
    except ImportError:
        return _listening_from_proc(pids)
    found = []
    for pid in pids:
        try:
            conns = psutil.Process(pid).net_connections(kind="inet")
        except psutil.NoSuchProcess:
            continue
        found += [(pid, c.laddr.ip, c.laddr.port) for c in conns if c.status == psutil.CONN_LISTEN]
    return found


def _listening_from_proc(pids: list[int]) -> list[tuple[int, str, int]]:
    inodes: dict[str, int] = {}
    for pid in pids:
        try:
            for fd in os.listdir(f"/proc/{pid}/fd"):
                target = os.readlink(f"/proc/{pid}/fd/{fd}")
                if target.startswith("socket:["):
                    inodes[target[8:-1]] = pid
        except OSError:
            continue
    found = []
    for table in ("/proc/net/tcp", "/proc/net/tcp6"):
        with open(table, encoding="ascii") as fh:
            for line in fh.readlines()[1:]:
                fields = line.split()
                local, state, inode = fields[1], fields[3], fields[9]
                if state == "0A" and inode in inodes:  # 0A: LISTEN
                    raw, port = local.split(":")
                    found.append((inodes[inode], _proc_address(raw), int(port, 16)))
    return found


def _proc_address(raw: str) -> str:
    """/proc/net's hex address (little-endian 32-bit words) as text."""
    data = b"".join(bytes.fromhex(raw[i : i + 8])[::-1] for i in range(0, len(raw), 8))
    return socket.inet_ntop(socket.AF_INET if len(data) == 4 else socket.AF_INET6, data)


def _children(pid: int) -> list[int]:
    found: list[int] = []
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                with open(f"/proc/{entry}/stat", encoding="ascii", errors="replace") as fh:
                    parent = int(fh.read().rsplit(")", 1)[1].split()[1])
            except (OSError, ValueError, IndexError):
                continue
            if parent == pid:
                found += [int(entry), *_children(int(entry))]
    return found


def test_a_local_cluster_listens_on_the_loopback_interface_only() -> None:
    before = set(_listening([os.getpid()]))
    with cluster_client("local:1") as client:
        assert client is not None
        pids = [os.getpid(), *_children(os.getpid())]
        opened = [s for s in _listening(pids) if s not in before]
    assert len(pids) >= 2 and opened, "the cluster's processes and sockets were found"
    wide = [s for s in opened if s[1] in ("0.0.0.0", "::")]
    assert not wide, f"listening on every interface: {wide}"
    assert all(s[1] == "127.0.0.1" for s in opened), opened


def test_the_proc_reading_agrees_with_a_socket_of_known_address() -> None:
    with socket.create_server(("127.0.0.1", 0)) as loop_sock, socket.create_server(("0.0.0.0", 0)) as wide_sock:
        found = _listening_from_proc([os.getpid()])
        assert (os.getpid(), "127.0.0.1", loop_sock.getsockname()[1]) in found
        assert (os.getpid(), "0.0.0.0", wide_sock.getsockname()[1]) in found
