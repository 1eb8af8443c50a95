"""A run killed with SIGKILL mid-run resumes with every key exactly once."""

from __future__ import annotations

import json
import signal

import pytest

from povagent.config.pipeline import load_pipeline
from povagent.engine.cache import ResponseCache, cache_key, identity_json
from povagent.run.progress import QuietProgress
from povagent.run.runner import run_pipeline


def _lines(path):
    return path.read_text().splitlines() if path.exists() else []


def _records(path):
    """Complete JSON lines (a line the kill cut short is left out)."""
    out = []
    for line in _lines(path):
        try:
            out.append(json.loads(line))
        except json.JSONDecodeError:
            pass
    return out


@pytest.mark.skipif(not hasattr(signal, "SIGKILL"), reason="SIGKILL is POSIX-only")
def test_sigkill_mid_run_then_resume_gives_every_key_exactly_once(write_pipeline, tmp_path, run_killed_mid_way):
    runs = 8
    path = write_pipeline(backend={"name": "test-center", "options": {"delay_s": 0.02}}, runs=runs, concurrency=4)
    results = tmp_path / "run" / "results.jsonl"
    written_before = run_killed_mid_way(path, results, 20)
    assert 20 <= written_before < 12 * runs, "the kill must land mid-run"
    # Every row that survived the kill has its request event in the log too.
    durable = {e["key"] for e in _records(results)}
    logged = {e["row"] for e in _records(tmp_path / "run" / "log.jsonl") if e["event"] == "request"}
    assert durable <= logged
    # ... and its answer in the response cache (written off the event loop, before the row).
    identity = identity_json({"backend": "test-center", "reply": None})
    with ResponseCache(tmp_path / "run" / "cache.sqlite") as cache:
        for row in _records(results):
            hit = cache.get(cache_key(identity, row["exchanges"][0]["request_hash"], row["run"]))
            assert hit is not None and hit.text == row["exchanges"][0]["raw"], row["key"]

    # the resume: the same pipeline in this process (the kill above is what needs a process of
    # its own; an interpreter more costs a second of imports and tests nothing more here)
    done = run_pipeline(load_pipeline(path), progress=QuietProgress())
    assert done.exit_code == 0, done.stopped
    keys = [json.loads(line)["key"] for line in _lines(results)]
    assert len(keys) == len(set(keys)) == 12 * runs
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    assert summary["complete"] is True and summary["rows"]["answered"] == 12 * runs
