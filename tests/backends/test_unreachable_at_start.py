"""A server that refuses connections before it has ever answered is not retried; one that
refused after answering (restarting) is; an unset ``api_key_env`` stops a run before any request.

Real sockets on 127.0.0.1: the loopback server started and stopped, and a port where nothing
listens. Through ``povagent run`` both end in the documented one-line stop (exit 4) at once,
where a refused connection was retried for 42 s and an unset variable ended in a traceback.
The unset variable and an address carrying credentials are run as a user runs them, in a fresh
``povagent`` process (what the terminal shows); the plain address where nothing listens is run
in this process (typer's ``CliRunner``): what it checks is the runner's stop and its counts.
"""

from __future__ import annotations

import asyncio
import json
import os
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest
import yaml
from typer.testing import CliRunner

from povagent.interfaces import PermanentBackendError, TransientBackendError
from povagent.testing.loopback_server import LoopbackServer
from povagent_plugins.backends.litellm_backend import LiteLLMBackend
from povagent_plugins.backends.litellm_errors import unreachable_for_good

pytestmark = pytest.mark.timeout(300)

CLI = "from povagent.cli import main; main()"


def free_port() -> int:
    """A port nothing listens on (bound, then released)."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def backend(api_base: str) -> LiteLLMBackend:
    return LiteLLMBackend(model="openai/loopback-model", api_base=api_base, api_key_env="POVAGENT_TEST_KEY")


def test_a_refused_connection_before_any_answer_is_permanent_and_names_the_address(make_request, store, api_key):
    port = free_port()
    b = backend(f"http://127.0.0.1:{port}/v1")
    with pytest.raises(PermanentBackendError) as caught:
        asyncio.run(b.complete(make_request(1), store))
    assert caught.value.kind == "connection"
    assert f"cannot reach http://127.0.0.1:{port}/v1 (connection refused" in str(caught.value)


def test_a_refusal_after_the_server_answered_stays_transient(make_request, store, api_key):
    server = LoopbackServer(reply='{"x": 1, "y": 2}', max_lifetime_s=60).start()
    b = backend(server.url)

    async def answered_then_restarting() -> None:
        await b.complete(make_request(1), store)
        server.stop()  # the server restarts: nothing listens for a while
        await asyncio.sleep(0.2)  # the client sees its kept-alive connection closed
        with pytest.raises(TransientBackendError) as caught:
            await b.complete(make_request(1), store)
        assert caught.value.kind == "connection"
        assert unreachable_for_good(caught.value.__cause__) is not None  # it was refused, and still retried

    try:
        asyncio.run(answered_then_restarting())
    finally:
        server.stop()


def test_a_server_that_answered_with_an_error_was_reached(make_request, store, api_key):
    from povagent.testing.loopback_server import Fault

    server = LoopbackServer(reply='{"x": 1, "y": 2}', max_lifetime_s=60).start()
    server.script(Fault(503))
    b = backend(server.url)

    async def error_then_gone() -> None:
        with pytest.raises(TransientBackendError):
            await b.complete(make_request(1), store)
        server.stop()
        await asyncio.sleep(0.2)
        with pytest.raises(TransientBackendError):  # it answered once: a refusal now is a restart
            await b.complete(make_request(1), store)

    try:
        asyncio.run(error_then_gone())
    finally:
        server.stop()


# -- through `povagent run` ---------------------------------------------------------------------
def pipeline(tmp_path: Path, mini_root: Path, **backend_options) -> Path:
    path = tmp_path / "pipeline.yaml"
    path.write_text(yaml.safe_dump({
        "dataset": {"path": str(mini_root)},
        "backend": {"name": "litellm", "options": {"model": "openai/loopback-model", **backend_options}},
        "strategy": "basic", "parser": "json", "scorers": ["official"], "output": str(tmp_path / "run"),
        "retry": {"attempts": 5, "initial_wait": 2.0, "max_wait": 10.0},
    }))  # fmt: skip
    return path


def run_cli(path: Path, **env: str) -> tuple[subprocess.CompletedProcess[str], float]:
    environment = {k: v for k, v in os.environ.items() if k != "POVAGENT_UNSET_KEY"}
    t0 = time.monotonic()
    done = subprocess.run([sys.executable, "-c", CLI, "run", str(path), "--quiet"], capture_output=True, text=True,
                          timeout=150, env={**environment, **env})
    return done, time.monotonic() - t0


def run_here(path: Path, **env: str) -> subprocess.CompletedProcess[str]:
    """``povagent run PATH --quiet`` in this process, ``env`` set for the call."""
    from povagent.cli import app
    from povagent.cli.process_exit import fast_exit_allowed

    result = CliRunner().invoke(app, ["run", str(path), "--quiet"], env=env)
    fast_exit_allowed()  # only the console script ends its process early: nothing is left allowed here
    if result.exception is not None and not isinstance(result.exception, SystemExit):
        raise result.exception
    return subprocess.CompletedProcess(["povagent", "run"], result.exit_code, result.stdout, result.stderr)


def stop_line(done: subprocess.CompletedProcess[str]) -> str:
    assert done.returncode == 4, done.stderr[-3000:]
    assert "Traceback" not in done.stderr
    lines = [line for line in done.stderr.splitlines() if line.startswith("stopped early:")]
    assert len(lines) == 1, done.stderr[-3000:]
    return lines[0]


def session(tmp_path: Path) -> dict:
    return json.loads((tmp_path / "run" / "summary.json").read_text())["session"]


@pytest.fixture(scope="module")
def unset_key_run(tmp_path_factory, mini_root) -> tuple[subprocess.CompletedProcess[str], int, Path]:
    """(the finished process, the requests the server saw, the folder): ``povagent run`` whose
    ``api_key_env`` names an unset variable, run once (a process that imports litellm costs
    seconds of CPU) for the tests that read what it did."""
    folder = tmp_path_factory.mktemp("unset-key")
    with LoopbackServer(max_lifetime_s=120) as server:
        done, _ = run_cli(pipeline(folder, mini_root, api_base=server.url, api_key_env="POVAGENT_UNSET_KEY"))
        requests = server.request_count
    return done, requests, folder


def test_run_stops_at_once_on_an_unset_api_key_env_before_any_request(unset_key_run):
    done, requests, folder = unset_key_run
    line = stop_line(done)
    assert "environment variable POVAGENT_UNSET_KEY (api_key_env of backend 'litellm') is not set" in line
    assert requests == 0
    assert session(folder)["requests"] == 0


def test_an_unset_api_key_env_prints_only_the_one_line(unset_key_run):
    """No warning row, no error row, no empty score table: the stop line alone (exit code 4);
    the run's log file keeps the row's and the stop's events."""
    done, _, folder = unset_key_run
    stop_line(done)
    shown = [line for line in (done.stdout + done.stderr).splitlines() if line.strip() and "dataset_problem" not in line]
    assert len(shown) == 1 and shown[0].startswith("stopped early:"), shown
    events = [json.loads(line)["event"] for line in (folder / "run" / "log.jsonl").read_text().splitlines()]
    assert "infra_error" in events and "run_stopped" in events


def test_run_stops_at_once_when_nothing_listens_and_hides_url_credentials(tmp_path, mini_root):
    port = free_port()
    api_base = f"http://127.0.0.1:{port}/v1"
    done = run_here(pipeline(tmp_path, mini_root, api_base=api_base, api_key_env="POVAGENT_TEST_KEY"),
                    POVAGENT_TEST_KEY="sk-loopback-test-key")
    line = stop_line(done)
    assert f"cannot reach {api_base} (connection refused" in line
    stats = session(tmp_path)
    assert stats["requests"] == 1 and stats["retries"] == 0  # with 5 attempts and 2-10 s waits allowed

    secret = "pw-that-must-not-show"
    tmp2 = tmp_path / "with-credentials"
    tmp2.mkdir()
    # in a fresh process: what the user's terminal shows, litellm's own loggers included
    done, _ = run_cli(pipeline(tmp2, mini_root, api_base=f"http://user:{secret}@127.0.0.1:{port}/v1",
                               api_key_env="POVAGENT_TEST_KEY"), POVAGENT_TEST_KEY="sk-loopback-test-key")
    line = stop_line(done)
    assert f"127.0.0.1:{port}/v1" in line and secret not in done.stderr
    assert session(tmp2)["retries"] == 0
    for f in (tmp2 / "run").iterdir():
        if f.is_file():
            assert secret not in f.read_text(errors="replace"), f.name
