"""Runner test fixtures: a small synthetic release, pipeline YAMLs using the offline test plugin, one
fresh interpreter's run of the litellm backend shared by the tests of what its start-up does, and
``povagent`` commands run as processes of their own (tests/run/command_forks.py)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
import yaml

from povagent.testing.pytest_plugin import write_release


@pytest.fixture(scope="session")
def small_release(tmp_path_factory) -> Path:
    """2 houses, 2 pairs, 4 (pair, direction)s, 3 frames: 12 instances over the 3 conditions."""
    return write_release(tmp_path_factory.mktemp("release") / "povbench", houses=2, pairs=2, pair_directions=4, frames=3)


@pytest.fixture
def offline_plugin(offline_plugin_file):
    """The offline test plugin module, as loaded from its copy beside the test's pipelines
    (``module.__file__``; shared with subprocesses)."""
    from povagent.plugins import _import_module_or_file

    module = _import_module_or_file(str(offline_plugin_file))
    module.CALLS["count"] = 0
    module.FlakyBackend.SCRIPT.clear()
    return module


@pytest.fixture
def write_pipeline(tmp_path, small_release, povagent_host, offline_plugin):
    """``write_pipeline(**overrides) -> Path``: a pipeline YAML over the small release."""

    def make(name: str = "pipeline.yaml", **overrides: Any) -> Path:
        data: dict[str, Any] = {
            "plugins": [offline_plugin.__file__],
            "dataset": {"path": str(small_release)},
            "backend": {"name": "test-center"},
            "strategy": "test-point",
            "parser": "test-json",
            "scorers": ["official"],
            "runs": 1,
            "concurrency": 4,
            "retry": {"attempts": 3, "initial_wait": 0.0, "max_wait": 0.01},
            "timeout": 5,
            "output": str(tmp_path / "run"),
        }
        data.update(overrides)
        path = tmp_path / name
        path.write_text(yaml.safe_dump(data, sort_keys=False))
        return path

    return make


#: Runs a pipeline in a fresh interpreter (litellm not yet imported) and reports, from inside
#: the dataset's loading, whether litellm was being imported in the background meanwhile.
FRESH_RUN = """
import json, sys, threading
seen = {"litellm_at_start": "litellm" in sys.modules}
import povagent.run.runner as runner
from povagent.config.pipeline import load_pipeline

real_prepare = runner.prepare_dataset

def prepare_dataset(config):
    seen["preloading"] = [t.name for t in threading.enumerate() if t.name == "povagent-preload-litellm" and t.is_alive()]
    return real_prepare(config)

runner.prepare_dataset = prepare_dataset
result = runner.run_pipeline(load_pipeline(sys.argv[1]))
rows = result.summary.rows
print(json.dumps({**seen, "exit_code": result.exit_code, "requests": result.stats.requests,
                  "answered": rows.answered, "infra_error": rows.infra_error}))
"""


@pytest.fixture(scope="session")
def fresh_litellm_run(tmp_path_factory, mini_root) -> dict[str, Any]:
    """One run of the litellm backend by a fresh interpreter, shared by the tests that read what
    such a start-up does (importing litellm costs seconds of CPU): 6 keys of the hand-made
    dataset at concurrency 4 from a loopback server, a 3 s timeout and no retry. Returns the
    child's report (``litellm_at_start``, ``preloading`` as seen while the dataset loaded,
    ``exit_code``, ``requests``, ``answered``, ``infra_error``), the requests the server saw
    (``server_requests``) and the rows' ``statuses``.

    Its two test files run in different xdist workers: the run is made once between them
    (tests/shared_sets.py), its report kept beside it for the workers that read it."""
    from shared_sets import made_once

    def make(folder: Path) -> None:
        import shutil

        shutil.rmtree(folder, ignore_errors=True)  # a run cut short is not resumed: made afresh
        folder.mkdir(parents=True)
        report = _run_fresh_litellm(folder, mini_root)
        (folder / "report.json").write_text(json.dumps(report))
        # what made_once waits for, written last: a folder without it is made again
        (folder / "meta.json.part").write_text("{}\n")
        (folder / "meta.json.part").rename(folder / "meta.json")

    folder = made_once(tmp_path_factory, "fresh-litellm-run", make)
    return json.loads((folder / "report.json").read_text())


def _run_fresh_litellm(folder: Path, mini_root: Path) -> dict[str, Any]:
    from povagent.testing.loopback_server import LoopbackServer

    with LoopbackServer(reply='{"selected_image": 0, "x": 10, "y": 20}', max_lifetime_s=200) as server:
        path = folder / "pipeline.yaml"
        path.write_text(json.dumps({
            "dataset": str(mini_root),
            "backend": {"name": "litellm", "options": {"model": "openai/loopback", "api_base": server.url,
                                                       "api_key_env": "POVAGENT_TEST_KEY"}},
            "strategy": "basic", "parser": "json", "instances": {"conditions": ["a", "b"], "limit": 6},
            "concurrency": 4, "retry": {"attempts": 1}, "timeout": 3.0, "output": str(folder / "run"),
        }))  # fmt: skip
        env = {**os.environ, "POVAGENT_TEST_KEY": "sk-test-fresh-run"}
        done = subprocess.run([sys.executable, "-c", FRESH_RUN, str(path)], capture_output=True, text=True, env=env, timeout=200)
        assert done.returncode == 0, done.stderr[-3000:]
        server_requests = server.request_count
    seen = json.loads(done.stdout.strip().splitlines()[-1])
    statuses = [json.loads(line)["status"] for line in (folder / "run" / "results.jsonl").read_text().splitlines()]
    return {**seen, "server_requests": server_requests, "statuses": statuses}


#: The environment the tests started with: what the command server imports povagent under.
START_ENV = dict(os.environ)


@pytest.fixture(scope="session")
def command_forks(tmp_path_factory) -> Any:
    """A :class:`command_forks.CommandForks`: ``povagent`` commands as processes of their own,
    forked from one interpreter that imported povagent once (a fresh interpreter costs most of a
    second of imports and compiling, which these tests do not test). Started when a test first
    asks for it, stopped when the session ends."""
    from command_forks import CommandForks

    forks = CommandForks(tmp_path_factory.mktemp("command-forks"), START_ENV)
    try:
        yield forks
    finally:
        forks.close()


@pytest.fixture
def run_killed_mid_way(command_forks) -> Any:
    """``run_killed_mid_way(pipeline, results, rows) -> int``: ``povagent run`` of ``pipeline`` in
    a process of its own, SIGKILLed once ``results`` holds ``rows`` lines (within 60 s, the
    command still running); the lines it held after the kill."""
    import signal
    import time

    def run(pipeline: Path, results: Path, rows: int) -> int:
        env = {**os.environ, "PYTHONUNBUFFERED": "1"}
        proc = command_forks.start("run", pipeline, "--quiet", cwd=Path.cwd(), env=env)
        try:
            deadline = time.monotonic() + 60
            while len(results.read_text().splitlines()) < rows if results.exists() else True:
                assert proc.poll() is None, proc.stderr()
                assert time.monotonic() < deadline, "no rows written in time"
                time.sleep(0.005)
            proc.send_signal(signal.SIGKILL)
        finally:
            proc.wait(timeout=30)
        assert proc.returncode == -signal.SIGKILL
        return len(results.read_text().splitlines())

    return run
