"""A scorer's declared metrics reach summary.json (a ``metrics`` section per scorer, per slice),
the console and rescore, whatever the scorer: a third-party one with two metrics, and the
``official`` scorer, whose declared mean is the official number."""

from __future__ import annotations

import json

from typer.testing import CliRunner

from povagent.cli import app
from povagent.run.rescore import rescore_run

NEAR_PLUGIN = '''
from povagent import hookimpl
from povagent.interfaces import Scorer
from povagent.scoring.metrics import Metric


class NearScorer(Scorer):
    metrics = (
        Metric("near_rate", "higher", "rate", "near", "Near the centre", "answers within 100 px of the centre", over="all"),
        Metric("offset", "lower", "mean", "offset", "Offset", "mean distance from the centre in pixels"),
    )

    def score(self, instance, answer, dataset=None):
        offset = abs(answer.x - 255.5) + abs(answer.y - 255.5)
        return {"answered": True, "near": offset < 100, "offset": offset}


@hookimpl
def register_scorers(register):
    register("test-near", NearScorer, description="test: near the centre")
'''


def run_with_near(tmp_path, write_pipeline, offline_plugin, scorers):
    (tmp_path / "near_plugin.py").write_text(NEAR_PLUGIN, encoding="utf-8")
    path = write_pipeline(plugins=[offline_plugin.__file__, "near_plugin.py"], scorers=scorers)
    result = CliRunner().invoke(app, ["run", str(path)], env={"COLUMNS": "200"})
    assert result.exit_code == 0, result.output
    return tmp_path / "run", result.stdout


def test_a_third_party_scorers_metrics_are_in_the_summary_per_slice(tmp_path, write_pipeline, offline_plugin):
    folder, _ = run_with_near(tmp_path, write_pipeline, offline_plugin, ["test-near"])
    metrics = json.loads((folder / "summary.json").read_text(encoding="utf-8"))["metrics"]["test-near"]
    assert set(metrics["declared"]) == {"near_rate", "offset"}
    assert metrics["overall"]["near_rate"]["value"] == 1.0 and metrics["overall"]["offset"]["value"] == 0.0
    assert metrics["overall"]["near_rate"]["n"] == 12 and set(metrics["per_condition"]) == {"a", "b", "c"}


def test_a_third_party_scorers_metrics_get_a_console_table(tmp_path, write_pipeline, offline_plugin):
    _, printed = run_with_near(tmp_path, write_pipeline, offline_plugin, ["test-near"])
    assert "scorer test-near" in printed and "Near the centre ↑" in printed and "Offset ↓" in printed


def test_rescore_writes_the_same_metrics_section(tmp_path, write_pipeline, offline_plugin):
    folder, _ = run_with_near(tmp_path, write_pipeline, offline_plugin, ["official", "test-near"])
    result = rescore_run(folder, "test-json", plugins=[offline_plugin.__file__, str(tmp_path / "near_plugin.py")])
    ran = json.loads((folder / "summary.json").read_text(encoding="utf-8"))["metrics"]
    assert json.loads((result.out_dir / "summary.json").read_text(encoding="utf-8"))["metrics"] == ran


def test_the_official_scorers_declared_mean_is_the_official_number(tmp_path, write_pipeline, offline_plugin):
    folder, _ = run_with_near(tmp_path, write_pipeline, offline_plugin, ["official"])
    summary = json.loads((folder / "summary.json").read_text(encoding="utf-8"))
    declared = summary["metrics"]["official"]
    assert declared["overall"]["mean_l2"]["value"] == summary["overall"]["mean_l2"]
    assert declared["overall"]["response_rate"]["value"] == summary["overall"]["response_rate"]
    assert set(declared["declared"]) == {"mean_l2", "response_rate", "strict_l2", "frame_accuracy", "blind_spot", "center_l2"}


def test_a_third_party_scorers_metrics_get_a_report_table(tmp_path, write_pipeline, offline_plugin):
    folder, _ = run_with_near(tmp_path, write_pipeline, offline_plugin, ["test-near"])
    out = tmp_path / "report"
    result = CliRunner().invoke(app, ["report", str(folder), "--out", str(out), "--bootstrap", "50", "--no-gallery"])
    assert result.exit_code == 0, result.output
    tables = (out / "tables.md").read_text(encoding="utf-8")
    assert "Scorer test-near" in tables and "Near the centre" in tables and "100.0%" in tables


def test_rescore_prints_a_third_party_scorers_metrics_table(tmp_path, write_pipeline, offline_plugin):
    folder, _ = run_with_near(tmp_path, write_pipeline, offline_plugin, ["official", "test-near"])
    plugins = ["--plugin", offline_plugin.__file__, "--plugin", str(tmp_path / "near_plugin.py")]
    result = CliRunner().invoke(app, ["rescore", str(folder), "--parser", "test-json", *plugins], env={"COLUMNS": "200"})
    assert result.exit_code == 0, result.output
    assert "scorer test-near" in result.stdout and "Offset ↓" in result.stdout
