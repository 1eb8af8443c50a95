"""The response cache: keys cover what changes an answer; stored answers come back marked cached."""

from __future__ import annotations

import pytest

from povagent.answers import AnswerSpec, point_answer_schema
from povagent.cache import CacheError, ResponseCache, cache_key, identity_json
from povagent.exchange import GenerationParams, ImagePart, Message, Request, Response, TextPart, Usage

SPEC = AnswerSpec(schema=point_answer_schema(512, 512), asks_frame=False)


def request(image="a" * 64, text="where?", max_tokens=256):
    return Request((Message("user", (ImagePart(image), TextPart(text))),), SPEC, GenerationParams(max_tokens=max_tokens))


def test_key_changes_with_backend_messages_images_generation_and_run():
    base = cache_key({"model": "m"}, request().content_hash(), 0)
    assert cache_key({"model": "n"}, request().content_hash(), 0) != base
    assert cache_key({"model": "m"}, request(text="other").content_hash(), 0) != base
    assert cache_key({"model": "m"}, request(image="b" * 64).content_hash(), 0) != base
    assert cache_key({"model": "m"}, request(max_tokens=64).content_hash(), 0) != base
    assert cache_key({"model": "m"}, request().content_hash(), 1) != base


def test_precomputed_identity_gives_the_same_key():
    ident = {"model": "m", "temperature": 0}
    assert cache_key(identity_json(ident), "h", 2) == cache_key(ident, "h", 2)


def test_stored_response_comes_back_marked_cached(tmp_path):
    with ResponseCache(tmp_path / "c.sqlite") as cache:
        cache.put("k", Response("answer", Usage(10, 2, 0.5), latency_s=1.5, model="m"))
        hit = cache.get("k")
        assert hit.text == "answer" and hit.cached and hit.usage.prompt_tokens == 10 and hit.usage.cost_usd == 0.5
        assert cache.get("missing") is None and (cache.hits, cache.misses) == (1, 1)


def test_cache_persists_across_opens(tmp_path):
    with ResponseCache(tmp_path / "c.sqlite") as cache:
        cache.put("k", Response("answer"))
    with ResponseCache(tmp_path / "c.sqlite") as cache:
        assert cache.get("k").text == "answer" and len(cache) == 1


def test_a_file_that_is_not_a_cache_is_reported(tmp_path):
    path = tmp_path / "c.sqlite"
    path.write_bytes(b"not a database at all" * 100)
    with pytest.raises(CacheError, match=r"cannot be used as a response cache"):
        ResponseCache(path)
