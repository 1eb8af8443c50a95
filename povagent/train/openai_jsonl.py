"""The ``openai`` format: OpenAI's chat fine-tuning JSONL, images inline as data URLs.

One line per example, holding ``messages`` only (the fine-tuning API reads that key): the user
turn's content is the question's parts in the benchmark's order, text parts as ``{"type":
"text"}`` and each image as ``{"type": "image_url", "image_url": {"url": "data:image/png;base64,
..."}}``; the assistant turn's content is the answer text (the rationale, then the JSON). The
same shape is what OpenAI-compatible fine-tuning services (Together, Fireworks) read. Images are
embedded, so a shard is self-contained and needs no folder beside it; its size is planned with
base64's 4/3.
"""

from __future__ import annotations

import base64
import json
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from povagent.train.examples import TrainingExample, image_bytes
from povagent.train.shards import atomic_file


def openai_line(example: TrainingExample) -> dict[str, Any]:
    """One JSONL record: ``{"messages": [user, assistant]}``."""
    content: list[dict[str, Any]] = []
    images = iter(example.images)
    for part in example.parts:
        if part.image is None:
            content.append({"type": "text", "text": part.text or ""})
            continue
        image = next(images)
        url = f"data:{image.media_type};base64,{base64.b64encode(image_bytes(image)).decode('ascii')}"
        content.append({"type": "image_url", "image_url": {"url": url}})
    return {"messages": [{"role": "user", "content": content}, {"role": "assistant", "content": example.answer}]}


def write_openai_shard(path: Path, out: Path, examples: Iterable[TrainingExample]) -> int:
    """Write ``examples`` to the JSONL file ``path`` atomically; returns the count."""
    count = 0
    with atomic_file(path, inside=out) as handle:
        for example in examples:
            handle.write(json.dumps(openai_line(example), ensure_ascii=False).encode() + b"\n")
            count += 1
    return count
