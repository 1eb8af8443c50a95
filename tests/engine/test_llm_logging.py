"""litellm's base64 truncation for logging is skipped for povagent's calls only while nothing can
read litellm's logging payload (povagent/engine/llm_logging.py), against the pinned litellm.

Every call goes through the litellm backend to the loopback server with real PNG data URLs;
a spy counts how often litellm's own truncation function runs, and a real litellm
``CustomLogger`` reads the standard logging payload it is handed.
"""

from __future__ import annotations

import asyncio
import base64
import io
import json
import logging
import os
import re

import pytest
from PIL import Image

from povagent.answers.spec import AnswerSpec, point_answer_schema
from povagent.engine.llm_import import import_litellm
from povagent.engine.llm_logging import (
    CALLBACK_LISTS,
    LITELLM_LOGGERS,
    NOT_CALLBACK_LISTS,
    PRINT_PAYLOAD_SETTING,
    USER_SETTING,
    logging_payload_unobserved,
    povagent_call,
    skip_truncation_when_unobserved,
)
from povagent.exchange.images import ImageStore
from povagent.exchange.messages import GenerationParams, ImagePart, Message, Request, TextPart
from povagent_plugins.backends.litellm_backend import LiteLLMBackend

pytestmark = pytest.mark.timeout(60)

#: A base64 run this long is (part of) a whole image: litellm's placeholders are a few dozen characters.
WHOLE_IMAGE = re.compile(r"[A-Za-z0-9+/]{2000,}")


@pytest.fixture(scope="module")
def litellm():
    """litellm with the wrapper installed (as the backend's ``start`` does)."""
    module = import_litellm()
    if os.environ.get(USER_SETTING) is None:
        assert skip_truncation_when_unobserved(module)
    return module


@pytest.fixture
def quiet_litellm(litellm, monkeypatch):
    """No callback in any of litellm's lists (a Router made by another test leaves its own
    there), debug off, the payload not printed: nothing can read the logging payload."""
    for name in CALLBACK_LISTS:
        monkeypatch.setattr(litellm, name, [])
    monkeypatch.setattr(litellm, "set_verbose", False)
    monkeypatch.delenv(PRINT_PAYLOAD_SETTING, raising=False)
    monkeypatch.delenv(USER_SETTING, raising=False)
    loggers = [logging.getLogger(name) for name in LITELLM_LOGGERS]
    levels = [lg.level for lg in loggers]
    for lg in loggers:
        lg.setLevel(logging.WARNING)
    assert logging_payload_unobserved(litellm)
    yield litellm
    for lg, level in zip(loggers, levels):
        lg.setLevel(level)


@pytest.fixture
def truncations(litellm, monkeypatch) -> list[int]:
    """Each run of litellm's own truncation (the function its async form delegates to)."""
    from litellm.litellm_core_utils import logging_utils

    seen: list[int] = []
    real = logging_utils.truncate_base64_in_messages

    def counting(messages):
        seen.append(1)
        return real(messages)

    monkeypatch.setattr(logging_utils, "truncate_base64_in_messages", counting)
    return seen


@pytest.fixture
def image_request():
    """A request with three real 64x64 noise PNGs (each data URL ~16 K characters)."""
    store = ImageStore()
    parts: list = []
    for i in range(3):
        im = Image.frombytes("RGB", (64, 64), os.urandom(64 * 64 * 3))
        parts += [TextPart(f"Image {i}:"), ImagePart(store.add_pil(im).image_hash)]
    parts.append(TextPart("Sentence: the mug is left of the sofa."))
    spec = AnswerSpec(schema=point_answer_schema(512, 512), n_frames=1, asks_frame=False)
    return Request(messages=(Message("user", tuple(parts)),), answer=spec, generation=GenerationParams(max_tokens=16)), store


def _backend(server, **options) -> LiteLLMBackend:
    os.environ.setdefault("POVAGENT_LOGGING_TEST_KEY", "k")
    return LiteLLMBackend(model="hosted_vllm/loopback", api_base=server.url, api_key_env="POVAGENT_LOGGING_TEST_KEY", **options)


async def _through_backend(backend: LiteLLMBackend, request, store) -> None:
    from litellm.litellm_core_utils.logging_worker import GLOBAL_LOGGING_WORKER

    await backend.start()
    await backend.complete(request, store)
    # litellm logs after returning, in its logging worker: wait for it
    await asyncio.wait_for(GLOBAL_LOGGING_WORKER.flush(), 20)


def _watcher(litellm):
    """A real litellm CustomLogger keeping every standard logging payload's messages."""
    from litellm.integrations.custom_logger import CustomLogger

    class Watch(CustomLogger):
        def __init__(self) -> None:
            super().__init__()
            self.logged: list[str] = []

        async def async_log_success_event(self, kwargs, response_obj, start_time, end_time):
            payload = kwargs.get("standard_logging_object") or {}
            self.logged.append(json.dumps(payload.get("messages"), default=str))

    return Watch()


# -- nobody listening: skipped for our calls ------------------------------------------------------
def test_with_nothing_listening_our_calls_skip_the_truncation(quiet_litellm, truncations, loopback_server, image_request):
    request, store = image_request
    asyncio.run(_through_backend(_backend(loopback_server), request, store))
    assert len(loopback_server.requests) == 1
    assert truncations == []


def test_litellm_calls_that_are_not_ours_are_still_truncated(quiet_litellm, truncations, loopback_server, image_request):
    request, store = image_request
    from litellm.litellm_core_utils.logging_worker import GLOBAL_LOGGING_WORKER

    from povagent_plugins.backends.openai_messages import openai_messages

    async def bare() -> None:
        await quiet_litellm.acompletion(model="hosted_vllm/loopback", api_base=loopback_server.url, api_key="k",
                                        messages=openai_messages(request, store), max_tokens=16, num_retries=0)
        await asyncio.wait_for(GLOBAL_LOGGING_WORKER.flush(), 20)

    asyncio.run(bare())
    assert truncations == [1]


def test_the_mark_is_gone_after_our_call():
    from povagent.engine import llm_logging

    with povagent_call({}):
        assert llm_logging._POVAGENT_CALL.get()
    assert not llm_logging._POVAGENT_CALL.get()


# -- somebody listening: litellm truncates as usual -----------------------------------------------
def test_a_registered_callback_receives_truncated_images_never_whole_ones(quiet_litellm, truncations, loopback_server, image_request, monkeypatch):
    request, store = image_request
    watch = _watcher(quiet_litellm)
    monkeypatch.setattr(quiet_litellm, "callbacks", [watch])
    asyncio.run(_through_backend(_backend(loopback_server), request, store))
    assert truncations == [1]
    assert len(watch.logged) == 1
    logged = watch.logged[0]
    assert logged.count("base64_data truncated") == 3
    assert not WHOLE_IMAGE.search(logged)


def test_a_callback_named_by_the_call_itself_keeps_the_truncation(quiet_litellm, truncations, loopback_server, image_request):
    request, store = image_request
    watch = _watcher(quiet_litellm)
    asyncio.run(_through_backend(_backend(loopback_server, extra={"callbacks": [watch]}), request, store))
    assert truncations == [1]
    assert watch.logged and not WHOLE_IMAGE.search(watch.logged[0])


@pytest.mark.parametrize("name", CALLBACK_LISTS)
def test_any_callback_list_in_use_counts_as_listening(quiet_litellm, monkeypatch, name):
    monkeypatch.setattr(quiet_litellm, name, ["langfuse"])
    assert not logging_payload_unobserved(quiet_litellm)


def test_debug_logging_on_keeps_the_truncation_and_logs_no_whole_image(quiet_litellm, truncations, loopback_server, image_request, capsys):
    request, store = image_request
    handlers = [h for name in LITELLM_LOGGERS for h in logging.getLogger(name).handlers if isinstance(h, logging.StreamHandler)]
    assert handlers, "litellm's loggers have no stream handler to capture"
    captured = io.StringIO()
    streams = [h.setStream(captured) for h in handlers]
    quiet_litellm._turn_on_debug()  # sets litellm's loggers to DEBUG (quiet_litellm restores them)
    try:
        assert not logging_payload_unobserved(quiet_litellm)
        asyncio.run(_through_backend(_backend(loopback_server), request, store))
    finally:
        for handler, stream in zip(handlers, streams):
            handler.setStream(stream)
    output = captured.getvalue() + capsys.readouterr().out
    assert "chat/completions" in output or "acompletion" in output, "debug output was not captured"
    assert truncations == [1]
    assert not WHOLE_IMAGE.search(output)


def test_a_printed_logging_payload_holds_no_whole_image(quiet_litellm, truncations, loopback_server, image_request, monkeypatch, capsys):
    request, store = image_request
    monkeypatch.setenv(PRINT_PAYLOAD_SETTING, "1")
    asyncio.run(_through_backend(_backend(loopback_server), request, store))
    printed = capsys.readouterr().out
    assert "base64_data truncated" in printed
    assert truncations == [1]
    assert not WHOLE_IMAGE.search(printed)


def test_a_users_own_max_base64_length_setting_is_respected(quiet_litellm, truncations, loopback_server, image_request, monkeypatch):
    request, store = image_request
    monkeypatch.setenv(USER_SETTING, "64")
    assert not skip_truncation_when_unobserved(quiet_litellm)  # nothing new is installed
    asyncio.run(_through_backend(_backend(loopback_server), request, store))
    assert truncations == [1]


# -- what this relies on in the pinned litellm ----------------------------------------------------
def test_every_callback_list_of_litellm_is_checked(litellm):
    lists = {name for name in dir(litellm) if "callback" in name.lower() and isinstance(getattr(litellm, name), list | set | tuple)}
    assert lists - NOT_CALLBACK_LISTS == set(CALLBACK_LISTS)


def test_the_wrapper_sits_where_litellm_calls_the_truncation(litellm):
    from litellm.litellm_core_utils import litellm_logging, logging_utils

    wrapped = litellm_logging.truncate_base64_in_messages_async
    assert wrapped.__povagent_wrapped__ is logging_utils.truncate_base64_in_messages_async


def test_a_whole_image_really_is_long(image_request):
    request, store = image_request
    url = store.url(request.image_hashes()[0])
    assert WHOLE_IMAGE.search(url) and base64.b64decode(url.split(",", 1)[1]).startswith(b"\x89PNG")
