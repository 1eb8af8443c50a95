"""A row keeps each message once; every request is rebuilt from it as sent, and rows written
before (each prompt whole) read exactly as they always did."""

from __future__ import annotations

import json

from povagent.report.collect import observation_of
from povagent.results.rows import ResultRow, iter_rows
from povagent.results.transcript import transcripts

FIRST = "--- user ---\nImage 0:\n[image: Image 0]\nWhere is it?"
SECOND = FIRST + "\n--- assistant ---\n\n[tool call c0: turn({\"degrees\": 5})]\n--- tool (c0) ---\nView 1: turned 5 degrees"


def older_row(tmp_path) -> ResultRow:
    """A row as written before prompts were kept once: every prompt whole, no ``prompt_continues``."""
    row = {"key": "h/0/left/a#0", "instance_id": "h/0/left/a", "house_id": "h", "pair_id": "0", "direction": "left",
           "condition": "a", "status": "parse_error",
           "exchanges": [{"request_hash": "r1", "prompt": FIRST, "raw": ""}, {"request_hash": "r2", "prompt": SECOND, "raw": "{}"}]}  # fmt: skip
    (tmp_path / "results.jsonl").write_text(json.dumps(row) + "\n")
    (read,) = iter_rows(tmp_path / "results.jsonl")
    return read


def test_a_row_written_before_reads_each_prompt_whole(tmp_path):
    row = older_row(tmp_path)
    assert [e.prompt_continues for e in row.exchanges] == [False, False]
    assert transcripts(row.exchanges) == [FIRST, SECOND]


def test_the_report_shows_a_row_written_before_as_it_always_did(tmp_path):
    turns = observation_of(older_row(tmp_path), "system", "run", "official").turns
    assert turns == ((FIRST, ""), (SECOND, "{}"))


def test_a_row_kept_once_rebuilds_each_request_and_keeps_only_the_leading_characters_asked_for(tmp_path):
    row = older_row(tmp_path)
    second = row.exchanges[1].model_copy(update={"prompt": SECOND[len(FIRST) + 1 :], "prompt_continues": True})
    last = second.model_copy(update={"prompt": "", "raw": "record"})  # a strategy's own last answer: nothing new
    exchanges = [row.exchanges[0], second, last]
    assert transcripts(exchanges) == [FIRST, SECOND, SECOND]
    assert transcripts(exchanges, keep=len(FIRST) + 3) == [FIRST, SECOND[: len(FIRST) + 3], SECOND[: len(FIRST) + 3]]
