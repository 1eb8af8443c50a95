"""A request's content hash is the SHA-256 of its fingerprint's canonical JSON (cache keys
depend on it), however it is put together."""

from __future__ import annotations

import hashlib
import json

from povagent.answers.spec import AnswerSpec
from povagent.exchange.messages import GenerationParams, ImagePart, Message, Request, TextPart, ToolCall

SPEC = AnswerSpec(schema={"type": "object"})


def test_the_content_hash_is_the_sha256_of_the_fingerprints_canonical_json():
    messages = (
        Message("user", (TextPart("Image 0: é </script>"), ImagePart("a" * 64, label="Image 0"))),
        Message("assistant", (TextPart("hm"),), (ToolCall("c1", "turn", '{"degrees": 5}'),)),
        Message("tool", (TextPart("View 1"),), tool_call_id="c1"),
    )
    for request in (
        Request(messages[:1], SPEC),
        Request(messages, SPEC, GenerationParams(max_tokens=None, temperature=0.5, extra=(("seed", 1),)),
                tools=({"type": "function", "function": {"name": "turn"}},)),
    ):  # fmt: skip
        canonical = json.dumps(request.fingerprint(), sort_keys=True, separators=(",", ":"))
        assert request.content_hash() == hashlib.sha256(canonical.encode()).hexdigest()
