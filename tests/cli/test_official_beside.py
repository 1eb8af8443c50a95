"""After ``povagent run``, a run parsed leniently shows the official parse's numbers beside its own."""

from __future__ import annotations

import yaml
from typer.testing import CliRunner

from povagent.cli import app

runner = CliRunner()


#: An answer only a repair reads: the official runner's json.loads rejects the trailing comma.
TRAILING_COMMA = '{"x": 100, "y": 100,}'


def run_cli(tmp_path, mini_root, parser: str | None, backend: dict | None = None):
    pipeline = tmp_path / f"{parser}.yaml"
    config = {
        "plugins": [str(tmp_path / "offline_plugin.py")] if tmp_path.joinpath("offline_plugin.py").exists() else [],
        "dataset": {"path": str(mini_root)},
        "instances": {"conditions": ["c"]},
        "backend": backend or {"name": "center", "options": {"frame_policy": "first"}},
        "strategy": "basic",
        "parser": parser,
        "scorers": ["official"],
        "output": str(tmp_path / f"run-{parser}"),
    }
    pipeline.write_text(yaml.safe_dump({k: v for k, v in config.items() if v is not None}))
    result = runner.invoke(app, ["run", str(pipeline), "--quiet"], env={"COLUMNS": "200"})
    assert result.exit_code == 0, result.output
    return result.stdout


def test_a_repair_that_changed_answers_prints_the_official_parse_beside(tmp_path, mini_root, offline_plugin_file):
    out = run_cli(tmp_path, mini_root, "json", {"name": "test-center", "options": {"reply": TRAILING_COMMA}})
    assert "Official parse beside 'json' (repaired)" in out
    assert "L2 official (official)" in out and "resp. official" in out


def test_a_repair_that_changed_no_answer_prints_no_second_table(tmp_path, mini_root, offline_plugin_file):
    out = run_cli(tmp_path, mini_root, "json", {"name": "test-center"})
    assert "Official parse beside" not in out and "note:" not in out


def test_a_baseline_parsed_by_a_repair_prints_no_second_table(tmp_path, mini_root):
    out = run_cli(tmp_path, mini_root, "json")
    assert "Official parse beside" not in out and "note:" not in out


def test_a_pipeline_naming_no_parser_reads_officially(tmp_path, mini_root, offline_plugin_file):
    run_cli(tmp_path, mini_root, None, {"name": "test-center", "options": {"reply": TRAILING_COMMA}})
    summary = yaml.safe_load((tmp_path / "run-None" / "summary.json").read_text())
    assert summary["pipeline"]["parser"] == "official"
    assert summary["overall"]["response_rate"] == 0.0


def test_an_official_run_prints_no_second_table(tmp_path, mini_root):
    out = run_cli(tmp_path, mini_root, "official")
    assert "Official parse beside" not in out and "note:" not in out


def test_a_sweep_table_shows_the_official_parse_of_cells_a_repair_changed(tmp_path, mini_root, offline_plugin_file):
    base = tmp_path / "base.yaml"
    base.write_text(yaml.safe_dump({
        "plugins": [str(offline_plugin_file)],
        "dataset": {"path": str(mini_root)},
        "instances": {"conditions": ["c"]},
        "backend": {"name": "test-center", "options": {"reply": TRAILING_COMMA}},
        "strategy": "basic",
        "scorers": ["official"],
        "output": str(tmp_path / "unused"),
    }))
    sweep = tmp_path / "sweep.yaml"
    sweep.write_text(yaml.safe_dump({"base": "base.yaml", "output": str(tmp_path / "sweep"), "axes": {"parser": ["json", "official"]}}))
    result = runner.invoke(app, ["sweep", str(sweep), "--quiet"], env={"COLUMNS": "200"})
    assert result.exit_code == 0, result.output
    assert "official parse L2" in result.stdout and "official parse resp." in result.stdout
    rows = {line.split("│")[1].strip(): line for line in result.stdout.splitlines() if line.startswith("│")}
    cells = [c.strip() for c in rows["json"].split("│")[1:-1]]
    assert cells[2] == "100.0%" and cells[5] == "0.0%"  # repaired: every answer; official: none
    assert rows["official"].split("│")[5].strip() == "="  # reads officially itself


def test_a_sweep_of_baselines_parsed_by_a_repair_shows_no_official_columns(tmp_path, mini_root):
    base = tmp_path / "base.yaml"
    base.write_text(yaml.safe_dump({
        "dataset": {"path": str(mini_root)},
        "instances": {"conditions": ["c"]},
        "backend": {"name": "center", "options": {"frame_policy": "first"}},
        "parser": "json",
        "output": str(tmp_path / "unused"),
    }))
    sweep = tmp_path / "sweep.yaml"
    sweep.write_text(yaml.safe_dump({"base": "base.yaml", "output": str(tmp_path / "sweep"), "axes": {"backend": ["center", "random"]}}))
    result = runner.invoke(app, ["sweep", str(sweep), "--quiet"], env={"COLUMNS": "200"})
    assert result.exit_code == 0, result.output
    assert "official parse" not in result.stdout and "Official parse beside" not in result.stdout


def test_run_warns_about_rows_with_a_nan_coordinate(tmp_path, mini_root, offline_plugin_file):
    offline = str(offline_plugin_file)
    pipeline = tmp_path / "nan.yaml"
    pipeline.write_text(yaml.safe_dump({
        "plugins": [offline],
        "dataset": {"path": str(mini_root)},
        "instances": {"conditions": ["c"], "limit": 1},
        "backend": {"name": "test-center", "options": {"reply": '{"x": NaN, "y": 100}'}},
        "strategy": "basic",
        "parser": "official",
        "scorers": ["official"],
        "output": str(tmp_path / "run-nan"),
    }))
    result = runner.invoke(app, ["run", str(pipeline), "--quiet"])
    assert result.exit_code == 0, result.output
    assert "NaN coordinate" in result.stderr and "/c#0" in result.stderr
