"""An OpenAI-compatible server of one's own that needs no key (vLLM without ``--api-key``,
Ollama's ``/v1``), reached as ``openai/...`` with ``api_base``: the run goes on with no key set,
and a server that does ask for one is reported as such. Real HTTP: a loopback server the test
starts (:class:`povagent.testing.loopback_server.LoopbackServer`)."""

from __future__ import annotations

import pytest
import yaml

from povagent.config.pipeline import load_pipeline
from povagent.run.runner import run_pipeline
from povagent.testing.loopback_server import Fault, LoopbackServer
from povagent_plugins.backends.litellm_backend import NO_KEY, keyless_placeholder

#: A ViewSpatial-Bench file in its published layout (gold A, B, A, C), written per test.
QUESTIONS = [
    {"question_type": "Camera perspective - Relative Direction", "image_path": ["images/scene.png"],
     "question": f"Where is object {i}?", "answer": f"{gold}. x", "choices": "A. x\nB. y\nC. z\nD. w"}
    for i, gold in enumerate("ABAC")
]  # fmt: skip


@pytest.fixture
def set_file(tmp_path):
    """``set_file("viewspatial") -> Path``: the file above, beside the image it names."""
    import json

    from PIL import Image

    (tmp_path / "set" / "images").mkdir(parents=True)
    Image.new("RGB", (32, 24), (90, 40, 60)).save(tmp_path / "set" / "images" / "scene.png")
    (tmp_path / "set" / "viewspatial.json").write_text(json.dumps(QUESTIONS), encoding="utf-8")
    return lambda format: tmp_path / "set" / f"{format}.json"


@pytest.fixture
def no_openai_key(monkeypatch):
    monkeypatch.delenv("OPENAI_API_KEY", raising=False)


def _pipeline(tmp_path, set_file, url: str, **backend_options) -> object:
    path = tmp_path / "keyless.yaml"
    path.write_text(yaml.safe_dump({
        "dataset": {"path": str(set_file("viewspatial")), "format": "viewspatial"},
        "backend": {"name": "litellm", "options": {"model": "openai/qwen3-vl", "api_base": url, **backend_options}},
        "cache": False, "timeout": 10, "concurrency": 2, "output": str(tmp_path / "run"),
    }))  # fmt: skip
    return path


def test_a_local_server_needing_no_key_answers_without_one(tmp_path, set_file, no_openai_key):
    with LoopbackServer(reply="A", max_lifetime_s=60) as server:
        result = run_pipeline(load_pipeline(_pipeline(tmp_path, set_file, server.url)))
        assert len(server.requests) == 4
    assert result.n_total == 4 and result.summary.metrics["choice"].overall["response_rate"].value == 1.0
    # always "A": questions 1 and 3
    assert result.summary.metrics["choice"].overall["accuracy"].value == 0.5


def test_the_placeholder_is_sent_in_the_keys_place_and_kept_out_of_the_run_folder(tmp_path, set_file, no_openai_key):
    with LoopbackServer(reply="A", max_lifetime_s=60) as server:
        result = run_pipeline(load_pipeline(_pipeline(tmp_path, set_file, server.url)))
        assert {r.headers.get("authorization") for r in server.requests} == {f"Bearer {NO_KEY}"}
    # nothing redacted for it: a reply mentioning "no-key" is kept as written
    assert "[REDACTED]" not in (result.run_dir / "results.jsonl").read_text(encoding="utf-8")


def test_a_set_key_is_sent_rather_than_the_placeholder(tmp_path, set_file, monkeypatch):
    monkeypatch.setenv("OPENAI_API_KEY", "sk-test-local-123456")
    with LoopbackServer(reply="A", max_lifetime_s=60) as server:
        run_pipeline(load_pipeline(_pipeline(tmp_path, set_file, server.url)))
        assert {r.headers.get("authorization") for r in server.requests} == {"Bearer sk-test-local-123456"}


def test_a_server_asking_for_a_key_stops_the_run_saying_so(tmp_path, set_file, no_openai_key):
    with LoopbackServer(reply=Fault(status=401, message="invalid api key"), max_lifetime_s=60) as server:
        result = run_pipeline(load_pipeline(_pipeline(tmp_path, set_file, server.url)))
        assert len(server.requests) >= 1
    assert result.summary.metrics["choice"].overall["response_rate"].value == 0.0
    log = (result.run_dir / "log.jsonl").read_text(encoding="utf-8")
    assert "auth" in log and "key" in log.lower()


def test_no_placeholder_for_a_hosted_provider_or_a_named_variable(no_openai_key):
    assert keyless_placeholder("openai/gpt-4o", None) is None  # OpenAI's own endpoint needs the real key
    assert keyless_placeholder("gemini/gemini-2.5-flash", "http://127.0.0.1:8000/v1") is None
    assert keyless_placeholder("openai/qwen", "http://127.0.0.1:8000/v1") == NO_KEY
