"""The ``hf`` format: Hugging Face ``datasets`` Parquet shards with the images embedded.

Each row is one example: ``messages`` (the chat turns in TRL's typed-content shape: the user's
text parts and ``{"type": "image"}`` placeholders in the benchmark's order, then the assistant's
answer), ``images`` (the ``Image`` feature: PNG bytes and the image's path in the house), the
benchmark's ``question`` text and ``answer`` JSON, the ``rationale``, the stated ``facts`` (JSON)
and the instance's fields. The features are written into the Parquet schema's ``huggingface``
metadata, exactly where ``datasets`` reads them, so ``load_dataset("parquet", ...)`` decodes the
images without being told. Needs ``pyarrow`` (the ``train`` extra).
"""

from __future__ import annotations

import json
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from povagent.train.examples import TrainingExample, image_bytes
from povagent.train.shards import atomic_file

#: Rows buffered before a row group is written, at least: a handful of 30-frame examples.
ROW_GROUP_BYTES = 16 * 1024 * 1024
#: The most row groups a shard is cut into. A streamed read with ``datasets`` that stops
#: before the end of a file of many row groups can leave the interpreter hanging at exit
#: (datasets 5.2, pyarrow 26: a race at shutdown, seen in 3 of 5 runs on a file of six row
#: groups and in none of 9 on a file of three; one row group would leave no read pending at
#: all, at the cost of buffering a whole shard). ``tests/train/test_export_formats.py`` reads
#: a stream left early in a subprocess that must exit. Memory while writing grows with the
#: shard size (``--max-shard-mb``) divided by this number.
MAX_ROW_GROUPS = 3

_STRING = {"dtype": "string", "_type": "Value"}

#: The ``datasets`` features of a row, as ``Features.to_dict()`` writes them.
FEATURES: dict[str, Any] = {
    "id": _STRING,
    "house_id": _STRING,
    "pair_id": _STRING,
    "direction": _STRING,
    "condition": _STRING,
    "split": _STRING,
    "messages": {
        "feature": {"role": _STRING, "content": {"feature": {"type": _STRING, "text": _STRING}, "_type": "List"}},
        "_type": "List",
    },
    "images": {"feature": {"_type": "Image"}, "_type": "List"},
    "question": _STRING,
    "answer": _STRING,
    "rationale": _STRING,
    "facts": _STRING,
}

MISSING_PYARROW = "the hf format writes Parquet with pyarrow: pip install 'povagent[train]'"


def require_pyarrow() -> None:
    """Raise the one-line error naming the extra when pyarrow cannot be imported."""
    _pyarrow()


def _pyarrow() -> Any:
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError:
        from povagent.errors import PovagentError

        raise PovagentError(MISSING_PYARROW) from None
    return pa, pq


def arrow_schema() -> Any:
    """The Arrow schema of a row, with the ``datasets`` features in its metadata."""
    pa, _ = _pyarrow()
    text = pa.string()
    content = pa.list_(pa.struct([("type", text), ("text", text)]))
    fields = [(name, text) for name in ("id", "house_id", "pair_id", "direction", "condition", "split")]
    fields += [
        ("messages", pa.list_(pa.struct([("role", text), ("content", content)]))),
        ("images", pa.list_(pa.struct([("bytes", pa.binary()), ("path", text)]))),
    ]
    fields += [(name, text) for name in ("question", "answer", "rationale", "facts")]
    meta = {"huggingface": json.dumps({"info": {"features": FEATURES}})}
    return pa.schema(fields, metadata=meta)


def chat_messages(example: TrainingExample) -> list[dict[str, Any]]:
    """The example as TRL's typed-content turns: text parts and image placeholders in order."""
    content = [{"type": "image", "text": None} if p.image is not None else {"type": "text", "text": p.text} for p in example.parts]
    return [
        {"role": "user", "content": content},
        {"role": "assistant", "content": [{"type": "text", "text": example.answer}]},
    ]


def example_row(example: TrainingExample, split: str, rationale: str) -> dict[str, Any]:
    """One Parquet row (images read from their files)."""
    return {
        **example.identity(split),
        "messages": chat_messages(example),
        "images": [{"bytes": image_bytes(i), "path": i.label} for i in example.images],
        "question": example.question_text,
        "answer": example.answer_json,
        "rationale": rationale,
        "facts": json.dumps(example.facts_record(), sort_keys=True),
    }


def write_parquet_shard(
    path: Path, examples: Iterable[TrainingExample], split: str, rationale: str, inside: Path | None = None, planned_bytes: int = 0
) -> int:
    """Write ``examples`` to the Parquet file ``path`` atomically (only in a folder inside
    ``inside``); returns the row count. ``planned_bytes`` (the shard's planned size) sets the
    row groups' size: at least :data:`ROW_GROUP_BYTES`, and at most :data:`MAX_ROW_GROUPS` of them."""
    group_bytes = max(ROW_GROUP_BYTES, -(-planned_bytes // MAX_ROW_GROUPS))
    pa, pq = _pyarrow()
    schema = arrow_schema()
    batches: list[Any] = []
    buffered = 0
    count = 0
    with atomic_file(path, inside=inside) as handle:
        # no dictionary and no min/max statistics for the image bytes: both would store image
        # data a second time (a dictionary page before the fallback, statistics per page)
        small = ["id", "house_id", "pair_id", "direction", "condition", "split", "rationale"]
        writer = pq.ParquetWriter(handle, schema, compression="zstd", use_dictionary=small, write_statistics=small)

        def flush() -> None:
            # the buffered examples as one row group: a table over the batches (no copy)
            table = pa.Table.from_batches(batches, schema=schema)
            writer.write_table(table, row_group_size=max(1, table.num_rows))
            batches.clear()
            # Arrow's allocator (mimalloc in the wheels) keeps the pages a row group used and
            # its footprint crept up with every shard; handing them back keeps it flat
            pa.default_memory_pool().release_unused()

        try:
            for example in examples:
                row = example_row(example, split, rationale)
                # each example becomes Arrow data at once: its Python bytes are not kept
                # beside the Arrow copy until the row group is written
                batches.append(pa.RecordBatch.from_pylist([row], schema=schema))
                buffered += sum(len(i["bytes"]) for i in row["images"]) + len(row["question"]) + len(row["answer"])
                del row
                count += 1
                if buffered >= group_bytes:
                    flush()
                    buffered = 0
            if batches or count == 0:
                flush()
        finally:
            writer.close()
    return count


def parquet_rows(path: Path) -> int:
    """Rows in a written Parquet file (from its footer, without reading the data)."""
    _, pq = _pyarrow()
    return int(pq.ParquetFile(path).metadata.num_rows)
