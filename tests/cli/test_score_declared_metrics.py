"""``povagent score`` reports the official scorer's declared metrics (summary ``metrics``
section, per slice, with bootstrap CIs) computed by the same function as run and rescore, and
prints their table."""

from __future__ import annotations

import json

import pytest
from typer.testing import CliRunner

from povagent.cli import app

runner = CliRunner()

#: Answers over conditions A and C, one the official parser cannot read.
ANSWERS = [
    ("train_house_00000/0/right/c", '{"x": 300, "y": 200}'),
    ("train_house_00000/0/left/c", '{"x": 100, "y": 100}'),
    ("train_house_00000/0/left/a", '{"selected_image": 0, "x": 40, "y": 470}'),
    ("train_house_00000/0/up/c", "somewhere near the bed"),
]


def score(path, mini_root, *extra):
    result = runner.invoke(app, ["score", "--predictions", str(path), "--dataset", str(mini_root), *extra], env={"COLUMNS": "200"})
    assert result.exit_code == 0, result.output
    return result.stdout


def official_file(tmp_path, name, x, y):
    """An official predictions file answering every C instance of house 0 at ``(x, y)``."""
    rows = [{"house_id": "train_house_00000", "pair_id": 0, "direction": d, "type": "c", "predicted_x": x, "predicted_y": y,
             "predicted_image": None, "parse_error": False} for d in ("left", "right", "up")]  # fmt: skip
    path = tmp_path / name
    path.write_text(json.dumps(rows), encoding="utf-8")
    return path


def test_scores_declared_metrics_equal_rescores_for_the_same_answers(tmp_path, mini_root, write_answered_run):
    run = write_answered_run(tmp_path / "run", ANSWERS)
    rescored = runner.invoke(app, ["rescore", str(run), "--parser", "official", "--json"])
    assert rescored.exit_code == 0, rescored.output
    expected = json.loads(rescored.stdout)["metrics"]["official"]
    scored = json.loads(score(run / "rescored-official", mini_root, "--json"))["metrics"]["official"]
    assert scored == expected
    assert scored["overall"]["response_rate"]["n"] == 4 and set(scored["per_condition"]) == {"a", "c"}


def test_the_declared_mean_of_an_official_file_is_the_official_number(tmp_path, mini_root):
    summary = json.loads(score(official_file(tmp_path, "p.json", 100, 400), mini_root, "--json"))
    declared = summary["metrics"]["official"]["overall"]
    assert declared["mean_l2"]["value"] == pytest.approx(summary["overall"]["mean_l2"], abs=1e-12)
    assert declared["response_rate"]["value"] == summary["overall"]["response_rate"] == 1.0
    assert declared["mean_l2"]["ci_lo"] <= declared["mean_l2"]["value"] <= declared["mean_l2"]["ci_hi"]


def test_the_centre_baseline_of_an_official_file_is_the_error_of_answering_the_centre(tmp_path, mini_root):
    answered = json.loads(score(official_file(tmp_path, "p.json", 100, 400), mini_root, "--json"))
    centre = json.loads(score(official_file(tmp_path, "centre.json", 256, 256), mini_root, "--json"))
    assert answered["metrics"]["official"]["overall"]["center_l2"]["value"] == pytest.approx(centre["overall"]["mean_l2"], abs=1e-12)
    assert answered["overall"]["mean_l2"] != centre["overall"]["mean_l2"]


def test_score_prints_the_declared_metrics_table(tmp_path, mini_root):
    printed = score(official_file(tmp_path, "p.json", 100, 400), mini_root)
    assert "scorer official" in printed and "GT behind camera ↓" in printed and "Centre guess L2 ↓" in printed
