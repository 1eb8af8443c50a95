"""The how-to's scripted tool-calling model (docs/how-to/active.md, "Try it without a model"):
its turns file, pipeline and server command, run as the page shows them, make an episode that
takes exactly the scripted actions."""

from __future__ import annotations

import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from povagent.config.pipeline import load_pipeline
from povagent.results.episode import read_record
from povagent.results.rows import read_rows
from povagent.run.runner import run_pipeline

pytestmark = pytest.mark.timeout(120)

PAGE = Path(__file__).resolve().parents[2] / "docs" / "how-to" / "active.md"


def block(first_line: str) -> str:
    """The code block of the page whose first line is ``first_line``."""
    for body in re.findall(r"```[a-z]*\n(.*?)```", PAGE.read_text(), re.S):
        if body.startswith(first_line):
            return body
    raise AssertionError(f"{PAGE.name} has no code block starting {first_line!r}")


def server_command() -> list[str]:
    """The page's command starting the server, on any free port, in this interpreter."""
    console = block("python -m povagent.testing.loopback_server")
    line = console.splitlines()[0].rstrip(" &")
    args = shlex.split(line)
    assert args[:3] == ["python", "-m", "povagent.testing.loopback_server"] and "--script" in args
    args[args.index("--port") + 1] = "0"
    return [sys.executable, *args[1:], "--lifetime", "60"]


def test_the_episode_takes_the_scripted_actions_of_the_how_to(generated_release, tmp_path, monkeypatch):
    turns = yaml.safe_load(block("# turns.yaml"))
    (tmp_path / "turns.yaml").write_text(block("# turns.yaml"))
    server = subprocess.Popen(server_command(), cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert server.stdout is not None
        url = server.stdout.readline().strip()
        assert url.startswith("http://127.0.0.1:"), server.stderr.read() if server.stderr else ""
        doc = yaml.safe_load(block("# scripted.yaml"))
        assert doc["backend"]["options"]["api_base"] == "http://127.0.0.1:8000/v1"  # the port of the page's command
        doc["backend"]["options"]["api_base"] = url
        doc["dataset"]["path"] = str(generated_release)
        doc["output"] = str(tmp_path / "runs" / "active-scripted")
        (tmp_path / "scripted.yaml").write_text(yaml.safe_dump(doc))
        monkeypatch.setenv(doc["backend"]["options"]["api_key_env"], "any-value")
        run_pipeline(load_pipeline(tmp_path / "scripted.yaml"))
    finally:
        server.terminate()
        server.wait(timeout=30)
    (row,) = read_rows(tmp_path / "runs" / "active-scripted" / "results.jsonl")
    record = read_record(row.exchanges[-1].raw)
    scripted = [(c["name"], c["arguments"]) for turn in turns for c in turn["tool_calls"]]
    taken = [(s.action, yaml.safe_load(s.arguments)) for s in record.steps]
    assert taken == scripted
    assert all(s.valid for s in record.steps) and record.counts.questions == 1 and record.counts.views == 3
    assert record.answer.image == "view 2" and record.answer.camera == record.views[1].camera
    assert row.status == "answered" and row.scores["official"]["answered"]
