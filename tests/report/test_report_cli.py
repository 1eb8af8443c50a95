"""The ``report``, ``export`` and ``compare`` commands (povagent/cli/reporting.py); here beside the
report tests because they share the simulated run and sweep fixtures of tests/report/conftest.py."""

from __future__ import annotations

import json

from typer.testing import CliRunner

from povagent.cli import app

runner = CliRunner()


def test_report_command_writes_the_page_and_prints_the_main_table(run_dir, tmp_path):
    result = runner.invoke(app, ["report", str(run_dir), "--out", str(tmp_path / "r"), "--bootstrap", "50"])
    assert result.exit_code == 0, result.output
    assert "| mock-a · basic |" in result.output and "Center baseline (computed)" in result.output
    assert (tmp_path / "r" / "report.html").exists() and (tmp_path / "r" / "tables" / "main.tex").exists()


def test_report_without_dataset_warns_and_still_writes_tables(run_dir, tmp_path):
    result = runner.invoke(app, ["report", str(run_dir), "--out", str(tmp_path / "r"), "--bootstrap", "0", "--dataset", str(tmp_path / "missing")])
    assert result.exit_code == 0, result.output
    assert "warning: no center baseline" in result.output
    assert (tmp_path / "r" / "tables" / "main.md").exists()


def test_export_command_writes_official_rows(run_dir, tmp_path):
    out = tmp_path / "p.json"
    result = runner.invoke(app, ["export", str(run_dir), "--format", "official", "--out", str(out), "--run", "0"])
    assert result.exit_code == 0, result.output
    assert len(json.loads(out.read_text())["predictions"]) == 18


def test_export_command_refuses_an_unknown_format(run_dir, tmp_path):
    result = runner.invoke(app, ["export", str(run_dir), "--format", "csv"])
    assert result.exit_code != 0 and "unknown export format" in str(result.exception)


def test_compare_command_prints_the_paired_summary_and_most_changed(sweep_dir, tmp_path):
    result = runner.invoke(app, ["compare", str(sweep_dir / "cell_00"), str(sweep_dir / "cell_02"), "--top", "3", "--bootstrap", "50", "--out", str(tmp_path)])
    assert result.exit_code == 0, result.output
    assert "Instances that changed most" in result.output and "Wilcoxon" in result.output and "95% CI" in result.output
    assert (tmp_path / "compare.html").exists()
