"""The test servers from a shell: ``python -m povagent.testing.loopback_server`` and
``python -m povagent.testing.hub_server`` explain their options and say what is wrong with a
port, a folder or a file in one line, exit code 2, never a traceback."""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys

import pytest

from povagent.testing import hub_server, loopback_server

SERVERS = {"loopback_server": loopback_server, "hub_server": hub_server}


def start(module: str, *args: str) -> subprocess.CompletedProcess[str]:
    """Run a server's command line; a server that does start is stopped by --lifetime."""
    return subprocess.run(
        [sys.executable, "-m", f"povagent.testing.{module}", *args, "--lifetime", "5"],
        capture_output=True, text=True, timeout=120,
    )  # fmt: skip


@pytest.fixture
def busy_port():
    """A port on 127.0.0.1 that another socket is listening on."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as sock:
        sock.bind(("127.0.0.1", 0))
        sock.listen()
        yield sock.getsockname()[1]


@pytest.mark.parametrize("module", SERVERS)
def test_every_option_is_explained_in_help(module):
    parser = SERVERS[module].argument_parser()
    unexplained = [a.dest for a in parser._actions if not (a.help or "").strip()]
    assert unexplained == []
    shown = subprocess.run(
        [sys.executable, "-m", f"povagent.testing.{module}", "--help"],
        capture_output=True, text=True, timeout=60, env={**os.environ, "COLUMNS": "80"},
    )  # fmt: skip
    assert shown.returncode == 0
    assert f"python -m povagent.testing.{module}" in shown.stdout and "--port N" in shown.stdout
    assert "example:" in shown.stdout
    assert max(len(line) for line in shown.stdout.splitlines()) <= 80


@pytest.mark.parametrize("module", SERVERS)
def test_a_port_in_use_is_a_clear_message_not_a_traceback(module, busy_port, tmp_path):
    args = [str(tmp_path)] if module == "hub_server" else []
    done = start(module, *args, "--port", str(busy_port))
    assert done.returncode == 2
    assert f"port {busy_port} in use (try --port 0" in done.stderr
    assert "Traceback" not in done.stderr and done.stdout == ""


@pytest.mark.parametrize("module", SERVERS)
def test_a_port_out_of_range_is_refused_before_binding(module, tmp_path):
    args = [str(tmp_path)] if module == "hub_server" else []
    done = start(module, *args, "--port", "70000")
    assert done.returncode == 2 and "70000 is not a port number (0 to 65535" in done.stderr
    assert "Traceback" not in done.stderr


def test_the_hub_server_names_a_missing_folder(tmp_path):
    done = start("hub_server", str(tmp_path / "nowhere"))
    assert done.returncode == 2 and "nowhere: not a folder" in done.stderr and "Traceback" not in done.stderr


def test_the_loopback_server_names_an_unreadable_digest_file(tmp_path):
    done = start("loopback_server", "--expect-sha256", str(tmp_path / "digests.txt"))
    assert done.returncode == 2 and "--expect-sha256" in done.stderr and "cannot read it" in done.stderr
    assert "Traceback" not in done.stderr


def test_the_loopback_server_still_serves_on_a_free_port():
    """The happy path of the same command line: the URL first, then it serves until --lifetime."""
    import json
    import urllib.request

    proc = subprocess.Popen(
        [sys.executable, "-m", "povagent.testing.loopback_server", "--port", "0", "--lifetime", "30", "--reply", "hello"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    try:
        assert proc.stdout is not None
        url = proc.stdout.readline().strip()
        assert url.startswith("http://127.0.0.1:") and url.endswith("/v1")
        body = json.dumps({"model": "m", "messages": [{"role": "user", "content": "hi"}]}).encode()
        request = urllib.request.Request(f"{url}/chat/completions", data=body, headers={"Content-Type": "application/json"})
        with urllib.request.urlopen(request, timeout=30) as response:
            assert json.load(response)["choices"][0]["message"]["content"] == "hello"
    finally:
        proc.terminate()
        proc.wait(timeout=30)


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_the_loopback_server_stops_on_sigint_or_sigterm_and_prints_its_counts(signum):
    """Started with SIGINT ignored, as a background job inherits it: SIGINT still stops it."""
    import json

    proc = subprocess.Popen(
        [sys.executable, "-m", "povagent.testing.loopback_server", "--port", "0", "--lifetime", "30", "--count-bodies"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_IGN),
    )  # fmt: skip
    try:
        assert proc.stdout is not None
        assert proc.stdout.readline().startswith("http://127.0.0.1:")
        proc.send_signal(signum)
        out, _ = proc.communicate(timeout=20)
    finally:
        proc.kill()
    assert json.loads(out.strip().splitlines()[-1]) == {"requests": 0, "body_sha256": {}}


def test_the_loopback_server_answers_after_its_delay():
    import json
    import time
    import urllib.request

    proc = subprocess.Popen(
        [sys.executable, "-m", "povagent.testing.loopback_server", "--port", "0", "--lifetime", "30", "--delay", "0.5",
         "--reply", "late"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    try:
        assert proc.stdout is not None
        url = proc.stdout.readline().strip()
        body = json.dumps({"model": "m", "messages": [{"role": "user", "content": "hi"}]}).encode()
        request = urllib.request.Request(f"{url}/chat/completions", data=body, headers={"Content-Type": "application/json"})
        t0 = time.monotonic()
        with urllib.request.urlopen(request, timeout=30) as response:
            assert json.load(response)["choices"][0]["message"]["content"] == "late"
        assert time.monotonic() - t0 >= 0.5
    finally:
        proc.terminate()
        proc.wait(timeout=30)
