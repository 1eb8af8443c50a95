"""The litellm backend against a real OpenAI-compatible HTTP server on 127.0.0.1.

What arrives at the server (30 labelled images in order, the prompt, the generation
parameters, the key from the environment), how each failure is classified (429 with
Retry-After, 500, slow answers past the timeout, dropped connections are transient; 400 and
401 are permanent), that litellm itself never retries underneath the runner, and the Router
over two local servers. Every test is bounded by a timeout.
"""

from __future__ import annotations

import asyncio
import time

import pytest

from povagent.exchange.messages import GenerationParams, ImagePart
from povagent.interfaces import PermanentBackendError, TransientBackendError
from povagent.testing.loopback_server import Fault, LoopbackServer, Reply
from povagent_plugins.backends.litellm_backend import LiteLLMBackend

pytestmark = pytest.mark.timeout(30)


def run(coro):
    return asyncio.run(coro)


@pytest.fixture
def second_loopback():
    """Another loopback server (the Router's second deployment)."""
    with LoopbackServer(reply='{"selected_image": 1, "x": 30, "y": 40}', max_lifetime_s=60) as server:
        yield server


def direct(server: LoopbackServer, **options) -> LiteLLMBackend:
    return LiteLLMBackend(model="openai/loopback-model", api_base=server.url, api_key_env="POVAGENT_TEST_KEY", **options)


def router(*servers: LoopbackServer, **settings) -> LiteLLMBackend:
    deployments = [
        {"litellm_params": {"model": "openai/loopback-model", "api_base": s.url, "api_key_env": "POVAGENT_TEST_KEY"}}
        for s in servers
    ]
    return LiteLLMBackend(model="loopback-group", router=deployments, router_settings={"retry_after": 0, **settings})


def only_request(*servers: LoopbackServer):
    recorded = [r for s in servers for r in s.requests]
    assert len(recorded) == 1
    return recorded[0]


# -- what the server receives -------------------------------------------------------------------
@pytest.mark.parametrize("mode", ["direct", "router"])
def test_server_receives_30_images_in_order_each_after_its_label(mode, make_request, store, loopback, second_loopback, api_key):
    backend = direct(loopback) if mode == "direct" else router(loopback, second_loopback)
    request = make_request(30)
    run(backend.complete(request, store))
    parts = only_request(loopback, second_loopback).user_parts()
    hashes = [p.image_hash for p in request.messages[1].parts if isinstance(p, ImagePart)]
    assert len(hashes) == 30
    for i, h in enumerate(hashes):
        assert parts[2 * i] == {"type": "text", "text": f"Image {i}:"}
        assert parts[2 * i + 1] == {"type": "image_url", "image_url": {"url": store.data_url(h)}}
    assert parts[60] == {"type": "text", "text": "Sentence: the mug is left of the sofa."}
    assert len(parts) == 61


def test_server_receives_the_system_prompt_first(make_request, store, loopback, api_key):
    run(direct(loopback).complete(make_request(2), store))
    assert loopback.requests[0].body["messages"][0] == {"role": "system", "content": "You are a robot."}


@pytest.mark.parametrize("mode", ["direct", "router"])
def test_server_receives_the_generation_parameters(mode, make_request, store, loopback, second_loopback, api_key):
    options = {"temperature": 0.25, "extra": {"top_p": 0.9, "seed": 7}}
    backend = direct(loopback, **options) if mode == "direct" else router(loopback, second_loopback)
    if mode == "router":
        backend = LiteLLMBackend(**{**backend.options.model_dump(), **options})
    run(backend.complete(make_request(2, generation=GenerationParams(max_tokens=123)), store))
    body = only_request(loopback, second_loopback).body
    assert body["model"] == "loopback-model"
    assert body["max_tokens"] == 123
    assert body["temperature"] == 0.25
    assert body["top_p"] == 0.9 and body["seed"] == 7


def test_server_receives_the_key_from_the_environment(make_request, store, loopback, api_key):
    run(direct(loopback).complete(make_request(1), store))
    assert loopback.requests[0].headers["authorization"] == f"Bearer {api_key}"


def test_answer_text_and_usage_come_back(make_request, store, loopback, api_key):
    response = run(direct(loopback).complete(make_request(2), store))
    assert response.text == '{"selected_image": 0, "x": 10, "y": 20}'
    assert (response.usage.prompt_tokens, response.usage.completion_tokens) == (10, 5)
    assert response.model == "loopback-model"


# -- faults: transient ones are raised for the runner to retry, exactly one attempt each ----------
def test_rate_limit_is_transient_with_the_servers_retry_after(make_request, store, loopback, api_key):
    loopback.script(Fault(429, retry_after=7))
    with pytest.raises(TransientBackendError) as err:
        run(direct(loopback).complete(make_request(1), store))
    assert err.value.status == 429 and err.value.retry_after == 7
    assert loopback.request_count == 1  # litellm did not retry underneath the runner


def test_server_error_is_transient(make_request, store, loopback, api_key):
    loopback.script(Fault(500))
    with pytest.raises(TransientBackendError) as err:
        run(direct(loopback).complete(make_request(1), store))
    assert err.value.status == 500 and loopback.request_count == 1


def test_slow_answer_past_the_timeout_is_transient_and_prompt(make_request, store, loopback, api_key):
    loopback.script(Reply("late", delay_s=20))
    started = time.monotonic()
    with pytest.raises(TransientBackendError):
        run(direct(loopback, timeout=0.5).complete(make_request(1), store))
    assert time.monotonic() - started < 5
    assert loopback.request_count == 1


def test_dropped_connection_is_transient(make_request, store, loopback, api_key):
    loopback.script(Fault(drop=True))
    with pytest.raises(TransientBackendError):
        run(direct(loopback).complete(make_request(1), store))
    assert loopback.request_count == 1


def test_next_attempt_after_a_transient_fault_succeeds(make_request, store, loopback, api_key):
    backend = direct(loopback)
    loopback.script(Fault(500), Fault(drop=True))

    async def two_failures_then_answer():
        for _ in range(2):
            with pytest.raises(TransientBackendError):
                await backend.complete(make_request(1), store)
        return await backend.complete(make_request(1), store)

    assert run(two_failures_then_answer()).text.startswith("{")
    assert loopback.request_count == 3


# -- faults: permanent ones ---------------------------------------------------------------------
@pytest.mark.parametrize("status", [400, 401])
def test_client_errors_are_permanent_and_not_retried(status, make_request, store, loopback, api_key):
    loopback.script(Fault(status, message=f"injected {status}"))
    with pytest.raises(PermanentBackendError) as err:
        run(direct(loopback).complete(make_request(1), store))
    assert err.value.status == status and f"injected {status}" in str(err.value)
    assert loopback.request_count == 1


# -- the Router over two local servers ----------------------------------------------------------
def test_router_spreads_requests_over_both_servers(make_request, store, loopback, second_loopback, api_key):
    backend = router(loopback, second_loopback)

    async def many():
        return await asyncio.gather(*[backend.complete(make_request(1), store) for _ in range(24)])

    assert len(run(many())) == 24
    assert loopback.request_count > 0 and second_loopback.request_count > 0
    assert loopback.request_count + second_loopback.request_count == 24


def test_router_retries_inside_and_then_reports_a_permanent_failure(make_request, store, loopback, second_loopback, api_key):
    loopback.reply = second_loopback.reply = Fault(500)
    backend = router(loopback, second_loopback, num_retries=2)
    assert backend.retries_inside
    with pytest.raises(PermanentBackendError, match="Router retries") as err:
        run(backend.complete(make_request(1), store))
    assert err.value.status == 500
    assert loopback.request_count + second_loopback.request_count == 3  # 1 + the Router's 2 retries


def test_router_does_not_retry_a_bad_request(make_request, store, loopback, second_loopback, api_key):
    loopback.reply = second_loopback.reply = Fault(400)
    with pytest.raises(PermanentBackendError) as err:
        run(router(loopback, second_loopback).complete(make_request(1), store))
    assert err.value.status == 400
    assert loopback.request_count + second_loopback.request_count == 1


def test_router_identity_names_models_not_hosts(loopback, second_loopback):
    ident = router(loopback, second_loopback).identity()
    assert ident["router_models"] == ["openai/loopback-model"]
    assert loopback.url not in str(ident)


# -- answers that are no answers ---------------------------------------------------------------
@pytest.mark.parametrize("reply", [Reply(None), Reply("", no_choices=True)], ids=["null-content", "no-choices"])
def test_an_empty_response_is_transient_not_an_empty_answer(reply, make_request, store, loopback, api_key):
    loopback.script(reply)
    with pytest.raises(TransientBackendError) as info:
        run(direct(loopback).complete(make_request(1), store))
    assert info.value.kind == "empty_response"


def test_start_imports_litellm_and_finds_a_missing_key(monkeypatch, loopback):
    monkeypatch.delenv("POVAGENT_TEST_KEY", raising=False)
    with pytest.raises(PermanentBackendError, match="POVAGENT_TEST_KEY") as info:
        run(direct(loopback).start())
    assert info.value.kind == "missing_key" and loopback.request_count == 0
