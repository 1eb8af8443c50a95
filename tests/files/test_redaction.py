"""Redaction: secret-named values, key-shaped strings, the environment's keys and the keys a
config names are removed; a variable's name and an answer's other characters are kept."""

from __future__ import annotations

from povagent.files.redaction import REDACTED, Redactor, secrets_named_by


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


def test_a_key_naming_an_environment_variable_is_kept():
    assert Redactor().value({"api_key_env": "OPENAI_API_KEY"}) == {"api_key_env": "OPENAI_API_KEY"}


def test_the_key_a_config_names_by_api_key_env_is_known_whatever_the_variable_is_called(monkeypatch):
    monkeypatch.setenv("LAB_VAR", "lab-key-0123456789")
    monkeypatch.setenv("OTHER_VAR", "other-key-987654321")
    config = {"backend": {"options": {"api_key_env": "LAB_VAR", "router": [
        {"litellm_params": {"api_key_env": "UNSET_VAR_XYZ"}}, {"litellm_params": {"api_key": "os.environ/OTHER_VAR"}}]}}}
    redactor = Redactor(secrets_named_by(config))
    assert secrets_named_by(config) == ("lab-key-0123456789", "other-key-987654321")
    assert redactor.known("echo: Bearer lab-key-0123456789!") == "echo: Bearer [REDACTED]!"


def test_an_answer_keeps_every_character_but_the_known_keys():
    answer = 'see http://user:pw@host and sk-abcdefghijkl {"x": 1}'
    assert Redactor(("lab-key-0123456789",)).known(answer) == answer  # patterns are for messages
