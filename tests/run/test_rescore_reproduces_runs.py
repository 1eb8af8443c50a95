"""``rescore RUN`` with the run's own parser reproduces the run: every row's parse, status,
prediction, scores and official reading, and ``summary.json``'s sections, for each dataset kind
and strategy (run and rescore share one score step and one loader choice)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import yaml

from povagent.config.pipeline import load_pipeline
from povagent.errors import PluginError
from povagent.results.rows import read_rows
from povagent.run.rescore import rescore_run
from povagent.run.runner import run_pipeline

pytestmark = pytest.mark.timeout(180)

DEMO = Path(__file__).resolve().parents[2] / "examples" / "realworld_demo"

#: What a row's answer reads as: the fields rescore recomputes.
SCORED_FIELDS = ("status", "parse", "prediction", "scores", "official_reading")
#: Summary sections only the runner writes (its session) or only rescore writes (what it re-read).
RUN_ONLY = {"pipeline", "complete", "interrupted", "stopped", "session", "images"}
RESCORE_ONLY = {"source_run", "parser", "n_rows", "parse_status", "repaired"}


def run(tmp_path: Path, **config) -> Path:
    doc = {"output": str(tmp_path / "run"), **config}
    (tmp_path / "pipeline.yaml").write_text(yaml.safe_dump(doc), encoding="utf-8")
    run_pipeline(load_pipeline(tmp_path / "pipeline.yaml"))
    return tmp_path / "run"


def assert_rescore_reproduces(folder: Path) -> None:
    ran = {r.key: r.model_dump(mode="json", include=set(SCORED_FIELDS)) for r in read_rows(folder / "results.jsonl")}
    (parser,) = {r.parser for r in read_rows(folder / "results.jsonl")}
    result = rescore_run(folder, parser)
    again = {r.key: r.model_dump(mode="json", include=set(SCORED_FIELDS)) for r in read_rows(result.out_dir / "results.jsonl")}
    assert again == ran
    summary = json.loads((folder / "summary.json").read_text(encoding="utf-8"))
    rescored = json.loads((result.out_dir / "summary.json").read_text(encoding="utf-8"))
    assert {k: v for k, v in rescored.items() if k not in RESCORE_ONLY} == {k: v for k, v in summary.items() if k not in RUN_ONLY}


def test_a_run_showing_fewer_frames_rescores_to_its_own_scores(tmp_path, small_release, povagent_host, offline_plugin):
    # frame 2 exists in the instance but was never shown (max_frames: 2): no frame, as in the run
    folder = run(
        tmp_path, plugins=[offline_plugin.__file__], dataset={"path": str(small_release)},
        backend={"name": "test-center", "options": {"reply": '{"selected_image": 2, "x": 100, "y": 200}'}},
        strategy={"name": "basic", "options": {"max_frames": 2}}, parser="json", scorers=["official"],
    )  # fmt: skip
    answered_ab = [r for r in read_rows(folder / "results.jsonl") if r.condition != "c" and r.scores["official"]["answered"]]
    assert answered_ab == []
    assert_rescore_reproduces(folder)


@pytest.fixture(scope="module")
def active_run(generated_release, tmp_path_factory) -> Path:
    """Three keys of the active strategy, the random explorer looking around (8 of 12 frames shown)."""
    return run(
        tmp_path_factory.mktemp("active"), dataset={"path": str(generated_release)},
        instances={"houses": ["train_house_00001"], "limit": 3}, backend="explorer-random", strategy="active",
        scorers=["official"],
    )  # fmt: skip


def test_an_active_run_rescores_to_its_own_scores(active_run):
    assert_rescore_reproduces(active_run)


def test_rescore_refuses_a_parser_that_cannot_read_the_runs_answers(active_run):
    with pytest.raises(PluginError, match="parser 'json' cannot read the answers of strategy 'active'"):
        rescore_run(active_run, "json")
    assert not (active_run / "rescored-json").exists()


#: Official-format answers to the demo set's A/B commands: a hit, a non-response, a miss, an
#: answer in an unmarked frame.
DEMO_ANSWERS = [
    {"house_id": "house_1", "pair_id": "kitchen", "direction": "right", "type": "a",
     "predicted_image": "house_1/frame_01.jpg", "predicted_x": 216.0, "predicted_y": 236.0},
    {"house_id": "house_1", "pair_id": "kitchen", "direction": "right", "type": "b"},
    {"house_id": "house_1", "pair_id": "bedroom", "direction": "up", "type": "a",
     "predicted_image": "house_1/frame_02.jpg", "predicted_x": 20.0, "predicted_y": 130.0},
    {"house_id": "house_1", "pair_id": "study", "direction": "front", "type": "a",
     "predicted_image": "house_1/frame_00.jpg", "predicted_x": 256.0, "predicted_y": 256.0},
]  # fmt: skip


def test_a_real_world_run_rescores_to_its_own_scores(tmp_path):
    (tmp_path / "answers.json").write_text(json.dumps(DEMO_ANSWERS), encoding="utf-8")
    folder = run(
        tmp_path, dataset={"path": str(DEMO)}, backend={"name": "replay", "options": {"path": str(tmp_path / "answers.json")}},
        instances={"houses": ["house_1"], "conditions": ["a", "b"]}, strategy="basic", parser="json", scorers=["success"],
    )  # fmt: skip
    assert_rescore_reproduces(folder)


def test_an_answered_rows_prediction_carries_its_typed_point(tmp_path, small_release, povagent_host, offline_plugin):
    folder = run(
        tmp_path, plugins=[offline_plugin.__file__], dataset={"path": str(small_release)},
        backend={"name": "test-center", "options": {"reply": '{"selected_image": 1, "x": 100, "y": 200}'}},
        strategy="basic", parser="json", scorers=["official"],
    )  # fmt: skip
    rows = read_rows(folder / "results.jsonl")
    ab = [r for r in rows if r.condition != "c"]
    assert ab and all(r.prediction.answer_type == "point" and r.prediction.value == {"selected_image": 1, "x": 100.0, "y": 200.0}
                      for r in ab)  # fmt: skip
