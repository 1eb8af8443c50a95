"""``povagent quickstart``: baselines swept, table printed, report written, resumable."""

from __future__ import annotations

import json

from typer.testing import CliRunner

from povagent.cli import app

runner = CliRunner()


def test_quickstart_on_a_given_dataset_prints_the_main_table_and_writes_the_report(mini_root, tmp_path):
    out = tmp_path / "qs"
    result = runner.invoke(app, ["quickstart", "--out", str(out), "--dataset", str(mini_root), "--quiet"])
    assert result.exit_code == 0, result.output
    assert "| Baseline | Inferred | Stated | Given |" in result.output  # only baselines ran: no "Model" column
    oracle_line = next(line for line in result.output.splitlines() if "oracle" in line and line.startswith("|"))
    assert oracle_line.count("0.000") >= 3  # the oracle is the metric's floor: the pipeline is wired right
    assert (out / "sweep" / "report" / "report.html").exists()
    cells = json.loads((out / "sweep" / "sweep.json").read_text())
    assert len(cells["cells"]) == 3


def test_running_the_quickstart_again_makes_no_new_rows(mini_root, tmp_path):
    out = tmp_path / "qs"
    args = ["quickstart", "--out", str(out), "--dataset", str(mini_root), "--quiet"]
    assert runner.invoke(app, args).exit_code == 0
    files = sorted((out / "sweep").rglob("results.jsonl"))
    before = [f.read_bytes() for f in files]
    assert runner.invoke(app, args).exit_code == 0
    assert [f.read_bytes() for f in files] == before
