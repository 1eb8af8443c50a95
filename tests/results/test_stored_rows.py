"""Rows held as where they lie in the results file: the same rows as read_rows, none kept in memory."""

from __future__ import annotations

import tracemalloc

import pytest

from povagent.errors import PredictionsError
from povagent.results.rows import ExchangeRecord, ResultRow, RowStatus, StoredRows, read_rows


def row(key: str, raw: str = "{}") -> ResultRow:
    return ResultRow(key=key, instance_id=key.split("#")[0], house_id="h", pair_id="0", direction="up", condition="c",
                     status=RowStatus.ANSWERED, exchanges=[ExchangeRecord(request_hash="r", prompt="p" * 20, raw=raw)])


def write(path, *rows: ResultRow, tail: bytes = b"") -> None:
    path.write_bytes(b"".join((r.model_dump_json() + "\n").encode() for r in rows) + tail)


def test_stored_rows_are_the_rows_read_rows_returns(tmp_path):
    path = tmp_path / "results.jsonl"
    write(path, row("a#0", "first"), row("b#0"), row("a#0", "second"), row("c#0"), tail=b"\n" + row("d#0").model_dump_json()[:30].encode())
    stored = StoredRows(path)
    assert list(stored) == read_rows(path)
    assert len(stored) == 3 and stored[0].exchanges[0].raw == "second" and stored[-1].key == "c#0"
    assert [r.key for r in stored[1:]] == ["b#0", "c#0"]


def test_stored_rows_keep_no_row_in_memory(tmp_path):
    path = tmp_path / "results.jsonl"
    write(path, *(row(f"i{k}#0", raw="x" * 10_000) for k in range(400)))  # 4 MB of answers
    tracemalloc.start()
    try:
        stored = StoredRows(path)
        held, _ = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert len(stored) == 400
    assert held < 100_000


def test_a_line_that_is_not_a_row_is_named_when_the_rows_are_stored(tmp_path):
    path = tmp_path / "results.jsonl"
    write(path, row("a#0"), tail=b"not json\n")
    with pytest.raises(PredictionsError, match="line 2"):
        StoredRows(path)


def test_stored_rows_know_the_scorers_their_rows_carry_as_the_rows_say(tmp_path):
    path = tmp_path / "results.jsonl"
    scored = [row(k) for k in ("a#0", "b#0", "a#0", "c#0")]
    scored[0].scores = {"early": {"x": 1}}  # superseded by a#0's last row: not carried
    scored[1].scores = {"choice": {"correct": True, "chosen": "A"}, "official": {"l2": 0.1}}
    scored[2].scores = {"official": {"l2": 0.2, "answered": True}}
    write(path, *scored)
    stored = StoredRows(path)
    assert list(stored.carried_scores) == list(dict.fromkeys(name for r in stored for name in r.scores))
    assert stored.carried_scores == {
        "official": frozenset({frozenset({"l2", "answered"}), frozenset({"l2"})}),
        "choice": frozenset({frozenset({"correct", "chosen"})}),
    }
