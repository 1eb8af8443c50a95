"""The client's count of finished rows on a cluster, read from the cells' journals."""

from __future__ import annotations

import json

from povagent.run.journal import drop_rows
from povagent.run.sweep import JournalWatch


def _row(key: str, status: str = "answered") -> str:
    return json.dumps({"key": key, "status": status}) + "\n"


def test_each_new_complete_row_counts_once_with_its_status(tmp_path) -> None:
    results = tmp_path / "results.jsonl"
    results.write_text(_row("k0"))
    watch = JournalWatch()
    watch.watch(tmp_path, wanted={"k0", "k1", "k2", "k3"}, counted={"k0"})
    assert watch.poll() == []
    with open(results, "a") as fh:
        fh.write(_row("k1") + _row("k2", "parse_error") + '{"key": "k3", "sta')  # the last one half-written
    assert watch.poll() == ["answered", "parse_error"]
    with open(results, "a") as fh:
        fh.write('tus": "answered"}\n' + _row("other-cell-key"))
    assert watch.poll() == ["answered"]  # completed now; a key outside the cell is not counted
    assert watch.poll() == []


def test_a_journal_rewritten_to_retry_failed_keys_counts_only_the_retried_rows(tmp_path) -> None:
    results = tmp_path / "results.jsonl"
    results.write_text(_row("k0") + _row("k1", "infra_error") + _row("k2"))
    watch = JournalWatch()
    watch.watch(tmp_path, wanted={"k0", "k1", "k2"}, counted={"k0", "k2"})  # k1 is pending again
    drop_rows(results, {"k1"})  # what the runner does first (a new file)
    with open(results, "a") as fh:
        fh.write(_row("k1"))
    assert watch.poll() == ["answered"]
    assert watch.poll() == []


def test_a_cell_whose_journal_does_not_exist_yet_is_waited_for(tmp_path) -> None:
    watch = JournalWatch()
    watch.watch(tmp_path / "cell", wanted={"k0"}, counted=set())
    assert watch.poll() == []
    (tmp_path / "cell").mkdir()
    (tmp_path / "cell" / "results.jsonl").write_text(_row("k0"))
    assert watch.poll() == ["answered"]
