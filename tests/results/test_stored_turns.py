"""A stored row's turns, read from the results file when looked at, as the row's own transcript."""

from __future__ import annotations

from povagent.results.rows import ExchangeRecord, ResultRow, RowStatus, StoredRows
from povagent.results.transcript import StoredTurns, transcripts


def test_stored_turns_are_the_rows_transcript_and_answers_redacted_as_read(tmp_path):
    exchanges = [ExchangeRecord(request_hash="1", prompt="look at sk-SECRET", raw="first sk-SECRET"),
                 ExchangeRecord(request_hash="2", prompt="again", raw=None)]
    r = ResultRow(key="a#0", instance_id="a", house_id="h", pair_id="0", direction="up", condition="c",
                  status=RowStatus.ANSWERED, exchanges=exchanges)
    path = tmp_path / "results.jsonl"
    path.write_text(r.model_dump_json() + "\n", encoding="utf-8")
    turns = StoredTurns(StoredRows(path), 0)
    assert tuple(turns) == tuple(zip(transcripts(exchanges), ("first sk-SECRET", None)))
    assert len(turns) == 2 and turns[1] == (transcripts(exchanges)[1], None)
    hidden = tuple(turns.redacted(lambda text: text.replace("sk-SECRET", "[key]")))
    assert hidden[0] == ("look at [key]", "first [key]")
