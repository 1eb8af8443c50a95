"""A fresh run summarizes its rows as they were written: the summary of its results file."""

from __future__ import annotations

import json

from povagent.config.pipeline import load_pipeline
from povagent.run.runner import run_pipeline
from povagent.run.summary import declared_metrics, summarize_run


def test_a_fresh_runs_summary_is_the_summary_of_its_results_file_read_back(write_pipeline):
    config = load_pipeline(write_pipeline(runs=2))
    result = run_pipeline(config)
    written = json.loads((result.run_dir / "summary.json").read_text())
    from povagent.plugins import get_plugin_host

    host = get_plugin_host(config.plugins)
    declared = declared_metrics({name: host.scorer(name, None) for name in ("official",)})
    keys = {json.loads(line)["key"] for line in (result.run_dir / "results.jsonl").read_text().splitlines()}
    read_back = json.loads(json.dumps(summarize_run(result.run_dir / "results.jsonl", keys, declared), default=str))
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
