"""A run of several run indices: summary.json, the console table and ``score`` give the mean of
per-run means (the paper's aggregation) and keep the pooled numbers, labelled."""

from __future__ import annotations

import json

import pytest
from typer.testing import CliRunner

from povagent.cli import app
from povagent.config.pipeline import load_pipeline
from povagent.run.runner import run_pipeline

runner = CliRunner()


def test_summary_json_of_several_runs_is_the_mean_of_per_run_means_with_pooled_labelled(write_pipeline):
    result = run_pipeline(load_pipeline(write_pipeline(runs=2)))
    summary = json.loads((result.run_dir / "summary.json").read_text())
    assert summary["aggregation"] == "mean of per-run means" and summary["runs"] == [0, 1]
    assert summary["pooled"]["aggregation"] == "pooled"
    per_run = [summary["per_run"][k]["mean_l2"] for k in ("0", "1")]
    assert summary["overall"]["mean_l2"] == pytest.approx(sum(per_run) / 2, abs=1e-12)


def test_score_on_a_run_folder_averages_its_runs_when_they_differ(write_pipeline, small_release):
    result = run_pipeline(load_pipeline(write_pipeline(runs=2)))
    results = result.run_dir / "results.jsonl"
    rows = [json.loads(line) for line in results.read_text().splitlines() if line.strip()]
    # run 1 loses its answers to the Given instances: its mean moves, run 0's does not
    for r in rows:
        r["official_reading"] = None  # scored as parsed (the test parser's reading), not re-read
        if r["run"] == 1 and r["condition"] == "c":
            r["prediction"]["x"] = r["prediction"]["y"] = None
    results.write_text("".join(json.dumps(r) + "\n" for r in rows))
    out = runner.invoke(app, ["score", "--predictions", str(result.run_dir), "--dataset", str(small_release), "--json"])
    assert out.exit_code == 0, out.output
    doc = json.loads(out.stdout)
    means = [doc["per_run"][k]["mean_l2"] for k in ("0", "1")]
    assert means[0] != pytest.approx(means[1])
    assert doc["overall"]["mean_l2"] == pytest.approx(sum(means) / 2, abs=1e-12)
    assert doc["overall"]["mean_l2"] != pytest.approx(doc["pooled"]["overall"]["mean_l2"], abs=1e-9)
    assert doc["per_condition"]["c"]["mean_l2"] == pytest.approx(doc["pooled"]["per_condition"]["c"]["mean_l2"])
