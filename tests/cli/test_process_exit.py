"""After ``run`` and ``sweep`` the console script ends without the interpreter's teardown
(povagent/cli/process_exit.py), with the same exit code and nothing buffered lost."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from povagent.testing.pytest_plugin import write_release

pytestmark = pytest.mark.timeout(120)

#: The console script, plus an atexit handler that leaves a mark only an ordinary exit writes.
CLI = (
    "import atexit, os\n"
    "atexit.register(lambda: open(os.environ['TEARDOWN_MARK'], 'w').close())\n"
    "from povagent.cli import main\n"
    "main()\n"
)
EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
@pytest.fixture
def write_pipeline(tmp_path, offline_plugin_file):
    """``write_pipeline(**overrides) -> Path``: a pipeline over 12 instances, into ``tmp_path/run``."""
    release = write_release(tmp_path / "povbench", houses=2, pairs=2, pair_directions=4, frames=3)

    def make(**overrides):
        doc = {
            "plugins": [str(offline_plugin_file)],  # offline backends, strategy and parser, beside the YAML
            "dataset": {"path": str(release)},
            "backend": {"name": "test-center"},
            "strategy": "test-point",
            "parser": "test-json",
            "scorers": ["official"],
            "retry": {"attempts": 1},
            "output": str(tmp_path / "run"),
            **overrides,
        }
        path = tmp_path / "pipeline.yaml"
        path.write_text(yaml.safe_dump(doc, sort_keys=False))
        return path

    return make


def _cli(tmp_path: Path, *args: str) -> tuple[subprocess.CompletedProcess, bool]:
    """Run the console script with stdout and stderr piped (block-buffered); also say whether
    the interpreter's ordinary teardown ran."""
    mark = tmp_path / "torn-down"
    mark.unlink(missing_ok=True)
    env = {**os.environ, "TEARDOWN_MARK": str(mark)}
    done = subprocess.run([sys.executable, "-c", CLI, *args], capture_output=True, text=True, env=env, timeout=110,
                          cwd=EXAMPLES.parent)
    return done, mark.exists()


def test_run_exits_at_once_with_summary_log_and_stdout_complete(write_pipeline, tmp_path):
    path = write_pipeline()
    done, torn_down = _cli(tmp_path, "run", str(path), "--quiet", "--json")
    assert done.returncode == 0, done.stderr
    assert not torn_down, "the ordinary interpreter exit ran after `run`"
    run = tmp_path / "run"
    printed = json.loads(done.stdout)  # the whole summary reached the pipe
    assert printed == json.loads((run / "summary.json").read_text())
    assert printed["rows"]["answered"] == 12 and printed["complete"] is True
    rows = (run / "results.jsonl").read_text().splitlines()
    assert len(rows) == 12 and all(json.loads(r)["status"] == "answered" for r in rows)
    events = [json.loads(line)["event"] for line in (run / "log.jsonl").read_text().splitlines()]
    assert events[0] == "run_start" and events[-1] == "run_end"


def test_tables_and_a_stopped_runs_message_and_exit_code_survive(write_pipeline, tmp_path):
    # the first request is refused (401): the run stops early, exit code 4, hints on stderr
    path = write_pipeline(backend={"name": "test-flaky", "options": {"script": [401]}})
    done, torn_down = _cli(tmp_path, "run", str(path), "--quiet")
    assert done.returncode == 4, done.stderr
    assert not torn_down
    assert done.stdout.rstrip().splitlines()[-1].startswith("this session: 1 requests"), done.stdout
    assert "stopped early" in done.stderr and "run `povagent run" in done.stderr
    assert (tmp_path / "run" / "summary.json").exists()


def test_sweep_exits_at_once_with_every_cell_written(tmp_path):
    sweep = tmp_path / "sweep.yaml"
    sweep.write_text(
        (EXAMPLES / "sweep_baselines.yaml").read_text()
        .replace("base: pipeline_center.yaml", f"base: {EXAMPLES / 'pipeline_center.yaml'}")
        .replace("output: runs/example-baselines", f"output: {tmp_path / 'sweep'}")
    )
    done, torn_down = _cli(tmp_path, "sweep", str(sweep), "--quiet")
    assert done.returncode == 0, done.stderr
    assert not torn_down
    assert "sweep" in done.stdout and "cells" in done.stdout  # the last table reached the pipe
    cells = json.loads((tmp_path / "sweep" / "sweep.json").read_text())
    assert cells
    summaries = sorted((tmp_path / "sweep").glob("*/summary.json"))
    assert len(summaries) == 9 and all(json.loads(s.read_text())["complete"] for s in summaries)


def test_other_commands_exit_the_ordinary_way(tmp_path):
    # `schema` prints a file's JSON Schema: a command that is neither run nor sweep, and cheap
    done, torn_down = _cli(tmp_path, "schema", "summary")
    assert done.returncode == 0, done.stderr
    assert torn_down, "only run and sweep end without the teardown"
    assert json.loads(done.stdout)  # the whole schema reached the pipe


def test_an_exit_code_is_what_sys_exit_would_give(capsys):
    from povagent.cli.process_exit import exit_code_of

    assert [exit_code_of(c) for c in (None, 0, 3, 4, 130, 256 + 3)] == [0, 0, 3, 4, 130, 3]
    assert exit_code_of("boom") == 1 and capsys.readouterr().err == "boom\n"
