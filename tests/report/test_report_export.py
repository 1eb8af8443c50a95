"""Exporting runs in the official prediction format and reading them back."""

from __future__ import annotations

import json

import pytest

from povagent.errors import PredictionsError
from povagent.report.export import export_run
from povagent.results.official_format import read_official_predictions
from povagent.results.prediction_files import score_predictions
from povagent.results.rows import read_rows
from povagent.scoring.breakdown import ScoredRow, breakdown


def test_export_writes_one_official_file_per_run_index(run_dir, tmp_path):
    files = export_run(run_dir, tmp_path / "preds.json")
    assert [f.name for f in files] == ["run_0.json", "run_1.json"]
    doc = json.loads(files[1].read_text())
    assert doc["metadata"]["run"] == 1 and doc["metadata"]["model"] == "mock-a"
    assert len(doc["predictions"]) == 18


def test_exported_rows_have_the_official_fields(run_dir, tmp_path, mini_dataset):
    (path,) = export_run(run_dir, tmp_path / "p.json", run=0)
    rows = read_official_predictions(path)
    ours = {r.instance_id: r for r in read_rows(run_dir / "results.jsonl") if r.run == 0}
    for row in rows:
        mine = ours[row.instance_id]
        answered = mine.scores["official"]["answered"]
        assert row.parse_error is (not answered)
        if row.type.value == "c":
            assert row.predicted_image is None and row.candidate_images is None
        else:
            inst = mini_dataset.instance(row.instance_id)
            assert row.candidate_images == [f.image_path for f in inst.frames]
            if answered:
                assert row.predicted_image == inst.frames[mine.prediction.selected_image].image_path


def test_exported_predictions_score_exactly_like_the_run(run_dir, tmp_path, mini_dataset):
    (path,) = export_run(run_dir, tmp_path / "p.json", run=1)
    summary, warnings = score_predictions(path, mini_dataset)
    assert warnings == []
    rows = [r for r in read_rows(run_dir / "results.jsonl") if r.run == 1]
    expected = breakdown(
        ScoredRow(r.condition, r.direction, r.scores["official"]["answered"], r.scores["official"]["l2"], r.scores["official"]["gt_in_frame"])
        for r in rows
    )
    assert summary["overall"]["mean_l2"] == pytest.approx(expected["overall"]["mean_l2"], abs=1e-12)
    assert summary["overall"]["response_rate"] == expected["overall"]["response_rate"]
    for c, cell in expected["per_condition"].items():
        assert summary["per_condition"][c]["mean_l2"] == pytest.approx(cell["mean_l2"], abs=1e-12)


def test_exporting_a_sweep_folder_asks_for_one_run_folder(sweep_dir, tmp_path):
    with pytest.raises(PredictionsError, match="one run folder at a time"):
        export_run(sweep_dir, tmp_path / "x.json")


def test_exported_predictions_replayed_through_the_runner_score_exactly_like_the_run(run_dir, tmp_path, mini_root):
    import yaml

    from povagent.config.pipeline import load_pipeline
    from povagent.run.runner import run_pipeline

    (path,) = export_run(run_dir, tmp_path / "p.json", run=0)
    doc = {
        "dataset": str(mini_root),
        "backend": {"name": "replay", "options": {"path": str(path)}},
        "strategy": "basic",
        "parser": "json",
        "scorers": ["official"],
        "cache": False,
        "output": str(tmp_path / "replayed"),
    }
    (tmp_path / "pipeline.yaml").write_text(yaml.safe_dump(doc))
    result = run_pipeline(load_pipeline(tmp_path / "pipeline.yaml"))
    original = {r.instance_id: r.scores["official"] for r in read_rows(run_dir / "results.jsonl") if r.run == 0}
    replayed = {r.instance_id: r.scores.get("official") or {} for r in read_rows(result.run_dir / "results.jsonl")}
    assert set(replayed) == set(original)
    for iid, off in original.items():
        again = replayed[iid]
        assert bool(again.get("answered")) == bool(off["answered"]), iid
        if off["answered"]:
            assert again["l2"] == pytest.approx(off["l2"], abs=1e-9), iid
