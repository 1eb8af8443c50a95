"""A backend answering in this process (``answers_in_process``): keys a chunk at a time, the same rows."""

from __future__ import annotations

import asyncio
import json
import signal

import pytest

from povagent.config.pipeline import load_pipeline
from povagent.results.rows import read_rows
from povagent.run.progress import QuietProgress
from povagent.run.runner import run_pipeline

N_KEYS = 12  # 4 (pair, direction)s x 3 conditions in the small release
#: what differs between two runs of one pipeline whatever the path (clocks)
TIMED = ("latency_s", "started_at", "finished_at")


def _rows(run_dir):
    """The rows in key order, without their clocks."""
    rows = [json.loads(line) for line in (run_dir / "results.jsonl").read_text().splitlines()]
    for row in rows:
        for name in TIMED:
            row.pop(name)
        for exchange in row["exchanges"]:
            exchange.pop("latency_s")
    return sorted(rows, key=lambda r: r["key"])


def _events(run_dir):
    return [json.loads(line) for line in (run_dir / "log.jsonl").read_text().splitlines()]


def test_an_in_process_backend_makes_the_rows_and_summary_the_concurrent_path_makes(write_pipeline, offline_plugin, tmp_path, monkeypatch):
    concurrent = run_pipeline(load_pipeline(write_pipeline("b.yaml", runs=2, output=str(tmp_path / "concurrent"))))
    monkeypatch.setattr(offline_plugin.CenterBackend, "answers_in_process", True)  # the same pipeline, declared in-process
    chunked = run_pipeline(load_pipeline(write_pipeline("a.yaml", runs=2, output=str(tmp_path / "chunked"))))
    assert _rows(chunked.run_dir) == _rows(concurrent.run_dir) and len(_rows(chunked.run_dir)) == 2 * N_KEYS
    a, b = (json.loads((r.run_dir / "summary.json").read_text()) for r in (chunked, concurrent))
    for summary in (a, b):
        summary.pop("session")
    assert a == b, {k: (a[k], b.get(k)) for k in a if a[k] != b.get(k)}
    # the same events, each request's too
    assert sorted((e["event"], e.get("row")) for e in _events(chunked.run_dir)) == sorted((e["event"], e.get("row")) for e in _events(concurrent.run_dir))


def test_an_in_process_backend_is_answered_with_no_task_per_request(write_pipeline, offline_plugin, monkeypatch):
    tasks_seen = set()
    answer = offline_plugin.CenterBackend.complete

    async def complete(self, request, images):
        tasks_seen.add(asyncio.current_task())
        return await answer(self, request, images)

    monkeypatch.setattr(offline_plugin.CenterBackend, "complete", complete)
    result = run_pipeline(load_pipeline(write_pipeline(backend={"name": "test-center", "options": {"in_process": True}}, concurrency=4, runs=2)))
    assert result.stats.requests == 2 * N_KEYS
    assert len(tasks_seen) == 1  # the run's own task: the first key's and every chunk's alike


def test_a_backend_exception_on_one_key_of_a_chunk_is_that_row_alone(write_pipeline, offline_plugin):
    path = write_pipeline(backend={"name": "test-flaky", "options": {"in_process": True}}, retry={"attempts": 3, "initial_wait": 0.0, "max_wait": 0.0})
    offline_plugin.FlakyBackend.SCRIPT[:] = ["ok", "ok", "crash", "ok", 503, "ok"]
    result = run_pipeline(load_pipeline(path))
    rows = read_rows(result.run_dir / "results.jsonl")
    assert [r.status.value for r in rows] == ["answered", "answered", "infra_error"] + ["answered"] * (N_KEYS - 3)
    assert rows[2].error_type == "backend_exception" and "bug in backend" in (result.run_dir / "log.jsonl").read_text()
    assert rows[4].retries == 1  # a transient failure is retried in a chunk as on the concurrent path
    assert result.summary.rows.done == N_KEYS and result.stats.requests == N_KEYS + 1


def test_failures_in_a_row_trip_the_circuit_breaker_inside_a_chunk(write_pipeline, offline_plugin):
    path = write_pipeline(backend={"name": "test-flaky", "options": {"in_process": True}}, stop_after_failures=3, retry={"attempts": 1})
    offline_plugin.FlakyBackend.SCRIPT[:] = ["ok", 503, "ok", 503, 503, 503, 503, 503]
    result = run_pipeline(load_pipeline(path))
    statuses = [r.status.value for r in read_rows(result.run_dir / "results.jsonl")]
    assert statuses == ["answered", "infra_error", "answered", "infra_error", "infra_error", "infra_error"]
    assert result.stopped is not None and "3 keys in a row failed" in result.stopped and result.n_missing == N_KEYS - 6


@pytest.mark.skipif(not hasattr(signal, "SIGKILL"), reason="SIGKILL is POSIX-only")
def test_sigkill_mid_chunked_run_then_resume_gives_every_key_exactly_once(write_pipeline, tmp_path, run_killed_mid_way):
    runs = 8
    path = write_pipeline(backend={"name": "test-center", "options": {"delay_s": 0.01, "in_process": True}}, runs=runs)
    results = tmp_path / "run" / "results.jsonl"
    written = run_killed_mid_way(path, results, 20)
    assert 20 <= written < 12 * runs, "the kill must land mid-run"
    # the resume: the same pipeline in this process (the kill above is what needs a process of its own)
    done = run_pipeline(load_pipeline(path), progress=QuietProgress())
    assert done.exit_code == 0, done.stopped
    keys = [json.loads(line)["key"] for line in results.read_text().splitlines()]
    assert len(keys) == len(set(keys)) == 12 * runs
    assert json.loads((tmp_path / "run" / "summary.json").read_text())["rows"]["answered"] == 12 * runs


def test_a_parser_raising_in_a_chunk_is_logged_for_its_own_key(write_pipeline, offline_plugin, monkeypatch):
    parse, calls = offline_plugin.JsonParser.parse, []

    def raising_on_the_third(self, text, spec):
        calls.append(text)
        if len(calls) == 3:
            raise RuntimeError("bug in parser")
        return parse(self, text, spec)

    monkeypatch.setattr(offline_plugin.JsonParser, "parse", raising_on_the_third)
    result = run_pipeline(load_pipeline(write_pipeline(backend={"name": "test-center", "options": {"in_process": True}})))
    rows = read_rows(result.run_dir / "results.jsonl")
    assert [r.status.value for r in rows] == ["answered", "answered", "parse_error"] + ["answered"] * (N_KEYS - 3)
    (event,) = [e for e in _events(result.run_dir) if e["event"] == "parser_exception"]
    assert event["row"] == rows[2].key and "bug in parser" in event["error"]
