"""After ``povagent run``, a run parsed leniently shows the official parse's numbers beside its own."""

from __future__ import annotations

import yaml
from typer.testing import CliRunner

from povagent.cli import app

runner = CliRunner()


def run_cli(tmp_path, mini_root, parser: str):
    pipeline = tmp_path / f"{parser}.yaml"
    pipeline.write_text(yaml.safe_dump({
        "dataset": {"path": str(mini_root)},
        "instances": {"conditions": ["a", "c"]},
        "backend": {"name": "center", "options": {"frame_policy": "first"}},
        "strategy": "basic",
        "parser": parser,
        "scorers": ["official"],
        "output": str(tmp_path / f"run-{parser}"),
    }))
    result = runner.invoke(app, ["run", str(pipeline), "--quiet"], env={"COLUMNS": "200"})
    assert result.exit_code == 0, result.output
    return result.stdout


def test_a_lenient_run_prints_the_official_parse_beside(tmp_path, mini_root):
    out = run_cli(tmp_path, mini_root, "json")
    assert "Official parse beside 'json' (repaired)" in out
    assert "L2 official (official)" in out and "resp. official" in out


def test_an_official_run_prints_no_second_table(tmp_path, mini_root):
    out = run_cli(tmp_path, mini_root, "official")
    assert "Official parse beside" not in out and "note:" not in out
