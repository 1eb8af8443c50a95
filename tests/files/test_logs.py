"""Run logs: JSON lines, and secrets never written."""

from __future__ import annotations

import json

from povagent.files.logs import RunLog


def test_events_are_json_lines_with_level_and_time(tmp_path):
    log = RunLog(tmp_path / "log.jsonl", run="r")
    log.info("request", latency_s=0.5, prompt_tokens=12)
    log.close()
    (event,) = [json.loads(line) for line in (tmp_path / "log.jsonl").read_text().splitlines()]
    assert event["event"] == "request" and event["level"] == "info" and event["run"] == "r" and "ts" in event
    assert event["prompt_tokens"] == 12  # counts named *token* are not secrets


def test_secret_never_reaches_the_log_file(tmp_path, monkeypatch):
    monkeypatch.setenv("OPENAI_API_KEY", "zz-secret-value-999")
    log = RunLog(tmp_path / "log.jsonl")
    log.error("request_failed", error="401: invalid key zz-secret-value-999", options={"api_key": "zz-secret-value-999"})
    log.close()
    assert "zz-secret-value-999" not in (tmp_path / "log.jsonl").read_text()


def test_an_event_is_written_as_the_structlog_processors_write_it(tmp_path, monkeypatch):
    # RunLog writes its events without structlog's wrapper (a run logs one a request); its
    # bound logger runs the processors themselves: the two lines must be the same bytes.
    monkeypatch.setenv("MY_LAB_API_KEY", "lab-secret-123456")
    monkeypatch.setattr("povagent.files.logs.utc_now", lambda: "2026-12-07T16:55:09.153+00:00")
    log = RunLog(tmp_path / "log.jsonl", run="runs/a", url="http://user:pw@host/x")
    events = [
        ("debug", "request", {"row": "set/1#0", "latency_s": 4.5e-05, "prompt_tokens": 0, "cost_usd": None, "cached": False}),
        ("info", "retry", {"row": "set/2#0", "error": "401 for key lab-secret-123456 (Bearer abcdefghijk)", "wait_s": 1.5}),
        ("warning", "override", {"run": "another", "level": "mine", "ts": "then", "api_key": "sk-abcdefghijklmnop"}),
        ("error", "nested", {"options": {"api_key_env": "sk-abcdefghijklmnop", "list": ["lab-secret-123456", 3]}, "path": tmp_path}),
        ("warn", "warned", {}),
    ]
    for method, event, fields in events:
        getattr(log, "warning" if method == "warn" else method)(event, **fields)
    for method, event, fields in events:
        getattr(log.logger, method)(event, **fields)
    log.close()
    lines = (tmp_path / "log.jsonl").read_text().splitlines()
    assert lines[: len(events)] == lines[len(events) :]
    assert "lab-secret-123456" not in "".join(lines) and "sk-abcdefghijklmnop" not in "".join(lines)
    assert json.loads(lines[2])["run"] == "another" and list(json.loads(lines[2]))[:2] == ["run", "url"]


def test_a_line_is_encoded_as_json_dumps_encodes_it_and_a_circular_event_leaves_the_next_unharmed(tmp_path):
    import pytest

    from povagent.files.logs import _LINE

    log = RunLog(tmp_path / "log.jsonl")
    events = [
        {"nan": float("nan"), "inf": float("-inf"), "text": "naïve ☃ \n\"q\"", "path": tmp_path, "exc": ValueError("x"), "nested": {"a": [1, 2.5, None, True]}},
        {"set": {1, 2}, "tuple": (1, "a"), "big": 2**70, "neg_zero": -0.0},
    ]
    for event in events:
        assert log._sinks._line(event) == _LINE.encode(event)
    circular: dict = {"a": [1]}
    circular["a"].append(circular)
    with pytest.raises(ValueError, match="Circular"):
        log._sinks._line(circular)
    circular["a"].pop()  # the same dict and list, no longer circular: the encoder's record starts afresh
    assert log._sinks._line(circular) == _LINE.encode(circular) == '{"a":[1]}'
    log.close()
