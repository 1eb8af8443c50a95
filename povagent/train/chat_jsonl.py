"""The ``messages`` format: JSONL chat examples with image references, and the images beside them.

Each line holds one example in the shapes the trainers read, so every one reads the same file:
``messages`` (TRL's SFT trainer: typed content, ``{"type": "image"}`` placeholders in the
benchmark's order) with ``images`` (paths relative to the export folder: LLaMA-Factory's
``dataset_dir``), ``conversations`` (LLaMA-Factory's ``sharegpt``: ``from``/``value`` turns,
one ``<image>`` token per image, in the same order as ``images``), and ``images_file_names``
(the same images relative to the shard's folder: the column ``datasets``' image-folder loader
turns into decoded images, so ``load_dataset(<export>)`` gives TRL's ``images`` from any working
folder; the card's config names the shards as its metadata files).

The images are copied once under ``messages/images/<aa>/<sha256>.<ext>``, named after their
content: the export builds every name it writes, so no text of the dataset (an ``rgb_path``
that climbs, a house's name) decides where a file lands, and an image two houses share is
stored once.
"""

from __future__ import annotations

import json
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from povagent.train.examples import ExampleImage, TrainingExample, image_bytes
from povagent.train.parquet import chat_messages
from povagent.train.shards import atomic_file

#: The images' folder, inside the shards' folder (``datasets`` resolves an image-folder
#: metadata file's names below the file's own folder only).
IMAGES_DIR = "images"
#: The shards' folder (``FORMAT_FOLDERS["messages"]``), where ``images/`` is too.
SHARDS_DIR = "messages"
#: LLaMA-Factory's image token in ``sharegpt`` text.
IMAGE_TOKEN = "<image>"


def image_file_name(image: ExampleImage) -> str:
    """Where the export stores ``image``, relative to the shards' folder (named after its bytes)."""
    suffix = image.media_type.partition("/")[2] or "png"
    suffix = "".join(c for c in suffix if c.isalnum())[:8] or "png"
    return f"{IMAGES_DIR}/{image.sha256[:2]}/{image.sha256}.{suffix}"


def image_reference(image: ExampleImage) -> str:
    """Where the export stores ``image``, relative to the export folder."""
    return f"{SHARDS_DIR}/{image_file_name(image)}"


def sharegpt_turns(example: TrainingExample) -> list[dict[str, str]]:
    """The example as ``sharegpt`` turns: parts joined by newlines, ``<image>`` for each image."""
    user = "\n".join(IMAGE_TOKEN if p.image is not None else (p.text or "") for p in example.parts)
    return [{"from": "human", "value": user}, {"from": "gpt", "value": example.answer}]


def example_line(example: TrainingExample, split: str, rationale: str) -> dict[str, Any]:
    """One JSONL record."""
    messages = chat_messages(example)
    for part in messages[0]["content"]:
        if part["type"] == "image":
            del part["text"]
    return {
        **example.identity(split),
        "messages": messages,
        "images": [image_reference(i) for i in example.images],
        "images_file_names": [image_file_name(i) for i in example.images],
        "conversations": sharegpt_turns(example),
        "answer": example.answer_json,
        "rationale": rationale,
        # a JSON string, as in the hf rows: its nullable fields would give the shards different
        # inferred features, which datasets' loader refuses across metadata files
        "facts": json.dumps(example.facts_record(), sort_keys=True),
    }


def copy_images(out: Path, example: TrainingExample) -> None:
    """Store ``example``'s images under ``out/images/`` (once: a file named after its content
    and of the right size is already the copy)."""
    for image in example.images:
        target = out / image_reference(image)
        if target.is_file() and not target.is_symlink():
            continue
        data = image_bytes(image)
        # unique: two cluster workers may store an image two houses share at the same time
        with atomic_file(target, inside=out, unique=True) as handle:
            handle.write(data)


def write_jsonl_shard(path: Path, out: Path, examples: Iterable[TrainingExample], split: str, rationale: str) -> int:
    """Write ``examples`` to the JSONL file ``path`` atomically (images copied first); returns the count."""
    count = 0
    with atomic_file(path, inside=out) as handle:
        for example in examples:
            copy_images(out, example)
            handle.write(json.dumps(example_line(example, split, rationale), ensure_ascii=False).encode() + b"\n")
            count += 1
    return count


def jsonl_rows(path: Path) -> int:
    """Lines in a written JSONL shard."""
    with open(path, "rb") as handle:
        return sum(1 for _ in handle)
