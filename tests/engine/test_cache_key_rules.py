"""The cache key's rules: the same call always gets the same key, any answer-changing difference another.

The key hashes the backend identity as canonical JSON (sorted keys, so two equal identities
written in another order share their answers), the request's hash and the run index, each
field delimited so that no two different calls can run together into one string.
"""

from __future__ import annotations

import hashlib

from povagent.engine.cache import cache_key, identity_json

IDENTITY = {"model": "openai/gpt-5.4", "temperature": 0.0, "max_tokens": 256}


def test_the_key_is_a_hex_sha256():
    key = cache_key(IDENTITY, "req", 0)
    assert len(key) == 64 and int(key, 16) >= 0


def test_the_key_does_not_depend_on_the_order_of_the_identity():
    reordered = {"max_tokens": 256, "temperature": 0.0, "model": "openai/gpt-5.4"}
    assert cache_key(reordered, "req", 0) == cache_key(IDENTITY, "req", 0)


def test_identity_json_is_sorted_and_compact():
    assert identity_json({"b": 1, "a": [1, 2]}) == '{"a":[1,2],"b":1}'


def test_a_precomputed_identity_gives_the_same_key():
    assert cache_key(identity_json(IDENTITY), "req", 3) == cache_key(IDENTITY, "req", 3)


def test_each_run_index_is_its_own_sample():
    assert cache_key(IDENTITY, "req", 0) != cache_key(IDENTITY, "req", 1)


def test_another_request_or_backend_is_another_key():
    assert cache_key(IDENTITY, "req", 0) != cache_key(IDENTITY, "req2", 0)
    assert cache_key(IDENTITY, "req", 0) != cache_key({**IDENTITY, "temperature": 0.7}, "req", 0)


def test_fields_cannot_run_into_each_other():
    assert cache_key(IDENTITY, "ab1", 2) != cache_key(IDENTITY, "ab", 12)


def test_the_key_format_is_stable_schema_1():
    # the key is part of the cache file's format: a change orphans every stored answer, so it
    # changes only with SCHEMA_VERSION (and then on purpose)
    blob = identity_json(IDENTITY)
    expected = hashlib.sha256(b"povagent-cache-v1\x00" + blob.encode() + b"\x00req\x003").hexdigest()
    assert cache_key(IDENTITY, "req", 3) == expected


def test_the_key_is_versioned_by_the_cache_schema():
    # a schema change must orphan old answers, never misread them: the version is hashed in
    blob = identity_json(IDENTITY)
    unversioned = hashlib.sha256(f"{blob}\x00req\x000".encode()).hexdigest()
    assert cache_key(IDENTITY, "req", 0) != unversioned
