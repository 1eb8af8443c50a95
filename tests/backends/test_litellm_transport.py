"""Which litellm deployments may be sent images by reference (plugins/backends/litellm_backend.py).

Only an OpenAI-compatible server at an ``api_base`` (``openai/...`` or ``hosted_vllm/...``)
fetches ``file://``/``http://`` URLs itself; a hosted provider's own endpoint cannot, so
``file``/``http`` are refused there before the run starts, with a message saying what to do.
"""

from __future__ import annotations

import asyncio

import pytest
from PIL import Image

from povagent.answers.spec import AnswerSpec, point_answer_schema
from povagent.errors import ConfigError
from povagent.exchange.images import ImageStore
from povagent.exchange.messages import ImagePart, Message, Request
from povagent.exchange.transport import FileTransport, image_transport
from povagent.interfaces import Backend, PermanentBackendError
from povagent_plugins.backends.litellm_backend import LiteLLMBackend


@pytest.mark.parametrize(
    "options",
    [
        {"model": "openai/gpt-5.4"},
        {"model": "gemini/gemini-2.5-flash"},
        {"model": "anthropic/claude-sonnet-4-5"},
        {"model": "gpt-5.4"},  # a bare name: litellm infers the provider
        {"model": "gemini/gemini-2.5-flash", "api_base": "http://localhost:8000/v1"},  # not OpenAI-compatible
    ],
    ids=["openai-hosted", "gemini", "anthropic", "bare-name", "gemini-with-api-base"],
)
@pytest.mark.parametrize("transport", ["file", "http"])
def test_hosted_endpoints_refuse_references_before_the_run(options, transport):
    backend = LiteLLMBackend(**options)
    with pytest.raises(ConfigError) as err:
        backend.check_image_transport(transport)
    message = str(err.value)
    assert f"transport {transport}" in message
    assert options["model"] in message
    assert "transport: inline" in message  # what to do instead


@pytest.mark.parametrize(
    "model",
    ["openai/loopback-vlm", "hosted_vllm/Qwen/Qwen3-VL-8B-Instruct"],
)
@pytest.mark.parametrize("transport", ["inline", "file", "http"])
def test_an_openai_compatible_server_at_an_api_base_takes_every_transport(model, transport):
    LiteLLMBackend(model=model, api_base="http://127.0.0.1:8000/v1").check_image_transport(transport)


def test_inline_is_accepted_everywhere():
    LiteLLMBackend(model="gemini/gemini-2.5-flash").check_image_transport("inline")


def test_a_router_with_one_hosted_deployment_refuses_references():
    backend = LiteLLMBackend(
        model="vlm",
        router=[
            {"litellm_params": {"model": "hosted_vllm/q", "api_base": "http://a:8000/v1"}},
            {"litellm_params": {"model": "openai/gpt-5.4"}},
        ],
    )
    with pytest.raises(ConfigError, match=r"openai/gpt-5.4"):
        backend.check_image_transport("file")


def test_a_router_of_vllm_replicas_takes_references():
    LiteLLMBackend(
        model="vlm",
        router=[
            {"litellm_params": {"model": "hosted_vllm/q", "api_base": f"http://replica{i}:8000/v1"}} for i in range(2)
        ],
    ).check_image_transport("http")


def test_a_self_hosted_profile_with_api_base_takes_references():
    LiteLLMBackend(model="qwen3-vl-8b", api_base="http://127.0.0.1:8000/v1").check_image_transport("file")


def test_a_backend_that_skipped_the_check_still_never_sends_a_reference_to_a_hosted_provider(tmp_path):
    # an embedding that attaches a transport itself: refused at the request, without a call
    store = ImageStore()
    path = tmp_path / "f.png"
    Image.new("RGB", (4, 4), "red").save(path)
    h = store.add_file(path).image_hash
    request = Request(messages=(Message("user", (ImagePart(h),)),), answer=AnswerSpec(schema=point_answer_schema(4, 4)))
    backend = LiteLLMBackend(model="gemini/gemini-2.5-flash")
    with image_transport(store, FileTransport(tmp_path / "cache")), pytest.raises(PermanentBackendError, match="inline"):
        asyncio.run(backend.complete(request, store))


def test_backends_accept_every_transport_by_default():
    class Offline(Backend):
        def identity(self):
            return {"backend": "offline"}

        async def complete(self, request, images):
            raise NotImplementedError

    for transport in ("inline", "file", "http"):
        Offline().check_image_transport(transport)
