"""The read-only static image server (povagent/exchange/image_server.py).

It serves only files it was told about, by content hash, only from inside its roots (symlinks
resolved, when published and when served), refuses every other path and method, is bounded,
and stops when told.
"""

from __future__ import annotations

import hashlib
import http.client
import os
import socket
import time
import urllib.error
import urllib.request
from pathlib import Path

import pytest

from povagent.config.addresses import parse_bind
from povagent.exchange.image_server import ImageReferenceError, StaticImageServer

pytestmark = pytest.mark.timeout(20)

PNG = b"\x89PNG\r\n\x1a\n" + b"frame bytes " * 50


def sha(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


@pytest.fixture
def dataset(tmp_path) -> Path:
    root = tmp_path / "povbench"
    (root / "artifacts" / "house").mkdir(parents=True)
    (root / "artifacts" / "house" / "frame_000.png").write_bytes(PNG)
    return root


@pytest.fixture
def outside(tmp_path) -> Path:
    secret = tmp_path / "secret"
    secret.mkdir()
    (secret / "key.png").write_bytes(b"not for the model server")
    return secret / "key.png"


@pytest.fixture
def server(dataset):
    with StaticImageServer([dataset], bind="127.0.0.1:0") as s:
        yield s


def get(url: str, method: str = "GET") -> tuple[int, bytes, dict[str, str]]:
    req = urllib.request.Request(url, method=method)
    try:
        with urllib.request.urlopen(req, timeout=5) as resp:
            return resp.status, resp.read(), dict(resp.headers)
    except urllib.error.HTTPError as exc:
        return exc.code, exc.read(), dict(exc.headers)


def raw_get(server: StaticImageServer, path: str) -> int:
    """A GET with the path exactly as given (urllib would normalize ``..``)."""
    conn = http.client.HTTPConnection("127.0.0.1", server.port, timeout=5)
    try:
        conn.request("GET", path)
        return conn.getresponse().status
    finally:
        conn.close()


def test_a_published_file_is_served_under_its_hash(server, dataset):
    url = server.publish(dataset / "artifacts" / "house" / "frame_000.png", sha(PNG))
    assert url == f"http://127.0.0.1:{server.port}/{sha(PNG)}.png"
    status, body, headers = get(url)
    assert (status, body, headers["Content-Type"]) == (200, PNG, "image/png")
    assert server.served == 1


def test_head_answers_the_headers_without_the_body(server, dataset):
    url = server.publish(dataset / "artifacts" / "house" / "frame_000.png", sha(PNG))
    status, body, headers = get(url, method="HEAD")
    assert (status, body, int(headers["Content-Length"])) == (200, b"", len(PNG))


def test_public_url_is_the_base_of_the_urls_handed_out(dataset):
    with StaticImageServer([dataset], bind="127.0.0.1:0", public_url="http://gpu-box:8765/") as s:
        url = s.publish(dataset / "artifacts" / "house" / "frame_000.png", sha(PNG))
    assert url == f"http://gpu-box:8765/{sha(PNG)}.png"


def test_a_hash_never_published_is_not_found(server):
    assert get(f"http://127.0.0.1:{server.port}/{sha(b'other')}.png")[0] == 404


@pytest.mark.parametrize(
    "path",
    [
        "/artifacts/house/frame_000.png",  # a dataset path, not a hash
        "/../secret/key.png",
        "/%2e%2e/secret/key.png",
        "/" + "0" * 64 + ".png/../../etc/passwd",
        "/",
    ],
)
def test_file_system_paths_in_urls_are_never_followed(server, dataset, path):
    server.publish(dataset / "artifacts" / "house" / "frame_000.png", sha(PNG))
    assert raw_get(server, path) == 404


def test_publishing_a_file_outside_the_roots_is_refused(server, outside):
    with pytest.raises(ImageReferenceError, match="outside the folders served"):
        server.publish(outside, sha(outside.read_bytes()))
    assert server.published == 0


def test_a_symlink_out_of_the_dataset_is_refused(server, dataset, outside):
    link = dataset / "artifacts" / "house" / "frame_001.png"
    link.symlink_to(outside)
    with pytest.raises(ImageReferenceError, match="outside"):
        server.publish(link, sha(outside.read_bytes()))


def test_a_symlink_within_the_dataset_is_served(server, dataset):
    link = dataset / "artifacts" / "house" / "alias.png"
    link.symlink_to(dataset / "artifacts" / "house" / "frame_000.png")
    url = server.publish(link, sha(PNG))
    assert get(url)[:2] == (200, PNG)


def test_a_file_swapped_for_a_symlink_out_after_publishing_is_refused(server, dataset, outside):
    frame = dataset / "artifacts" / "house" / "frame_000.png"
    url = server.publish(frame, sha(PNG))
    frame.unlink()
    frame.symlink_to(outside)
    status, body, _ = get(url)
    assert status == 403 and b"not for the model server" not in body
    assert server.refused == 1


def test_a_directory_is_not_served(server, dataset):
    with pytest.raises(ImageReferenceError, match="not a regular file"):
        server.publish(dataset / "artifacts", sha(b"dir"))


def test_writes_are_refused(server, dataset):
    url = server.publish(dataset / "artifacts" / "house" / "frame_000.png", sha(PNG))
    req = urllib.request.Request(url, data=b"overwrite", method="PUT")
    with pytest.raises(urllib.error.HTTPError) as err:
        urllib.request.urlopen(req, timeout=5)
    assert err.value.code == 405
    assert (dataset / "artifacts" / "house" / "frame_000.png").read_bytes() == PNG


def test_connections_beyond_the_bound_are_told_503(dataset):
    with StaticImageServer([dataset], bind="127.0.0.1:0", max_connections=1) as s:
        url = s.publish(dataset / "artifacts" / "house" / "frame_000.png", sha(PNG))
        s._connections.acquire()  # one connection being served
        try:
            assert get(url)[0] == 503
        finally:
            s._connections.release()
        assert get(url)[0] == 200


def test_after_stop_nothing_listens(dataset):
    s = StaticImageServer([dataset], bind="127.0.0.1:0").start()
    port = s.port
    s.stop()
    s.stop()  # twice is harmless
    with pytest.raises(OSError):
        socket.create_connection(("127.0.0.1", port), timeout=1)


def test_binds_the_address_asked_for(dataset):
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    with StaticImageServer([dataset], bind=f"127.0.0.1:{port}") as s:
        assert s.port == port and s.base_url == f"http://127.0.0.1:{port}"


def test_a_taken_port_is_an_os_error(dataset):
    with StaticImageServer([dataset], bind="127.0.0.1:0") as first, pytest.raises(OSError):
        StaticImageServer([dataset], bind=f"127.0.0.1:{first.port}").start()


@pytest.mark.parametrize(
    "bind, expected",
    [("127.0.0.1:8765", ("127.0.0.1", 8765)), ("[::1]:80", ("::1", 80)), ("0.0.0.0:0", ("0.0.0.0", 0))],
)
def test_parse_bind_reads_host_and_port(bind, expected):
    assert parse_bind(bind) == expected


@pytest.mark.parametrize("bind", ["8765", ":8765", "host:http", "host:70000"])
def test_parse_bind_refuses_what_is_not_host_port(bind):
    with pytest.raises(ValueError, match="bind"):
        parse_bind(bind)


def test_a_hash_that_is_not_a_digest_is_refused(server, dataset):
    with pytest.raises(ImageReferenceError, match="SHA-256"):
        server.publish(dataset / "artifacts" / "house" / "frame_000.png", "../../etc/passwd")


def test_no_root_is_an_error():
    with pytest.raises(ValueError, match="root"):
        StaticImageServer([])


def test_served_roots_are_resolved_so_a_symlinked_dataset_folder_works(tmp_path, dataset):
    alias = tmp_path / "alias"
    os.symlink(dataset, alias)
    with StaticImageServer([alias], bind="127.0.0.1:0") as s:
        url = s.publish(alias / "artifacts" / "house" / "frame_000.png", sha(PNG))
        assert get(url)[:2] == (200, PNG)


def _wait_until(condition, seconds: float = 10) -> None:
    deadline = time.monotonic() + seconds
    while not condition():
        assert time.monotonic() < deadline, "timed out"
        time.sleep(0.01)


def test_idle_connections_never_lock_a_real_client_out(dataset):
    # 300 clients that connect and say nothing (the default bound keeps 256 open): the oldest
    # idle ones are closed to make room, and a real request is answered at once
    with StaticImageServer([dataset], bind="127.0.0.1:0") as s:
        url = s.publish(dataset / "artifacts" / "house" / "frame_000.png", sha(PNG))
        idle = []
        try:
            for _ in range(300):
                idle.append(socket.create_connection(("127.0.0.1", s.port), timeout=5))
            _wait_until(lambda: s._open_connections >= s.max_open_connections)
            time.sleep(0.2)  # the server has accepted what it accepts
            assert s._open_connections <= s.max_open_connections
            t0 = time.monotonic()
            assert get(url)[:2] == (200, PNG)
            assert time.monotonic() - t0 < 2
            assert idle[0].recv(10) == b""  # the oldest idle connection was the one closed
        finally:
            for c in idle:
                c.close()


def test_an_idle_connection_is_closed_after_the_idle_timeout(dataset):
    with StaticImageServer([dataset], bind="127.0.0.1:0", idle_timeout_s=0.3) as s:
        s.publish(dataset / "artifacts" / "house" / "frame_000.png", sha(PNG))
        silent = socket.create_connection(("127.0.0.1", s.port), timeout=5)
        try:
            t0 = time.monotonic()
            assert silent.recv(10) == b""  # closed by the server, long before the 5 s client timeout
            assert time.monotonic() - t0 < 3
        finally:
            silent.close()
        kept_alive = socket.create_connection(("127.0.0.1", s.port), timeout=5)
        try:
            kept_alive.sendall(f"GET /{sha(PNG)}.png HTTP/1.1\r\nHost: x\r\n\r\n".encode())
            answer = b""
            while not answer.endswith(PNG):
                part = kept_alive.recv(65536)
                assert part, answer
                answer += part
            assert answer.startswith(b"HTTP/1.1 200")
            assert kept_alive.recv(10) == b""  # idle again after its answer: closed too
            _wait_until(lambda: s._open_connections == 0)
        finally:
            kept_alive.close()


def test_a_file_changed_since_published_is_refused_not_served(server, dataset):
    frame = dataset / "artifacts" / "house" / "frame_000.png"
    url = server.publish(frame, sha(PNG))
    swapped = b"\x89PNG\r\n\x1a\n" + b"another image " * 50
    frame.write_bytes(swapped)
    status, body, _ = get(url)
    assert status == 409 and swapped not in body
    assert raw_get(server, f"/{sha(PNG)}.png") == 409
    frame.write_bytes(PNG)  # the published bytes again: served again
    assert get(url)[:2] == (200, PNG)
