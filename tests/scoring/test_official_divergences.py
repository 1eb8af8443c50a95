"""The last divergences from the authors' scorer (issue 24, item 5), each pinned.

``povagent score`` counts official prediction rows exactly as ``eval_results.py`` does by
default (``--counting official``): the release indexed as it indexes it, pair ids and log paths
compared as written, every pair it can read scored with its defaults. ``--counting povagent``
keeps povagent's own (the loader's checks). A prediction root's stray files are ignored, and
summaries carry the official ``mean_abs_x``/``mean_abs_y`` and ``n_parse_error``.

Fixture geometry (tests/fixtures/make_povbench_mini.py): house 0's observer camera and its
frame 0 sit at (0, 1.5, 0), yaw 0, horizon 0, fov 90; the bed (pair 0) is centred at (0, 0.3, 3).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest
from typer.testing import CliRunner

from povagent.cli import app
from povagent.dataset import load_dataset
from povagent.dataset.loader import anchor_type
from povagent.results.prediction_files import score_predictions
from povagent.results.rows import ExchangeRecord, Prediction, ResultRow, ResultsWriter, RowStatus
from povagent.run.summary import summarize_run
from povagent.scoring.normalized_l2 import project_ground_truth
from povagent.scoring.official_release import read_release
from povagent.scoring.predictions import score_official_rows

runner = CliRunner()
H0, H1 = "train_house_00000", "train_house_00001"
FRAME0 = "exploration_images/frame_000.png"


def row(house=H0, pair=0, direction="left", cond="a", x=256.0, y=256.0, image=FRAME0, **extra):
    return {"house_id": house, "pair_id": pair, "direction": direction, "type": cond, "predicted_x": x,
            "predicted_y": y, "predicted_image": image, **extra}  # fmt: skip


def write(path: Path, doc) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(doc), encoding="utf-8")
    return path


def edit_pairs(root: Path, house: str, change) -> None:
    f = root / "artifacts" / house / f"{house}.json"
    pairs = json.loads(f.read_text())
    change(pairs)
    f.write_text(json.dumps(pairs))


def score_both(rows, root: Path):
    """``(official, povagent)``: the rows scored with each counting."""
    official, _ = score_official_rows(rows, read_release(root))
    own, _ = score_official_rows(rows, load_dataset(root, check_images=False))
    return official, own


def score_cli(preds: Path, root: Path, *flags: str) -> dict:
    result = runner.invoke(app, ["score", "--predictions", str(preds), "--dataset", str(root), "--json", *flags])
    assert result.exit_code == 0, result.output
    return json.loads(result.stdout)


# -- the loader's strictness: official counting by default ----------------------------------


def test_a_pair_id_is_compared_as_written(dataset_copy):
    # house 1 writes "7", house 0 writes 0: 7 and "0" name no pair officially
    rows = [row(house=H1, pair=7, direction="left", cond="c", image=None), row(pair="0", cond="c", image=None)]
    official, own = score_both(rows, dataset_copy)
    assert [s.score.reason for s in official] == ["entry_not_found", "entry_not_found"]
    assert [s.score.answered for s in own] == [True, True]


def test_a_dot_slash_log_path_matches_no_prediction_officially(dataset_copy):
    log = dataset_copy / "artifacts" / H0 / "exploration_log.json"
    records = json.loads(log.read_text())
    records[0]["image_path"] = "./" + FRAME0
    log.write_text(json.dumps(records))
    official, own = score_both([row(), row(image="./" + FRAME0)], dataset_copy)
    assert [s.score.reason for s in official] == ["image_not_in_log", "ok"]
    assert [s.score.answered for s in own] == [True, False]


def test_a_log_record_without_its_image_file_is_scored_officially(dataset_copy):
    (dataset_copy / "artifacts" / H0 / FRAME0).unlink()
    official, own = score_both([row()], dataset_copy)
    assert official[0].score.answered and not own[0].score.answered


@pytest.mark.parametrize(
    ("name", "bend", "same_as"),
    [
        # an empty type names no flat-topped anchor: the boundary rule, as for any other type
        ("empty landmark_type", lambda e: e.update(landmark_type=""), lambda e: e.update(landmark_type="Zzz")),
        # no box centre: the object's position stands in
        (
            "box without center",
            lambda e: e["object_landmark"]["raw_metadata"]["axisAlignedBoundingBox"].pop("center"),
            lambda e: e["object_landmark"]["raw_metadata"]["axisAlignedBoundingBox"].update(center=dict(e["object_landmark"]["position"])),
        ),
        # no corners: the top is the centre's height
        (
            "empty cornerPoints",
            lambda e: e["object_landmark"]["raw_metadata"]["axisAlignedBoundingBox"].update(cornerPoints=[]),
            lambda e: e["object_landmark"]["raw_metadata"]["axisAlignedBoundingBox"].update(cornerPoints=[[0.0, 0.3, 3.0]] * 8),
        ),
    ],
)
def test_a_pair_the_loader_skips_is_scored_officially_with_the_official_fallback(dataset_copy, tmp_path, name, bend, same_as):
    """Scored, and with the number the fallback gives (the same pair written out in full)."""

    def moved(e):  # the object's position off the box centre, so the fallback shows
        e["object_landmark"]["position"] = {"x": 0.4, "y": 0.3, "z": 3.3}

    edit_pairs(dataset_copy, H0, lambda ps: [moved(ps[0]), bend(ps[0])])
    rows = [row(direction=d, cond=c, image=FRAME0 if c != "c" else None) for d in ("left", "front", "up") for c in ("a", "c")]
    official, own = score_both(rows, dataset_copy)
    assert all(s.score.answered for s in official), name
    assert not any(s.score.answered for s in own), name  # povagent's loader skips the pair

    written = tmp_path / "written"
    import shutil

    shutil.copytree(dataset_copy, written)
    edit_pairs(written, H0, lambda ps: same_as(ps[0]))
    reference, _ = score_official_rows(rows, load_dataset(written, check_images=False))
    assert [s.score.l2 for s in official] == pytest.approx([s.score.l2 for s in reference], abs=1e-12)


def test_score_counts_officially_by_default_and_povagent_s_way_on_request(dataset_copy, tmp_path):
    preds = write(tmp_path / "p.json", [row(house=H1, pair=7, direction="left", cond="c", image=None)])
    official = score_cli(preds, dataset_copy)
    own = score_cli(preds, dataset_copy, "--counting", "povagent")
    assert (official["counting"], official["overall"]["n"]) == ("official", 0)
    assert (own["counting"], own["overall"]["n"]) == ("povagent", 1)


def test_anchor_type_says_it_is_the_landmark_type_with_no_official_fallback():
    doc = anchor_type.__doc__ or ""
    assert "landmark_type" in doc and "no fallback" in doc


# -- a prediction root's stray files -----------------------------------------------------------


def test_a_stray_json_file_at_a_prediction_root_is_ignored(tmp_path, mini_root):
    root = tmp_path / "eval_results"
    write(root / "POVBench_toy_0" / "predictions.json", {"predictions": [row(), row(x=None, y=None)]})
    write(root / "config.json", {"temperature": 0})
    summary, warnings = score_predictions(root, load_dataset(mini_root, check_images=False))
    assert summary["overall"]["n_total"] == 2 and summary["run_folders"] == ["POVBench_toy_0"]
    assert any("config.json" in w and "ignored" in w for w in warnings)


# -- mean_abs_x / mean_abs_y / n_parse_error ------------------------------------------------------


def test_score_json_has_the_official_mean_abs_errors_and_parse_error_count(dataset_copy, tmp_path):
    ds = load_dataset(dataset_copy, check_images=False)
    inst = ds.instance(f"{H0}/0/left/c")
    gt = project_ground_truth(inst.target, inst.frames[0].camera)
    gx, gy = min(1.0, max(0.0, gt.u)), min(1.0, max(0.0, gt.v))
    rows = [
        row(cond="c", image=None, x=100.0, y=50.0),
        row(cond="c", image=None, x=400.0, y=500.0),
        # RoboPoint: the first point is predicted_x/y; the signed error is its, not the centroid's
        row(cond="c", image=None, x=10.0, y=20.0, predicted_points=[[10.0, 20.0], [500.0, 500.0]]),
        row(cond="c", image=None, x=None, y=None, parse_error="failed to parse JSON"),
        row(cond="c", image=None, x=None, y=None, parse_error=None),
    ]
    summary = score_cli(write(tmp_path / "p.json", rows), dataset_copy)
    xs, ys = (100.0, 400.0, 10.0), (50.0, 500.0, 20.0)
    want_x = sum(abs(min(1.0, x / 512) - gx) for x in xs) / 3
    want_y = sum(abs(min(1.0, y / 512) - gy) for y in ys) / 3
    assert summary["overall"]["mean_abs_x"] == pytest.approx(want_x, abs=1e-12)
    assert summary["overall"]["mean_abs_y"] == pytest.approx(want_y, abs=1e-12)
    assert summary["n_parse_error"] == 1 and summary["overall"]["n_parse_error"] == 1


def test_summary_json_has_the_official_mean_abs_errors_and_parse_error_count(tmp_path):
    def make(key, status, score=None, **fields):
        return ResultRow(key=f"h/0/left/c#{key}", instance_id="h/0/left/c", house_id="h", pair_id="0", direction="left",
                         condition="c", run=key, status=status, scores={"official": score} if score else {}, **fields)  # fmt: skip

    ok = {"answered": True, "l2": 0.5, "l2_strict": 0.5, "gt_in_frame": True, "error_x": -0.3, "error_y": 0.4}
    rows = [
        make(0, RowStatus.ANSWERED, ok, prediction=Prediction(x=1.0, y=2.0)),
        make(1, RowStatus.PARSE_ERROR, exchanges=[ExchangeRecord(request_hash="r", raw="no idea")]),
        make(2, RowStatus.INFRA_ERROR, error_type="Timeout", error_message="timed out"),
    ]
    with ResultsWriter(tmp_path / "results.jsonl") as w:
        for r in rows:
            w.write(r)
    summary = summarize_run(tmp_path / "results.jsonl")
    assert summary["per_run"]["0"]["mean_abs_x"] == pytest.approx(0.3) and summary["per_run"]["0"]["mean_abs_y"] == pytest.approx(0.4)
    # the runner's official parse_error: a failed parse and a failed request, as officially
    assert summary["n_parse_error"] == 2


def test_a_run_writes_mean_abs_errors_into_summary_json(tmp_path, mini_root):
    import yaml

    doc = {"dataset": str(mini_root), "instances": {"limit": 6}, "backend": "center", "strategy": "basic",
           "parser": "official", "cache": False, "output": str(tmp_path / "run")}  # fmt: skip
    (tmp_path / "p.yaml").write_text(yaml.safe_dump(doc))
    assert runner.invoke(app, ["run", str(tmp_path / "p.yaml"), "--quiet"]).exit_code == 0
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    lines = [json.loads(line) for line in (tmp_path / "run" / "results.jsonl").read_text().splitlines()]
    errs = [r["scores"]["official"]["error_x"] for r in lines if r["scores"]["official"]["answered"]]
    assert errs and summary["overall"]["mean_abs_x"] == pytest.approx(sum(abs(e) for e in errs) / len(errs), abs=1e-12)
    assert summary["n_parse_error"] == 0
    assert math.isfinite(summary["overall"]["mean_abs_y"])
