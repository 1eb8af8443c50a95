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
