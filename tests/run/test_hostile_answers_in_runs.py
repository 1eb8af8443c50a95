"""Answers a real server may send that are not plain text answers, through the whole runner."""

from __future__ import annotations

import json

import pytest

from povagent.config.pipeline import load_pipeline
from povagent.engine.cache import ResponseCache
from povagent.results.rows import read_rows
from povagent.run.runner import run_pipeline
from povagent.testing.loopback_server import LoopbackServer, Reply

pytestmark = pytest.mark.timeout(120)

VALID = '{"selected_image": 0, "x": 10, "y": 20}'


def write(tmp_path, mini_root, server, **extra):
    doc = {
        "dataset": str(mini_root),
        "backend": {"name": "litellm", "options": {"model": "openai/loopback", "api_base": server.url, "api_key_env": "POVAGENT_TEST_KEY"}},
        "strategy": "basic",
        "parser": "json",
        "instances": {"conditions": ["a"], "limit": 2},
        "concurrency": 1,
        "retry": {"attempts": 3, "initial_wait": 0.0, "max_wait": 0.0},
        "output": str(tmp_path / "run"),
        **extra,
    }
    path = tmp_path / "pipeline.yaml"
    path.write_text(json.dumps(doc), encoding="utf-8")
    return path


@pytest.fixture
def server(monkeypatch):
    monkeypatch.setenv("POVAGENT_TEST_KEY", "sk-test-key-000")
    with LoopbackServer(reply=VALID, max_lifetime_s=100) as s:
        yield s


def test_an_answer_with_a_lone_surrogate_is_kept_and_the_run_goes_on(tmp_path, mini_root, server):
    # JSON "\ud800" escapes decode to a lone surrogate, which UTF-8 cannot hold
    server.script(Reply('{"selected_image": 0, "x": 10, "y": 20} \ud800'))
    result = run_pipeline(load_pipeline(write(tmp_path, mini_root, server)))
    rows = read_rows(tmp_path / "run" / "results.jsonl")
    assert [r.status for r in rows] == ["answered", "answered"] and result.exit_code == 0
    assert rows[0].exchanges[0].raw.endswith("\ufffd")
    with ResponseCache(tmp_path / "run" / "cache.sqlite") as cache:
        assert len(cache) == 2  # both answers of the batch were cached
    again = run_pipeline(load_pipeline(write(tmp_path, mini_root, server)))  # resumes cleanly
    assert again.n_pending == 0


def test_an_empty_response_is_retried_and_never_cached(tmp_path, mini_root, server):
    server.script(Reply(None), Reply("", no_choices=True))
    run_pipeline(load_pipeline(write(tmp_path, mini_root, server, instances={"conditions": ["a"], "limit": 1})))
    (row,) = read_rows(tmp_path / "run" / "results.jsonl")
    assert row.status == "answered" and row.retries == 2 and server.request_count == 3
    with ResponseCache(tmp_path / "run" / "cache.sqlite") as cache:
        assert len(cache) == 1  # only the real answer


def test_empty_responses_to_the_end_are_an_infra_error_named_so(tmp_path, mini_root, server):
    server.reply = Reply(None)
    result = run_pipeline(load_pipeline(write(tmp_path, mini_root, server, instances={"conditions": ["a"], "limit": 1})))
    (row,) = read_rows(tmp_path / "run" / "results.jsonl")
    assert row.status == "infra_error" and row.error_type == "empty_response" and row.retries == 2
    assert result.exit_code == 3


def test_the_litellm_import_does_not_count_against_the_first_requests_timeout(fresh_litellm_run):
    """A fresh interpreter imports litellm and loads its lazy modules for 5-25 s here; with a 3 s
    timeout and no retry, no key may time out (before, the first requests paid for all of it).
    The run is tests/run/conftest.py's ``fresh_litellm_run``: 6 keys, concurrency 4."""
    seen = fresh_litellm_run
    assert seen["litellm_at_start"] is False
    assert [seen["answered"], seen["infra_error"]] == [6, 0], seen
    assert seen["server_requests"] == 6
