"""A fresh run summarizes its rows as they were written: the summary of its results file, whatever
order the rows were written in."""

from __future__ import annotations

import json

from povagent.config.pipeline import load_pipeline
from povagent.results.rows import read_rows
from povagent.run.runner import run_pipeline
from povagent.run.summary import declared_metrics, summarize_rows, summarize_run
from povagent.scoring.metric_columns import metrics_breakdown
from povagent.scoring.metrics import valued_row


def _without_session(path):
    """A summary without what the session that wrote it did (its rows written, images read)."""
    summary = json.loads(path.read_text())
    summary.pop("session"), summary.pop("images")
    return summary


def test_a_fresh_runs_summary_is_the_summary_of_its_results_file_read_back(write_pipeline):
    config = load_pipeline(write_pipeline(runs=2))
    result = run_pipeline(config)
    written = json.loads((result.run_dir / "summary.json").read_text())
    from povagent.plugins import get_plugin_host

    host = get_plugin_host(config.plugins)
    declared = declared_metrics({name: host.scorer(name, None) for name in ("official",)})
    read_back = json.loads(json.dumps(summarize_run(result.run_dir / "results.jsonl", None, declared), default=str))
    for section in ("overall", "per_condition", "per_direction", "per_run", "rows", "usage", "metrics"):
        assert written[section] == read_back[section], section


def test_a_resumed_run_counts_the_rows_of_its_earlier_session(write_pipeline, tmp_path):
    path = write_pipeline(runs=1)
    run_pipeline(load_pipeline(path))
    results = tmp_path / "run" / "results.jsonl"
    lines = results.read_text().splitlines(keepends=True)
    results.write_text("".join(lines[: len(lines) // 2]))  # half the keys done before this session
    again = run_pipeline(load_pipeline(path))
    assert again.summary.rows.done == len(lines) and again.summary.rows.missing == 0


def test_a_runs_summary_does_not_depend_on_the_order_its_rows_were_written_in(write_pipeline, tmp_path):
    """Rows written as keys finish (concurrency), or over two sessions, are summarized in one
    order: the summary of a run that wrote them in order, to the last bit."""
    config = load_pipeline(write_pipeline(runs=2, concurrency=1))
    in_order = run_pipeline(config)
    results = in_order.run_dir / "results.jsonl"
    lines = results.read_text().splitlines(keepends=True)
    # the metrics of the rows in file order and in reverse are other numbers (the bootstrap draws
    # follow the rows' order), so the checks below can fail; the summary's are one
    from povagent.plugins import get_plugin_host

    host_declared = declared_metrics({"official": get_plugin_host(config.plugins).scorer("official", None)})
    rows = list(read_rows(results))
    as_read = json.dumps(metrics_breakdown([valued_row(r, host_declared) for r in rows], host_declared), default=str)
    reversed_as_read = json.dumps(metrics_breakdown([valued_row(r, host_declared) for r in rows[::-1]], host_declared), default=str)
    assert as_read != reversed_as_read
    assert json.dumps(summarize_rows(rows, None, host_declared), default=str) == json.dumps(summarize_rows(rows[::-1], None, host_declared), default=str)
    written_in_order = _without_session(in_order.run_dir / "summary.json")
    results.write_text("".join(lines[::-1]))
    (in_order.run_dir / "summary.json").unlink()
    again = run_pipeline(config)  # every key done: the summary is the file read back
    assert again.stats.rows_written == 0
    assert _without_session(again.run_dir / "summary.json") == written_in_order
