"""The results file's rules: appends survive a kill, a torn tail is cut, the last row of a key wins.

A kill mid-write leaves a last line without its newline; the next writer cuts it (its key runs
again) so its own first row starts on a fresh line, and readers skip it meanwhile. A file may
hold several rows of one key (a re-attempted failure): the last one is the row of that key. A
malformed line before the last is an error naming it (never a silent skip).
"""

from __future__ import annotations

import pytest

from povagent.errors import PredictionsError
from povagent.results.rows import ExchangeRecord, ResultRow, ResultsWriter, RowStatus, StagedResults, iter_rows, model_label, read_rows


def row(key: str, status: RowStatus = RowStatus.ANSWERED, raw: str | None = "{}") -> ResultRow:
    iid = key.split("#")[0]
    return ResultRow(key=key, instance_id=iid, house_id="h", pair_id="0", direction="up", condition="c",
                     status=status, exchanges=[ExchangeRecord(request_hash="r", raw=raw)] if raw is not None else [])


def line(r: ResultRow) -> bytes:
    return (r.model_dump_json() + "\n").encode()


def test_a_torn_last_line_is_cut_before_the_next_append(tmp_path):
    path = tmp_path / "results.jsonl"
    whole = line(row("a#0"))
    path.write_bytes(whole + line(row("b#0"))[:25])
    with ResultsWriter(path) as w:
        assert path.read_bytes() == whole
        w.write(row("c#0"))
    assert [r.key for r in iter_rows(path)] == ["a#0", "c#0"]
    assert path.read_bytes().count(b"\n") == 2


def test_a_file_that_is_only_a_torn_line_becomes_empty(tmp_path):
    path = tmp_path / "results.jsonl"
    path.write_bytes(line(row("a#0"))[:-1])
    ResultsWriter(path).close()
    assert path.read_bytes() == b""


def test_a_complete_file_is_left_byte_for_byte(tmp_path):
    path = tmp_path / "results.jsonl"
    data = line(row("a#0")) + line(row("b#0"))
    path.write_bytes(data)
    ResultsWriter(path).close()
    assert path.read_bytes() == data


def test_a_new_results_file_and_its_folders_are_created(tmp_path):
    path = tmp_path / "sweep" / "run" / "results.jsonl"
    with ResultsWriter(path) as w:
        w.write(row("a#0"))
    assert path.read_bytes() == line(row("a#0"))


def test_rows_are_appended_after_existing_ones(tmp_path):
    path = tmp_path / "results.jsonl"
    with ResultsWriter(path) as w:
        w.write(row("a#0"))
    with ResultsWriter(path) as w:
        w.write_lines(line(row("b#0")).decode() + line(row("c#0")).decode())
    assert [r.key for r in iter_rows(path)] == ["a#0", "b#0", "c#0"]


def test_readers_skip_a_torn_last_line(tmp_path):
    path = tmp_path / "results.jsonl"
    path.write_bytes(line(row("a#0")) + line(row("b#0")) + line(row("c#0"))[:30])
    assert [r.key for r in iter_rows(path)] == ["a#0", "b#0"]


def test_readers_stop_at_a_malformed_line_before_the_last(tmp_path):
    # skipping it would change a score silently; tests/results/test_torn_journal.py has the cases
    path = tmp_path / "results.jsonl"
    path.write_bytes(line(row("a#0")) + b"not json\n" + line(row("b#0")))
    with pytest.raises(PredictionsError, match="line 2: not a result row"):
        list(iter_rows(path))


def test_a_missing_results_file_has_no_rows(tmp_path):
    assert list(iter_rows(tmp_path / "nope.jsonl")) == []
    assert read_rows(tmp_path / "nope.jsonl") == []


def test_the_last_row_of_a_key_wins(tmp_path):
    path = tmp_path / "results.jsonl"
    with ResultsWriter(path) as w:
        w.write(row("a#0", RowStatus.INFRA_ERROR, raw=None))
        w.write(row("b#0"))
        w.write(row("a#0", RowStatus.ANSWERED, raw="second"))
    rows = {r.key: r for r in read_rows(path)}
    assert len(read_rows(path)) == 2
    assert rows["a#0"].status is RowStatus.ANSWERED
    assert rows["a#0"].raw_response == "second"


def test_the_raw_response_is_the_last_exchanges_answer():
    r = row("a#0")
    r.exchanges.append(ExchangeRecord(request_hash="r2", raw="final"))
    assert r.raw_response == "final"
    assert row("b#0", raw=None).raw_response is None


def test_a_minimal_row_reads_with_neutral_defaults(tmp_path):
    path = tmp_path / "results.jsonl"
    path.write_text('{"key": "a#0", "instance_id": "a", "house_id": "h", "pair_id": "0", "direction": "up", '
                    '"condition": "c", "status": "answered", "exchanges": [{"request_hash": "r"}]}\n', encoding="utf-8")
    (r,) = iter_rows(path)
    assert (r.run, r.retries, r.latency_s) == (0, 0, 0.0)
    (x,) = r.exchanges
    assert (x.retries, x.latency_s, x.cached) == (0, 0.0, False)


# -- a file written whole (rescore's): the previous file until commit, then the new one ----------
def test_a_staged_file_appears_only_at_commit_in_the_format_of_a_run(tmp_path):
    path = tmp_path / "rescored" / "run" / "results.jsonl"  # its folders are created
    rows = [row("a#0"), row("b#0", raw=None)]
    with StagedResults(path) as staged:
        for r in rows:
            staged.write(r)
        assert not path.exists()
        staged.commit()
    with ResultsWriter(tmp_path / "journal.jsonl") as w:
        for r in rows:
            w.write(r)
    # byte for byte what a run writes (null fields included), and nothing left beside it
    assert path.read_bytes() == (tmp_path / "journal.jsonl").read_bytes() == b"".join(line(r) for r in rows)
    assert list(path.parent.iterdir()) == [path]


def test_a_staged_file_replaces_the_previous_file_whole(tmp_path):
    path = tmp_path / "results.jsonl"
    path.write_bytes(line(row("old#0")) + line(row("old#1")))
    with StagedResults(path) as staged:  # its folder exists already
        staged.write(row("new#0"))
        staged.commit()
    assert [r.key for r in iter_rows(path)] == ["new#0"]


def test_leaving_without_commit_keeps_the_previous_file_and_removes_the_staged_one(tmp_path):
    path = tmp_path / "results.jsonl"
    path.write_bytes(line(row("old#0")))
    with pytest.raises(RuntimeError, match="scorer failed"), StagedResults(path) as staged:
        staged.write(row("new#0"))
        raise RuntimeError("scorer failed")
    assert [r.key for r in iter_rows(path)] == ["old#0"]
    assert list(tmp_path.iterdir()) == [path]
    assert staged._fh.closed  # no file handle left open either


def test_a_staged_file_removed_meanwhile_does_not_hide_the_error_that_ended_the_block(tmp_path):
    with pytest.raises(RuntimeError, match="scorer failed"), StagedResults(tmp_path / "results.jsonl") as staged:
        staged.tmp.unlink()
        raise RuntimeError("scorer failed")


# -- how a summary names the model that answered ---------------------------------------------------
def test_a_model_is_named_by_its_profile_and_its_model_string():
    assert model_label("openai/gpt-5.4", "gpt-5.4") == "gpt-5.4 = openai/gpt-5.4"
    assert model_label("anthropic/claude", "sonnet") == "sonnet = anthropic/claude"  # whatever their order
    assert model_label("gpt-5.4", "gpt-5.4") == "gpt-5.4"  # a profile named as its model: once
    assert model_label("", "gpt-5.4") == "gpt-5.4"  # a row written before rows named the model
    assert model_label("center", None) == model_label("center", "") == "center"
