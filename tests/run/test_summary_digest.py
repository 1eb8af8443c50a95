"""What a run keeps per key for its summary: a few hundred bytes, whatever the row's text."""

from __future__ import annotations

import enum
import gc
import json
import sys

from povagent.config.pipeline import load_pipeline
from povagent.results.rows import iter_rows
from povagent.run.runner import run_pipeline
from povagent.run.summary import summarize_run, summary_digest

#: The most a key's digest may hold (bytes): a row's official score, its reading's, its usage.
DIGEST_BUDGET = 1024


def own_bytes(root: object) -> int:
    """Bytes of the objects reachable from ``root`` that it holds alone: strings every row
    shares (interned), enum members, ``None``, booleans, small integers and classes are not
    counted."""
    seen: set[int] = set()
    total = 0
    stack = [root]
    while stack:
        obj = stack.pop()
        if id(obj) in seen or obj is None or isinstance(obj, (bool, type, enum.Enum)) or (type(obj) is int and -5 <= obj <= 256):
            continue
        if type(obj) is str and sys.intern(obj) is obj:
            continue
        seen.add(id(obj))
        total += sys.getsizeof(obj)
        stack.extend(gc.get_referents(obj))
    return total


def test_a_key_is_digested_into_a_few_hundred_bytes_however_long_its_answer(write_pipeline):
    result = run_pipeline(load_pipeline(write_pipeline()))
    rows = list(iter_rows(result.run_dir / "results.jsonl"))
    long_answer = rows[0].model_copy(update={"sentence": "s" * 5000, "exchanges": rows[0].exchanges * 20})
    for row in [*rows, long_answer]:
        assert own_bytes(summary_digest(row)) < DIGEST_BUDGET, row.key


def test_the_summary_a_run_writes_is_the_summary_of_its_results_file(write_pipeline):
    result = run_pipeline(load_pipeline(write_pipeline(runs=2)))
    written = json.loads((result.run_dir / "summary.json").read_text())
    again = json.loads(json.dumps(summarize_run(result.run_dir / "results.jsonl"), default=str))
    for section in ("overall", "per_condition", "per_direction", "per_run", "rows", "usage", "official_parse"):
        assert written.get(section) == again.get(section), section
