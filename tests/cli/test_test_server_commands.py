"""The test servers from a shell: ``python -m povagent.testing.loopback_server`` and
``python -m povagent.testing.hub_server`` explain their options and say what is wrong with a
port, a folder or a file in one line, exit code 2, never a traceback."""

from __future__ import annotations

import json
import signal
import socket
import subprocess
import sys
import textwrap

import pytest
from console_child import IMPORT

from povagent.testing import hub_server, loopback_server

SERVERS = {"loopback_server": loopback_server, "hub_server": hub_server}


# One child runs each command line below as ``python -m`` runs it (runpy, the module as
# ``__main__``, its own argv and its own stdout and stderr files: file descriptors 1 and 2 pointed
# at them), so each is still the real command line in a process, for one interpreter start
# instead of one each. An exception escaping it is printed as the interpreter would print it (a
# traceback, exit status 1). A server that does start is stopped by --lifetime.
EACH_COMMAND = IMPORT + textwrap.dedent("""
    import functools, json, os, runpy

    cases, folder = json.loads(sys.argv[1]), sys.argv[2]
    codes = []
    for n, (module, args, env) in enumerate(cases):
        os.environ.update(env)
        as_main = functools.partial(runpy.run_module, f"povagent.testing.{module}", run_name="__main__", alter_sys=True)
        codes.append(run_as_console(as_main, [module, *args], f"{folder}/{n}.out", f"{folder}/{n}.err"))
        for name in env:
            del os.environ[name]
    print(json.dumps(codes))
""")


@pytest.fixture(scope="module")
def shown(tmp_path_factory) -> dict[tuple[str, str], tuple[subprocess.CompletedProcess[str], int]]:
    """(case, module) -> (what the command line returned and printed, the port held busy): each
    server's ``--help`` at 80 columns and its refused command lines, run in one child while a
    port is held busy."""
    folder = tmp_path_factory.mktemp("commands")
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        port = busy.getsockname()[1]
        cases: dict[tuple[str, str], tuple[list[str], dict[str, str]]] = {}
        for module in SERVERS:
            args = [str(folder)] if module == "hub_server" else []
            cases["help", module] = (["--help"], {"COLUMNS": "80"})
            cases["port in use", module] = ([*args, "--port", str(port), "--lifetime", "5"], {})
            cases["port out of range", module] = ([*args, "--port", "70000", "--lifetime", "5"], {})
        cases["missing folder", "hub_server"] = ([str(folder / "nowhere"), "--lifetime", "5"], {})
        cases["digest file", "loopback_server"] = (["--expect-sha256", str(folder / "digests.txt"), "--lifetime", "5"], {})
        plan = [(module, args, env) for (_, module), (args, env) in cases.items()]
        child = subprocess.run([sys.executable, "-c", EACH_COMMAND, json.dumps(plan), str(folder)], capture_output=True,
                               text=True, timeout=120)  # fmt: skip
    assert child.returncode == 0, child.stderr[-2000:]
    codes = json.loads(child.stdout.splitlines()[-1])
    return {
        key: (subprocess.CompletedProcess(args, code, (folder / f"{n}.out").read_text(), (folder / f"{n}.err").read_text()), port)
        for n, ((key, (args, _)), code) in enumerate(zip(cases.items(), codes))
    }


@pytest.mark.parametrize("module", SERVERS)
def test_every_option_is_explained_in_help(module, shown):
    parser = SERVERS[module].argument_parser()
    unexplained = [a.dest for a in parser._actions if not (a.help or "").strip()]
    assert unexplained == []
    help_shown, _ = shown["help", module]
    assert help_shown.returncode == 0
    assert f"python -m povagent.testing.{module}" in help_shown.stdout and "--port N" in help_shown.stdout
    assert "example:" in help_shown.stdout
    assert max(len(line) for line in help_shown.stdout.splitlines()) <= 80


@pytest.mark.parametrize("module", SERVERS)
def test_a_port_in_use_is_a_clear_message_not_a_traceback(module, shown):
    done, busy_port = shown["port in use", module]
    assert done.returncode == 2
    assert f"port {busy_port} in use (try --port 0" in done.stderr
    assert "Traceback" not in done.stderr and done.stdout == ""


@pytest.mark.parametrize("module", SERVERS)
def test_a_port_out_of_range_is_refused_before_binding(module, shown):
    done, _ = shown["port out of range", module]
    assert done.returncode == 2 and "70000 is not a port number (0 to 65535" in done.stderr
    assert "Traceback" not in done.stderr


def test_the_hub_server_names_a_missing_folder(shown):
    done, _ = shown["missing folder", "hub_server"]
    assert done.returncode == 2 and "nowhere: not a folder" in done.stderr and "Traceback" not in done.stderr


def test_the_loopback_server_names_an_unreadable_digest_file(shown):
    done, _ = shown["digest file", "loopback_server"]
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
