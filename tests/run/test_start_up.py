"""A run starts at once: litellm loads in the background while the dataset loads, and a run
whose every answer is cached never loads it (povagent/run/runner.py, engine/llm_import.py)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from povagent.testing.loopback_server import LoopbackServer

pytestmark = pytest.mark.timeout(240)

KEY_ENV = "POVAGENT_TEST_KEY"
REPLY = '{"selected_image": 1, "x": 300, "y": 280}'


def _pipeline(tmp_path: Path, dataset: Path, url: str, name: str, cache: Path) -> Path:
    doc = {
        "dataset": str(dataset),
        "backend": {"name": "litellm", "options": {"model": "openai/loopback-vlm", "api_base": url, "api_key_env": KEY_ENV}},
        "strategy": "basic",
        "parser": "json",
        "instances": {"conditions": ["a"], "limit": 1},
        "retry": {"attempts": 1},
        "timeout": 60,
        "cache": str(cache),
        "output": str(tmp_path / name),
    }
    path = tmp_path / f"{name}.yaml"
    path.write_text(yaml.safe_dump(doc, sort_keys=False))
    return path


def _statuses(folder: Path) -> list[str]:
    return [json.loads(line)["status"] for line in (folder / "results.jsonl").read_text().splitlines()]


def test_litellm_loads_in_the_background_while_the_dataset_loads(fresh_litellm_run):
    # the run of a fresh interpreter (tests/run/conftest.py), seen from inside its dataset loading
    seen = fresh_litellm_run
    assert seen["preloading"] == ["povagent-preload-litellm"], seen
    assert seen["exit_code"] == 0 and seen["requests"] == 6 and seen["server_requests"] == 6, seen
    # no import deadlock, no half-imported module: every row is an answer
    assert seen["statuses"] == ["answered"] * 6, seen


def test_a_run_whose_every_answer_is_cached_never_imports_litellm(tmp_path, mini_root, monkeypatch):
    from povagent.config.pipeline import load_pipeline
    from povagent.run.runner import run_pipeline

    monkeypatch.setenv(KEY_ENV, "sk-test-start-up")
    cache = tmp_path / "shared-cache.sqlite"
    with LoopbackServer(reply=REPLY, max_lifetime_s=200) as server:
        first = run_pipeline(load_pipeline(_pipeline(tmp_path, mini_root, server.url, "first", cache)))
        assert first.stats.requests == 1 and _statuses(tmp_path / "first") == ["answered"]
        # a new run folder with the same response cache: every answer is cached
        again = _pipeline(tmp_path, mini_root, server.url, "again", cache)
        done = subprocess.run(
            [sys.executable, "-X", "importtime", "-c", "from povagent.cli import main; main()", "run", str(again), "--quiet"],
            capture_output=True, text=True, env=dict(os.environ), timeout=200,
        )
        assert done.returncode == 0, done.stderr[-3000:]
        assert len(server.requests) == 1, "the cached run sent a request"
    imported = {line.split("|")[-1].strip() for line in done.stderr.splitlines() if line.startswith("import time:")}
    assert "povagent.run.runner" in imported  # the import log is complete
    assert not {m for m in imported if m.split(".")[0] in ("litellm", "openai")}, "litellm imported by a cached run"
    assert "1 cache hits" in done.stdout and _statuses(tmp_path / "again") == ["answered"]
