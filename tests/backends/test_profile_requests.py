"""What a paper profile actually sends: the authors' runner's generation settings and prompts
arrive at an OpenAI-compatible server (a loopback server standing in for vLLM or OpenAI)."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from povagent.config.pipeline import load_pipeline
from povagent.run.runner import run_pipeline
from povagent.testing.loopback_server import LoopbackServer, RecordedRequest

pytestmark = pytest.mark.timeout(90)


def answer_for(request: RecordedRequest) -> str:
    images = [p for p in request.user_parts() if p.get("type") == "image_url"]
    return '{"selected_image": 0, "x": 10, "y": 20}' if len(images) > 1 else '{"x": 10, "y": 20}'


def run_model(tmp_path: Path, mini_root: Path, server: LoopbackServer, model: str, conditions: list[str], **backend) -> None:
    doc = {
        "dataset": str(mini_root),
        "backend": {"name": "litellm", "options": {"model": model, "api_base": server.url, **backend}},
        "strategy": "basic",
        "instances": {"conditions": conditions, "houses": ["train_house_00000"], "directions": ["left"]},
        "retry": {"attempts": 1, "initial_wait": 0.0, "max_wait": 0.0},
        "timeout": 20,
        "cache": False,
        "output": str(tmp_path / model),
    }
    path = tmp_path / f"{model}.yaml"
    path.write_text(yaml.safe_dump(doc))
    run_pipeline(load_pipeline(path))


def test_a_vllm_profile_sends_256_tokens_at_temperature_0(tmp_path, mini_root):
    with LoopbackServer(reply=answer_for, max_lifetime_s=80) as server:
        run_model(tmp_path, mini_root, server, "qwen3-vl-8b", ["a", "c"])
    assert len(server.requests) == 2
    for request in server.requests:
        assert request.body["max_tokens"] == 256 and request.body["temperature"] == 0.0


def test_the_gpt_profile_sends_256_completion_tokens(tmp_path, mini_root, monkeypatch):
    monkeypatch.setenv("POVAGENT_TEST_KEY", "sk-test")
    with LoopbackServer(reply=answer_for, max_lifetime_s=80) as server:
        run_model(tmp_path, mini_root, server, "gpt-5.4", ["c"], api_key_env="POVAGENT_TEST_KEY")
    (request,) = server.requests
    # litellm sends max_tokens as GPT-5's max_completion_tokens, as the runner set it
    assert request.body["max_completion_tokens"] == 256 and "temperature" not in request.body


def test_the_molmopoint_profile_sends_its_point_prompt(tmp_path, mini_root):
    with LoopbackServer(reply='<points coords="1 1 500 500">it</points>', max_lifetime_s=80) as server:
        run_model(tmp_path, mini_root, server, "molmopoint-8b", ["a"])
    (request,) = server.requests
    texts = [p["text"] for p in request.user_parts() if p.get("type") == "text"]
    assert texts[:3] == ["Image 0:", "Image 1:", "Image 2:"]
    assert texts[-1].endswith("WOULD be located.\n\nPoint to the center of the target object.")
    assert request.body["max_tokens"] == 256 and "temperature" not in request.body
