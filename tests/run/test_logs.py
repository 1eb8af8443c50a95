"""Run logs: JSON lines, and secrets never written."""

from __future__ import annotations

import json

from povagent.run.logs import REDACTED, Redactor, RunLog


def test_events_are_json_lines_with_level_and_time(tmp_path):
    log = RunLog(tmp_path / "log.jsonl", run="r")
    log.info("request", latency_s=0.5, prompt_tokens=12)
    log.close()
    (event,) = [json.loads(line) for line in (tmp_path / "log.jsonl").read_text().splitlines()]
    assert event["event"] == "request" and event["level"] == "info" and event["run"] == "r" and "ts" in event
    assert event["prompt_tokens"] == 12  # counts named *token* are not secrets


def test_values_of_secret_named_keys_are_redacted():
    r = Redactor()
    out = r.value({"api_key": "abc", "headers": {"Authorization": "xyz"}, "password": "p", "client_secret": "s"})
    assert out == {"api_key": REDACTED, "headers": {"Authorization": REDACTED}, "password": REDACTED, "client_secret": REDACTED}


def test_key_shaped_strings_are_redacted_anywhere():
    r = Redactor()
    text = r.text("failed with sk-proj-ABCDEF1234567890 and header Bearer eyJhbGciOiJIUzI1NiJ9.x")
    assert "ABCDEF1234567890" not in text and "eyJhbGci" not in text and text.count(REDACTED) == 2


def test_environment_api_key_values_are_redacted(monkeypatch):
    monkeypatch.setenv("SOMEPROVIDER_API_KEY", "plainvalue-123456")
    assert Redactor().text("the key plainvalue-123456 was rejected") == f"the key {REDACTED} was rejected"


def test_secret_never_reaches_the_log_file(tmp_path, monkeypatch):
    monkeypatch.setenv("OPENAI_API_KEY", "zz-secret-value-999")
    log = RunLog(tmp_path / "log.jsonl")
    log.error("request_failed", error="401: invalid key zz-secret-value-999", options={"api_key": "zz-secret-value-999"})
    log.close()
    assert "zz-secret-value-999" not in (tmp_path / "log.jsonl").read_text()


def test_a_key_naming_an_environment_variable_is_kept():
    assert Redactor().value({"api_key_env": "OPENAI_API_KEY"}) == {"api_key_env": "OPENAI_API_KEY"}


def test_the_key_a_config_names_by_api_key_env_is_known_whatever_the_variable_is_called(monkeypatch):
    from povagent.run.logs import Redactor, secrets_named_by

    monkeypatch.setenv("LAB_VAR", "lab-key-0123456789")
    monkeypatch.setenv("OTHER_VAR", "other-key-987654321")
    config = {"backend": {"options": {"api_key_env": "LAB_VAR", "router": [
        {"litellm_params": {"api_key_env": "UNSET_VAR_XYZ"}}, {"litellm_params": {"api_key": "os.environ/OTHER_VAR"}}]}}}
    redactor = Redactor(secrets_named_by(config))
    assert secrets_named_by(config) == ("lab-key-0123456789", "other-key-987654321")
    assert redactor.known("echo: Bearer lab-key-0123456789!") == "echo: Bearer [REDACTED]!"


def test_an_answer_keeps_every_character_but_the_known_keys():
    from povagent.run.logs import Redactor

    answer = 'see http://user:pw@host and sk-abcdefghijkl {"x": 1}'
    assert Redactor(("lab-key-0123456789",)).known(answer) == answer  # patterns are for messages
