"""``povagent validate`` and ``povagent score`` from the command line."""

from __future__ import annotations

import json
import math
import shutil
from pathlib import Path

import pytest
from console_once import console_script_once
from typer.testing import CliRunner

from povagent.cli import app

runner = CliRunner()


def test_validate_lists_every_problem_and_exits_non_zero(mini_root):
    result = runner.invoke(app, ["validate", str(mini_root)])
    assert result.exit_code == 1
    lines = [line for line in result.stdout.splitlines() if line.startswith("artifacts/train_house_00002/")]
    assert len(lines) == 9
    assert "9 problem(s)" in result.output


def test_validate_passes_a_clean_dataset(mini_root, tmp_path):
    root = tmp_path / "clean"
    shutil.copytree(mini_root, root, ignore=shutil.ignore_patterns("train_house_00002"))
    result = runner.invoke(app, ["validate", str(root)])
    assert result.exit_code == 0, result.output
    assert "valid" in result.output


def official_rows():
    return [
        {"house_id": "train_house_00000", "pair_id": 0, "direction": "up", "type": "c", "sentence": "s",
         "predicted_x": 256, "predicted_y": 256, "predicted_image": None, "parse_error": False, "candidate_images": []},
        {"house_id": "train_house_00000", "pair_id": 0, "direction": "left", "type": "b", "sentence": "s",
         "predicted_x": 256, "predicted_y": 256, "predicted_image": "exploration_images/frame_001.png",
         "parse_error": False, "candidate_images": []},
        {"house_id": "train_house_00000", "pair_id": 0, "direction": "front", "type": "a", "sentence": "s",
         "predicted_x": None, "predicted_y": None, "predicted_image": None, "parse_error": True},
    ]


@pytest.mark.parametrize("wrap", [False, True])
def test_score_json_prints_official_summary_keys_and_values(mini_root, tmp_path, wrap):
    doc = {"metadata": {"model": "x"}, "predictions": official_rows()} if wrap else official_rows()
    path = tmp_path / "preds.json"
    path.write_text(json.dumps(doc))
    result = runner.invoke(app, ["score", "--predictions", str(path), "--dataset", str(mini_root), "--json"])
    assert result.exit_code == 0, result.output
    out = json.loads(result.stdout)
    assert set(out) >= {"overall", "per_condition", "per_direction"}
    overall = out["overall"]
    assert set(overall) >= {"n", "n_total", "response_rate", "mean_l2", "std_l2", "pct_in_frame"}
    e_up = 0.5 * 0.7 / 3.0  # centre vs GT (0.5, 0.5 + 0.35/3)
    assert overall["n"] == 2 and overall["n_total"] == 3
    assert overall["mean_l2"] == pytest.approx((e_up + 0.0) / 2, abs=1e-9)
    assert out["per_condition"]["a"]["response_rate"] == 0.0
    assert math.isclose(out["per_direction"]["up"]["pct_in_frame"], 100.0)


def test_score_reads_a_folder_of_prediction_files(mini_root, tmp_path):
    folder = tmp_path / "preds"
    folder.mkdir()
    rows = official_rows()
    (folder / "part1.json").write_text(json.dumps(rows[:1]))
    (folder / "part2.json").write_text(json.dumps({"metadata": {}, "predictions": rows[1:]}))
    result = runner.invoke(app, ["score", "--predictions", str(folder), "--dataset", str(mini_root), "--json"])
    assert result.exit_code == 0, result.output
    assert json.loads(result.stdout)["overall"]["n_total"] == 3


def test_score_of_a_malformed_file_is_a_clear_message_not_a_traceback(mini_root, tmp_path_factory):
    # score --predictions bad.json, a JSON list cut off mid-row, --dataset the hand-made set
    proc = console_script_once(tmp_path_factory, mini_root)["score"]
    assert proc.returncode != 0
    assert "Traceback" not in proc.stderr
    assert "bad.json" in proc.stderr


def test_score_counts_an_unknown_direction_as_unanswered_and_names_the_row(mini_root, tmp_path):
    path = tmp_path / "odd.json"
    path.write_text('[{"house_id": "train_house_00000", "pair_id": 0, "direction": "sideways", "type": "c", "predicted_x": 1, "predicted_y": 1}]')
    result = runner.invoke(app, ["score", "--predictions", str(path), "--dataset", str(mini_root), "--json"])
    assert result.exit_code == 0, result.output
    out = json.loads(result.stdout)
    assert out["overall"]["n_total"] == 1 and out["overall"]["n"] == 0
    assert out["per_direction"]["sideways"]["n_total"] == 1
    assert "odd.json: row 0" in result.stderr and "'sideways'" in result.stderr


def test_score_reads_an_official_json_lines_file(mini_root, tmp_path):
    path = tmp_path / "preds.jsonl"
    path.write_text("".join(json.dumps(r) + "\n" for r in official_rows()))
    result = runner.invoke(app, ["score", "--predictions", str(path), "--dataset", str(mini_root), "--json"])
    assert result.exit_code == 0, result.output
    assert json.loads(result.stdout)["overall"]["n_total"] == 3


def test_score_warns_about_the_houses_it_skipped(mini_root, tmp_path):
    path = tmp_path / "preds.json"
    path.write_text(json.dumps(official_rows()))
    result = runner.invoke(app, ["score", "--predictions", str(path), "--dataset", str(mini_root), "--json"])
    assert result.exit_code == 0, result.output
    assert "warning: dataset problem, skipped by povagent's loader (official rows are counted against the release" in result.stderr
    assert "as officially): artifacts/train_house_00002/" in result.stderr
    own = runner.invoke(app, ["score", "--predictions", str(path), "--dataset", str(mini_root), "--json", "--counting", "povagent"])
    assert "warning: dataset problem, skipped: artifacts/train_house_00002/" in own.stderr
    strict = runner.invoke(app, ["score", "--predictions", str(path), "--dataset", str(mini_root), "--strict"])
    assert strict.exit_code != 0 and "train_house_00002" in str(strict.exception)


def test_validate_names_a_file_of_the_wrong_shape_plainly(mini_root, tmp_path):
    root = tmp_path / "ds"
    shutil.copytree(mini_root, root, ignore=shutil.ignore_patterns("train_house_00002"))
    (root / "artifacts/train_house_00001/exploration_log.json").write_text('{"frames": []}')
    result = runner.invoke(app, ["validate", str(root)])
    assert result.exit_code == 1
    assert "artifacts/train_house_00001/exploration_log.json: the file must hold a JSON list" in result.stdout


def test_validate_reads_a_real_world_folder_as_a_real_world_set():
    demo = Path(__file__).resolve().parents[2] / "examples" / "realworld_demo"
    result = runner.invoke(app, ["validate", str(demo)])
    assert result.exit_code == 0, result.output
    assert result.stdout == f"{demo}: valid\n"


def test_validate_help_lists_every_registered_format():
    from povagent.dataset.formats import registered_formats
    from povagent.plugins import get_plugin_host

    shown = " ".join(runner.invoke(app, ["validate", "--help"]).stdout.split())
    assert f"Registered: {', '.join(registered_formats(get_plugin_host()))}." in shown
