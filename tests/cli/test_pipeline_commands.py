"""``povagent run`` and ``povagent sweep`` on the shipped examples, offline, from the command line."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
from typer.testing import CliRunner

from povagent.cli import app
from povagent.errors import DatasetError

REPO = Path(__file__).resolve().parents[2]
runner = CliRunner()


@pytest.fixture
def examples_cwd(tmp_path, monkeypatch, mini_root):
    """A working directory laid out like the repository: the shipped examples and the fixture."""
    (tmp_path / "examples").mkdir()
    for name in ("pipeline_center.yaml", "sweep_baselines.yaml"):
        shutil.copy(REPO / "examples" / name, tmp_path / "examples" / name)
    (tmp_path / "tests" / "fixtures").mkdir(parents=True)
    (tmp_path / "tests" / "fixtures" / "povbench_mini").symlink_to(mini_root, target_is_directory=True)
    monkeypatch.chdir(tmp_path)
    return tmp_path


def test_the_shipped_pipeline_runs_offline_then_resumes_with_no_request(examples_cwd):
    first = runner.invoke(app, ["run", "examples/pipeline_center.yaml", "--quiet", "--json"])
    assert first.exit_code == 0, first.output
    summary = json.loads(first.stdout)
    assert summary["complete"] and summary["rows"]["answered"] == 18 and summary["session"]["requests"] == 18
    again = runner.invoke(app, ["run", "examples/pipeline_center.yaml", "--quiet", "--json"])
    assert again.exit_code == 0, again.output
    assert json.loads(again.stdout)["session"]["requests"] == 0
    assert len((examples_cwd / "runs/example-center/results.jsonl").read_text().splitlines()) == 18


def test_the_shipped_sweep_dry_run_counts_requests_then_nothing_is_left(examples_cwd):
    plan = runner.invoke(app, ["sweep", "examples/sweep_baselines.yaml", "--dry-run"])
    assert plan.exit_code == 0, plan.output
    total = next(line for line in plan.stdout.splitlines() if "total" in line)
    assert "54" in total  # 9 cells x 6 instances, none done yet
    assert not (examples_cwd / "runs/example-baselines/center__a/results.jsonl").exists()  # a dry run runs nothing
    done = runner.invoke(app, ["sweep", "examples/sweep_baselines.yaml", "--quiet"])
    assert done.exit_code == 0, done.output
    index = json.loads((examples_cwd / "runs/example-baselines/sweep.json").read_text())
    assert len(index["cells"]) == 9 and {c["status"] for c in index["cells"]} == {"done"}
    after = runner.invoke(app, ["sweep", "examples/sweep_baselines.yaml", "--dry-run"])
    cells = [line.split("│") for line in after.stdout.splitlines() if "__" in line]
    assert len(cells) == 9 and all((c[3].strip(), c[4].strip()) == ("6", "0") for c in cells)  # done, still to make


def test_run_strict_stops_at_the_broken_fixture_house(examples_cwd):
    result = runner.invoke(app, ["run", "examples/pipeline_center.yaml", "--quiet", "--strict"])
    assert isinstance(result.exception, DatasetError)
    assert "train_house_00002" in str(result.exception)
    assert not (examples_cwd / "runs/example-center").exists()
