"""A run's turns, shared by its rows: each row's found by its instance and run, read when looked at."""

from __future__ import annotations

from povagent.results.rows import ExchangeRecord, ResultRow, RowStatus, StoredRows
from povagent.results.transcript import RunTurns


def results_file(tmp_path, rows: list[tuple[str, int]]) -> StoredRows:
    """A results file of one exchange a row, its answer naming the row's instance and run."""
    path = tmp_path / "results.jsonl"
    lines = [
        ResultRow(key=f"{i}#{run}", instance_id=i, house_id="h", pair_id="0", direction="up", condition="c", run=run,
                  status=RowStatus.ANSWERED, exchanges=[ExchangeRecord(request_hash=f"{i}{run}", prompt=f"ask {i} {run}", raw=f"{i}/{run}")],
                  ).model_dump_json()
        for i, run in rows
    ]  # fmt: skip
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return StoredRows(path)


def test_each_rows_turns_are_found_by_its_instance_and_run(tmp_path):
    rows = results_file(tmp_path, [("a", 0), ("b", 0), ("a", 1)])
    turns = RunTurns(rows, keep=5)
    for row in rows:
        turns.add(row.instance_id, row.run)
    assert tuple(turns.of("a", 1)) == (("ask a", "a/1"),)
    assert tuple(turns.of("b", 0)) == (("ask b", "b/0"),)
    assert turns.of("b", 1) == ()


def test_a_row_of_the_same_hash_is_read_and_passed_over(tmp_path):
    rows = results_file(tmp_path, [("a", 0), ("b", 0)])
    turns = RunTurns(rows, redact=lambda text: text.replace("b", "[key]"))
    turns.add("b", 0)  # the first row's place collides with the second's
    turns.add("b", 0)
    assert tuple(turns.of("b", 0)) == (("ask [key] 0", "[key]/0"),)
