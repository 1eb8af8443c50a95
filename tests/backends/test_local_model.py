"""Decoding settings and out-of-memory recognition of the in-process backend (no torch needed)."""

from __future__ import annotations

import pytest

from povagent.answers.spec import AnswerSpec, point_answer_schema
from povagent.exchange.messages import GenerationParams, Message, Request
from povagent_plugins.backends.local_model import UNLIMITED_MAX_NEW_TOKENS, Decoding, decoding_of, is_out_of_memory


def request(**generation) -> Request:
    return Request((Message.text("user", "hi"),), AnswerSpec(schema=point_answer_schema(512, 512)), GenerationParams(**generation))


def test_greedy_unless_asked_drops_the_checkpoints_sampling_settings():
    kwargs = decoding_of(request(max_tokens=256), "greedy").generate_kwargs()
    assert kwargs == {"max_new_tokens": 256, "do_sample": False, "temperature": None, "top_p": None, "top_k": None}


def test_temperature_zero_is_greedy_even_when_the_checkpoint_samples():
    assert decoding_of(request(max_tokens=8, temperature=0.0), "checkpoint").generate_kwargs()["do_sample"] is False


def test_a_positive_temperature_samples_at_it():
    assert decoding_of(request(max_tokens=8, temperature=0.7), "greedy").generate_kwargs() == {"max_new_tokens": 8, "do_sample": True, "temperature": 0.7}


def test_checkpoint_sampling_passes_only_the_budget():
    assert decoding_of(request(max_tokens=1024), "checkpoint").generate_kwargs() == {"max_new_tokens": 1024}


def test_no_token_limit_is_a_generous_budget_not_generates_default():
    assert decoding_of(request(max_tokens=None), "greedy").max_new_tokens == UNLIMITED_MAX_NEW_TOKENS


def test_requests_with_the_same_settings_share_a_batch_group():
    assert decoding_of(request(max_tokens=8), "greedy") == Decoding(8, None, "greedy")
    assert hash(decoding_of(request(max_tokens=8), "greedy")) == hash(Decoding(8, None, "greedy"))


class OutOfMemoryError(RuntimeError):
    """Named as torch's (torch.OutOfMemoryError) is."""


@pytest.mark.parametrize(
    "exc, expected",
    [
        (OutOfMemoryError("CUDA out of memory. Tried to allocate 2.00 GiB"), True),
        (RuntimeError("DefaultCPUAllocator: can't allocate memory: you tried to allocate 1 bytes"), True),
        (MemoryError(), True),
        (RuntimeError("shape mismatch"), False),
        (ValueError("out of memory"), False),
    ],
)
def test_out_of_memory_is_recognised_by_type_and_torchs_messages(exc, expected):
    assert is_out_of_memory(exc) is expected
