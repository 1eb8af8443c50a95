"""The response cache: keys cover what changes an answer; stored answers come back marked cached."""

from __future__ import annotations

import pytest

from povagent.answers.spec import AnswerSpec, point_answer_schema
from povagent.engine.cache import CacheError, ResponseCache, cache_key, identity_json
from povagent.exchange.messages import GenerationParams, ImagePart, Message, Request, Response, TextPart, Usage

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


def _on_disk(path, key):
    import sqlite3

    with sqlite3.connect(path) as db:
        return db.execute("SELECT text FROM responses WHERE key = ?", (key,)).fetchone()


def test_a_deferred_answer_is_found_at_once_and_written_by_flush(tmp_path):
    path = tmp_path / "c.sqlite"
    with ResponseCache(path) as cache:
        cache.put_deferred("k", Response("answer", Usage(10, 2, 0.5), latency_s=1.5, model="m"))
        hit = cache.get("k")
        assert hit.cached and (hit.text, hit.usage.prompt_tokens, hit.usage.cost_usd, hit.latency_s, hit.model) == ("answer", 10, 0.5, 1.5, "m")
        assert cache.pending == 1 and _on_disk(path, "k") is None
        assert cache.flush() == 1 and cache.pending == 0 and cache.writes == 1
        assert _on_disk(path, "k") == ("answer",)
        assert cache.get("k").text == "answer" and cache.flush() == 0


def test_close_writes_deferred_answers(tmp_path):
    with ResponseCache(tmp_path / "c.sqlite") as cache:
        for i in range(5):
            cache.put_deferred(f"k{i}", Response(f"answer {i}"))
    with ResponseCache(tmp_path / "c.sqlite") as cache:
        assert len(cache) == 5 and cache.get("k4").text == "answer 4"


def test_a_failed_flush_raises_and_keeps_the_answers_queued(tmp_path, monkeypatch):
    import sqlite3

    cache = ResponseCache(tmp_path / "c.sqlite")
    cache.put_deferred("k", Response("answer"))

    def full(records):
        raise sqlite3.OperationalError("database or disk is full")

    monkeypatch.setattr(cache, "_insert", full)
    with pytest.raises(sqlite3.OperationalError):
        cache.flush()
    assert cache.pending == 1 and cache.get("k").text == "answer"
    assert cache.discard_pending() == 1 and cache.get("k") is None
    monkeypatch.undo()
    cache.close()


@pytest.mark.parametrize("name", ["c.sqlite", "c.sqlite-wal", "c.sqlite-journal"])
def test_a_cache_file_planted_as_a_link_is_refused_and_its_target_untouched(tmp_path, name):
    import os

    from povagent.errors import WriteTargetError

    outside = tmp_path / "elsewhere.db"
    outside.write_bytes(b"")  # an empty file: SQLite would happily make it a cache
    run = tmp_path / "run"
    run.mkdir()
    os.symlink(outside, run / name)
    with pytest.raises(WriteTargetError, match=rf"{name}: is a symbolic link"), ResponseCache(run / "c.sqlite") as cache:
        cache.put("k", Response("answer"))
    assert outside.read_bytes() == b""
