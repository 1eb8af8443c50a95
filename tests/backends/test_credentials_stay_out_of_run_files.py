"""Credentials never reach a run folder or a terminal, however a user writes them in YAML.

Two ways a secret slipped through: credentials inside a URL (``api_base:
http://user:password@host``), and a key pasted where its variable's *name* belongs
(``api_key_env: sk-abc123``). URL credentials are redacted wherever secrets are (``config.yaml``,
``log.jsonl``, ``results.jsonl``, the console, error messages); a value of ``api_key_env`` that
is not a plausible variable name is refused, with a message saying what the field wants and
without the value.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from povagent.config.pipeline import dump_pipeline, load_pipeline
from povagent.errors import ConfigError
from povagent.files.redaction import REDACTED, Redactor
from povagent.run.runner import run_pipeline
from povagent.testing.loopback_server import LoopbackServer
from povagent_plugins.backends.litellm_backend import LiteLLMBackend

pytestmark = pytest.mark.timeout(90)

PASSWORD = "hunter2-Pa55"
PASTED_KEY = "sk-abc123"


def pipeline_yaml(tmp_path: Path, mini_root: Path, options: dict, **extra) -> Path:
    doc = {
        "dataset": str(mini_root),
        "instances": {"conditions": ["c"], "houses": ["train_house_00001"]},
        "backend": {"name": "litellm", "options": {"model": "openai/loopback-vlm", **options}},
        "retry": {"attempts": 1, "initial_wait": 0.0, "max_wait": 0.0},
        "timeout": 20,
        "cache": False,
        "output": str(tmp_path / "run"),
        **extra,
    }
    path = tmp_path / "pipeline.yaml"
    path.write_text(yaml.safe_dump(doc, sort_keys=False))
    return path


def run_folder_text(folder: Path) -> str:
    return "\n".join(p.read_text(encoding="utf-8") for p in sorted(folder.iterdir()) if p.suffix in (".yaml", ".jsonl", ".json"))


# -- URL credentials --------------------------------------------------------------------------
@pytest.mark.parametrize(
    "url, kept",
    [
        (f"http://alice:{PASSWORD}@127.0.0.1:8000/v1", "http://[REDACTED]@127.0.0.1:8000/v1"),
        (f"https://{PASSWORD}@models.example.org/v1", "https://[REDACTED]@models.example.org/v1"),
        (f"see postgres://bob:{PASSWORD}@db:5432/x now", "see postgres://[REDACTED]@db:5432/x now"),
    ],
)
def test_url_credentials_are_redacted_keeping_scheme_and_host(url, kept):
    assert Redactor().text(url) == kept


@pytest.mark.parametrize("text", ["mail alice@example.org", "http://host/path/@handle", "http://127.0.0.1:8000/v1"])
def test_text_without_url_credentials_is_left_alone(text):
    assert Redactor().text(text) == text


def test_config_yaml_holds_no_url_credentials(tmp_path, mini_root):
    config = load_pipeline(pipeline_yaml(tmp_path, mini_root, {"api_base": f"http://alice:{PASSWORD}@127.0.0.1:9/v1"}))
    dumped = dump_pipeline(config)
    assert PASSWORD not in dumped and "alice" not in dumped
    assert yaml.safe_load(dumped)["backend"]["options"]["api_base"] == f"http://{REDACTED}@127.0.0.1:9/v1"


def test_a_run_with_url_credentials_writes_them_nowhere(tmp_path, mini_root, api_key, capsys):
    with LoopbackServer(reply='{"x": 10, "y": 20}', max_lifetime_s=60) as server:
        base = server.url.replace("http://", f"http://alice:{PASSWORD}@")
        path = pipeline_yaml(tmp_path, mini_root, {"api_base": base, "api_key_env": "POVAGENT_TEST_KEY"})
        run_pipeline(load_pipeline(path), console_log=True)
    assert (tmp_path / "run" / "results.jsonl").read_text().strip()  # rows were written
    assert PASSWORD not in run_folder_text(tmp_path / "run")
    captured = capsys.readouterr()
    assert PASSWORD not in captured.out + captured.err


UNREACHABLE_PLUGIN = """
from povagent import hookimpl
from povagent.interfaces import Backend, PermanentBackendError


class Unreachable(Backend):
    def __init__(self, api_base):
        self.api_base = api_base

    def identity(self):
        return {"backend": "test-unreachable", "api_base": self.api_base}

    async def complete(self, request, images):
        raise PermanentBackendError(f"cannot reach {self.api_base}/chat/completions: connection refused")


@hookimpl
def register_backends(register):
    register("test-unreachable", Unreachable, description="test: echoes its URL in every error")
"""


def test_error_messages_echoing_url_credentials_are_redacted(tmp_path, mini_root, capsys):
    plugin = tmp_path / "unreachable_plugin.py"
    plugin.write_text(UNREACHABLE_PLUGIN)
    path = pipeline_yaml(tmp_path, mini_root, {}, plugins=[str(plugin)])
    doc = yaml.safe_load(path.read_text())
    doc["backend"] = {"name": "test-unreachable", "options": {"api_base": f"http://alice:{PASSWORD}@127.0.0.1:9/v1"}}
    path.write_text(yaml.safe_dump(doc))
    run_pipeline(load_pipeline(path), console_log=True)
    rows = [json.loads(line) for line in (tmp_path / "run" / "results.jsonl").read_text().splitlines()]
    assert rows and all(r["status"] == "infra_error" for r in rows)
    assert all("cannot reach http://[REDACTED]@127.0.0.1:9/v1" in r["error_message"] for r in rows)  # kept, minus the password
    assert PASSWORD not in run_folder_text(tmp_path / "run")
    captured = capsys.readouterr()
    assert PASSWORD not in captured.out + captured.err


# -- a key pasted into api_key_env -----------------------------------------------------------------
@pytest.mark.parametrize("value", [PASTED_KEY, "sk-proj-AbCdEf0123456789xyz", "my key", "OPENAI_API_KEY=sk-1", "1PASSWORD", ""])
def test_a_value_that_is_no_variable_name_is_refused_without_echoing_it(value):
    with pytest.raises(ConfigError) as err:
        LiteLLMBackend(model="openai/gpt-4o", api_key_env=value)
    message = str(err.value)
    assert "api_key_env" in message and "name of an environment variable" in message
    assert not value or value not in message


@pytest.mark.parametrize("value", ["OPENAI_API_KEY", "GEMINI_API_KEY", "my_key_2", "_PRIVATE"])
def test_plausible_variable_names_are_accepted(value):
    assert LiteLLMBackend(model="openai/gpt-4o", api_key_env=value).options.api_key_env == value


def test_a_key_pasted_into_a_router_deployment_is_refused_without_echoing_it():
    router = [{"litellm_params": {"model": "openai/m", "api_base": "http://127.0.0.1:9/v1", "api_key_env": PASTED_KEY}}]
    with pytest.raises(ConfigError) as err:
        LiteLLMBackend(model="m", router=router)
    assert "api_key_env" in str(err.value) and PASTED_KEY not in str(err.value)


def test_povagent_run_with_a_pasted_key_stops_before_writing_anything(tmp_path, mini_root):
    path = pipeline_yaml(tmp_path, mini_root, {"api_base": "http://127.0.0.1:9/v1", "api_key_env": PASTED_KEY})
    result = subprocess.run([sys.executable, "-m", "povagent.cli", "run", str(path), "--quiet"], capture_output=True, text=True, timeout=60)
    output = result.stdout + result.stderr
    assert result.returncode != 0
    assert PASTED_KEY not in output and "Traceback" not in output
    assert "api_key_env" in output and "name of an environment variable" in output
    assert not (tmp_path / "run" / "config.yaml").exists()


def test_the_redactor_hides_a_key_pasted_into_any_env_field():
    r = Redactor()
    assert r.value({"api_key_env": PASTED_KEY}) == {"api_key_env": REDACTED}
    assert r.value({"api_key_env": "OPENAI_API_KEY", "token_env": "HF_TOKEN"}) == {"api_key_env": "OPENAI_API_KEY", "token_env": "HF_TOKEN"}
