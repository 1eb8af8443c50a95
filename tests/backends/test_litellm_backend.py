"""The litellm backend without a network: litellm's own mock_response (unit level)."""

from __future__ import annotations

import asyncio
import json
import os
import subprocess
import sys

import pytest

from povagent.engine.llm_import import import_litellm
from povagent.errors import ConfigError
from povagent.exchange.messages import GenerationParams
from povagent.interfaces import PermanentBackendError, TransientBackendError
from povagent_plugins.backends.litellm_backend import LiteLLMBackend

pytestmark = pytest.mark.timeout(60)


def run(coro):
    return asyncio.run(coro)


def mocked(reply, **options) -> LiteLLMBackend:
    """A backend whose every call litellm answers with ``reply`` (text or exception)."""
    return LiteLLMBackend(**{"model": "openai/gpt-4o", **options, "extra": {"mock_response": reply, **options.get("extra", {})}})


def test_returns_the_model_text(make_request, store):
    response = run(mocked('{"x": 1, "y": 2}').complete(make_request(1), store))
    assert response.text == '{"x": 1, "y": 2}'


def test_records_tokens_and_cost_per_request(make_request, store):
    response = run(mocked("ok").complete(make_request(1), store))
    assert response.usage.prompt_tokens == 10 and response.usage.completion_tokens == 20
    # gpt-4o is in litellm's bundled cost map: the price is known offline
    assert response.usage.cost_usd is not None and response.usage.cost_usd > 0


def test_cost_of_an_unknown_model_is_none(make_request, store):
    response = run(mocked("ok", model="openai/no-such-model-xyz").complete(make_request(1), store))
    assert response.usage.cost_usd is None


def test_records_latency(make_request, store):
    response = run(mocked("ok").complete(make_request(1), store))
    assert response.latency_s > 0


def test_rate_limit_is_transient(make_request, store):
    with pytest.raises(TransientBackendError) as err:
        run(mocked("litellm.RateLimitError").complete(make_request(1), store))
    assert err.value.status == 429


def test_internal_server_error_is_transient(make_request, store):
    with pytest.raises(TransientBackendError) as err:
        run(mocked("litellm.InternalServerError").complete(make_request(1), store))
    assert err.value.status == 500


def test_timeout_is_transient(make_request, store):
    backend = mocked("late", timeout=0.2, extra={"mock_timeout": True})
    with pytest.raises(TransientBackendError):
        run(backend.complete(make_request(1), store))


def test_context_window_exceeded_is_permanent(make_request, store):
    with pytest.raises(PermanentBackendError) as err:
        run(mocked("litellm.ContextWindowExceededError").complete(make_request(1), store))
    assert err.value.status == 400


def test_authentication_error_is_permanent(make_request, store):
    litellm = import_litellm()
    exc = litellm.AuthenticationError(message="bad key", llm_provider="openai", model="gpt-4o")
    with pytest.raises(PermanentBackendError) as err:
        run(mocked(exc).complete(make_request(1), store))
    assert err.value.status == 401


def test_error_messages_never_carry_the_key(make_request, store, api_key):
    litellm = import_litellm()
    exc = litellm.AuthenticationError(message=f"Incorrect API key provided: {api_key}", llm_provider="openai", model="x")
    with pytest.raises(PermanentBackendError) as err:
        run(mocked(exc, api_key_env="POVAGENT_TEST_KEY").complete(make_request(1), store))
    assert api_key not in str(err.value) and "***" in str(err.value)


def test_missing_key_variable_is_a_permanent_error_naming_it(make_request, store, monkeypatch):
    monkeypatch.delenv("POVAGENT_UNSET_KEY", raising=False)
    with pytest.raises(PermanentBackendError, match="POVAGENT_UNSET_KEY"):
        run(mocked("ok", api_key_env="POVAGENT_UNSET_KEY").complete(make_request(1), store))


def test_identity_names_model_and_answer_changing_options_only(api_key):
    backend = LiteLLMBackend(
        model="hosted_vllm/Qwen/Qwen3-VL-8B-Instruct",
        api_base="http://gpu:8000/v1",
        api_key_env="POVAGENT_TEST_KEY",
        temperature=0.0,
        extra={"top_p": 0.9},
        timeout=30,
    )
    ident = backend.identity()
    assert ident == {
        "backend": "litellm",
        "model": "hosted_vllm/Qwen/Qwen3-VL-8B-Instruct",
        "api_base": "http://gpu:8000/v1",
        "temperature": 0.0,
        "max_tokens": None,
        "extra": {"top_p": 0.9},
    }
    assert api_key not in json.dumps(ident) and "POVAGENT_TEST_KEY" not in json.dumps(ident)


def test_backend_options_override_the_strategys_generation(make_request):
    backend = LiteLLMBackend(model="openai/gpt-4o", temperature=0.3, max_tokens=64, extra={"top_p": 0.5})
    request = make_request(1, generation=GenerationParams(max_tokens=256, temperature=1.0))
    assert backend.generation_kwargs(request) == {"max_tokens": 64, "temperature": 0.3, "top_p": 0.5}


def test_strategys_generation_is_kept_when_the_backend_sets_none(make_request):
    backend = LiteLLMBackend(model="openai/gpt-4o")
    request = make_request(1, generation=GenerationParams(max_tokens=1024, temperature=0.7))
    assert backend.generation_kwargs(request) == {"max_tokens": 1024, "temperature": 0.7}


def test_literal_api_key_option_is_refused():
    with pytest.raises(ConfigError, match="api_key_env"):
        LiteLLMBackend(model="openai/gpt-4o", api_key="sk-live")


def test_literal_api_key_in_extra_is_refused():
    with pytest.raises(ConfigError, match="api_key_env"):
        LiteLLMBackend(model="openai/gpt-4o", extra={"api_key": "sk-live"})


def test_literal_api_key_in_a_router_deployment_is_refused():
    with pytest.raises(ConfigError, match=r"router\[0\]"):
        LiteLLMBackend(router=[{"model_name": "m", "litellm_params": {"model": "openai/m", "api_key": "sk-live"}}])


def test_litellm_retries_cannot_be_stacked_through_extra():
    with pytest.raises(ConfigError, match="num_retries"):
        LiteLLMBackend(model="openai/gpt-4o", extra={"num_retries": 3})


def test_unknown_option_is_a_config_error_listing_known_ones():
    with pytest.raises(ConfigError, match=r"option 'temprature'.*temperature"):
        LiteLLMBackend(model="openai/gpt-4o", temprature=0.1)


def test_model_is_required():
    with pytest.raises(ConfigError, match="option 'model'"):
        LiteLLMBackend()


def test_profile_name_resolves_to_its_litellm_model():
    backend = LiteLLMBackend(model="gemini-robotics-er")
    assert backend.model == "gemini/gemini-robotics-er-1.6-preview"
    assert backend.profile is not None and backend.profile.default_parser == "official"


def test_profile_backend_defaults_apply_under_the_users_options():
    backend = LiteLLMBackend(model="gpt-5.4", extra={"reasoning_effort": "low"})
    assert backend.options.extra == {"drop_params": True, "reasoning_effort": "low"}


def test_self_hosted_profile_without_api_base_is_a_config_error():
    with pytest.raises(ConfigError, match=r"qwen3-vl-8b.*api_base"):
        LiteLLMBackend(model="qwen3-vl-8b")


def test_self_hosted_profile_with_api_base_is_accepted():
    backend = LiteLLMBackend(model="qwen3-vl-8b", api_base="http://gpu:8000/v1")
    assert backend.model == "hosted_vllm/Qwen/Qwen3-VL-8B-Instruct"


def test_direct_calls_leave_retries_to_the_runner():
    assert LiteLLMBackend(model="openai/gpt-4o").retries_inside is False


def test_router_settings_without_a_router_are_a_config_error():
    with pytest.raises(ConfigError, match="router_settings apply to a router"):
        LiteLLMBackend(model="openai/gpt-4o", router_settings={"num_retries": 2})


def test_a_profile_refuses_a_condition_it_cannot_answer_before_calling(make_request, store, mini_dataset):
    a = mini_dataset.instances(conditions=["a"])[0]
    c = mini_dataset.instances(conditions=["c"])[0]
    backend = LiteLLMBackend(model="robopoint", api_base="http://127.0.0.1:9/v1", extra={"mock_response": "[(0.5, 0.5)]"})
    with pytest.raises(PermanentBackendError, match=r"'robopoint' answers Given \(c\) only, not Inferred \(a\)"):
        run(backend.complete(make_request(3, instance=a), store))
    assert run(backend.complete(make_request(1, instance=c), store)).text == "[(0.5, 0.5)]"


def test_litellm_is_imported_off_the_event_loop():
    # in a fresh interpreter: while the first request imports litellm (seconds), the loop ticks
    code = """
import asyncio, sys, time
from povagent_plugins.backends.litellm_backend import LiteLLMBackend
from povagent.exchange.messages import GenerationParams, Message, Request
from povagent.answers.spec import AnswerSpec, point_answer_schema
assert "litellm" not in sys.modules
backend = LiteLLMBackend(model="openai/gpt-4o", extra={"mock_response": "ok"})
request = Request(messages=(Message.text("user", "hi"),), answer=AnswerSpec(schema=point_answer_schema(512, 512)),
                  generation=GenerationParams(max_tokens=8))
async def main():
    beats = []
    async def tick():
        while True:
            beats.append(time.perf_counter())
            await asyncio.sleep(0.01)
    ticker = asyncio.create_task(tick())
    await asyncio.sleep(0)
    started = time.perf_counter()
    text = (await backend.complete(request, None)).text
    ended = time.perf_counter()
    ticker.cancel()
    marks = [started] + [b for b in beats if started < b < ended] + [ended]
    print(text, max(b - a for a, b in zip(marks, marks[1:])), ended - started)
asyncio.run(main())
"""
    env = {k: v for k, v in os.environ.items() if not k.startswith("LITELLM_")}
    # the timeout only ends a hang: at load 20 on two cores the import alone takes a minute
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=240)
    assert done.returncode == 0, done.stderr
    text, longest_gap, elapsed = done.stdout.split()
    assert text == "ok"
    # the import takes most of `elapsed`: on the loop, the loop would stand still for all of it
    # (one gap as long as the call); off it, the loop keeps beating. Both are measured in this
    # one process, so the machine's load stretches them alike.
    assert float(longest_gap) < 0.5 * float(elapsed), (longest_gap, elapsed)


@pytest.mark.parametrize("where", ["extra", "router"])
def test_a_credential_header_in_the_yaml_is_refused(where):
    headers = {"extra_headers": {"Authorization": "Bearer sk-live-123"}}
    options = (
        {"model": "openai/gpt-4o", "extra": headers}
        if where == "extra"
        else {"router": [{"litellm_params": {"model": "openai/m", **headers}}]}
    )
    with pytest.raises(ConfigError, match=r"carries a credential \(Authorization\).*api_key_env"):
        LiteLLMBackend(**options)


def test_litellm_keeps_the_concurrent_path_with_its_timeouts_and_slots():
    # it waits on a server: never declared as answering in this process (see Backend.answers_in_process)
    assert LiteLLMBackend(model="openai/gpt-4o").answers_in_process is False
