"""Training exports of the generated choice tasks (relation, multi-hop): each example asks the
task's question and answers with its gold label after a geometry-grounded rationale, in every
export format; evaluation houses stay out as for the point task."""

from __future__ import annotations

import base64
import json
from pathlib import Path

import pytest

from povagent.config.models import TaskSpec
from povagent.dataset.loader import load_dataset
from povagent.geometry.directions import spec_of
from povagent.tasks.task_set import for_task
from povagent.train.export_options import ExportError, ExportOptions
from povagent.train.training_export import export_training_set
from povagent_plugins.strategies.choice import plain_text


def _asked(generated_release: Path, task: str) -> dict:
    """The task's instances by id, as a choice question."""
    return {i.id: i for i in for_task(load_dataset(generated_release, check_images=False), TaskSpec(name=task, answer="choice")).instances()}


def _label(answer: str) -> str:
    return json.loads(answer.splitlines()[-1])["choice"]


@pytest.mark.parametrize("task", ["relation", "multi-hop"])
def test_a_messages_export_answers_each_question_with_its_gold_label(task, generated_release, tmp_path):
    out = tmp_path / task
    report = export_training_set(generated_release, out, ExportOptions(format="messages", task=task, split="1,0,0"), check_release=False)
    rows = [json.loads(line) for p in sorted((out / "messages").glob("*.jsonl")) for line in p.read_text().splitlines()]
    asked = _asked(generated_release, task)
    assert rows and len(rows) == report.examples and {r["id"] for r in rows} <= set(asked)
    for row in rows:
        question = asked[row["id"]].question
        assert json.loads(row["answer"]) == {"choice": question.gold} and _label(row["messages"][1]["content"][0]["text"]) == question.gold
        assert question.question in row["conversations"][0]["value"]


def test_the_rationale_reasons_from_the_observer_to_the_option_it_names(generated_release, tmp_path):
    out = tmp_path / "cot"
    export_training_set(generated_release, out, ExportOptions(format="messages", task="multi-hop", conditions=("a",), split="1,0,0"), check_release=False)
    rows = [json.loads(line) for p in sorted((out / "messages").glob("*.jsonl")) for line in p.read_text().splitlines()]
    asked = _asked(generated_release, "multi-hop")
    for row in rows:
        text, question = row["conversations"][1]["value"], asked[row["id"]].question
        facts = json.loads(row["facts"])
        assert f"Observer: in Image {facts['frame_index']} the speaker" in text and "Intermediate: the " in text
        assert text.splitlines()[-2] == f"Conclusion: {dict(question.options)[question.gold]}, option {question.gold}."
        assert f"target is {spec_of(row['direction']).paper_words} the " in text


def test_an_openai_export_answers_each_question_with_its_gold_label(generated_release, tmp_path):
    out = tmp_path / "openai"
    report = export_training_set(generated_release, out, ExportOptions(format="openai", task="relation", conditions=("c",), split="1,0,0"), check_release=False)
    lines = [json.loads(line) for p in sorted((out / "openai").glob("*.jsonl")) for line in p.read_text().splitlines()]
    gold = {plain_text(i.question): i.question.gold for i in _asked(generated_release, "relation").values() if i.condition.value == "c"}
    assert len(lines) == report.examples > 0
    for line in lines:
        user, assistant = line["messages"]
        text = "\n".join(p["text"] for p in user["content"] if p["type"] == "text")
        images = [p for p in user["content"] if p["type"] == "image_url"]
        assert len(images) == 1 and base64.b64decode(images[0]["image_url"]["url"].split(",", 1)[1])[:4] == b"\x89PNG"
        assert _label(assistant["content"]) == gold[text]


def test_an_hf_export_answers_each_question_with_its_gold_label(generated_release, tmp_path):
    pq = pytest.importorskip("pyarrow.parquet", reason="the hf format needs pyarrow (the train extra)")
    out = tmp_path / "hf"
    export_training_set(generated_release, out, ExportOptions(format="hf", task="relation", conditions=("c",), split="1,0,0"), check_release=False)
    rows = [r for p in sorted((out / "data").glob("*.parquet")) for r in pq.read_table(p).to_pylist()]
    asked = _asked(generated_release, "relation")
    assert rows and all(json.loads(r["answer"]) == {"choice": asked[r["id"]].question.gold} for r in rows)


def test_a_task_export_leaves_evaluation_houses_out(generated_release, tmp_path, copy_house):
    house = sorted(p for p in (generated_release / "artifacts").iterdir() if p.is_dir())[0]
    evaluation = tmp_path / "eval"
    copy_house(house, evaluation, "eval_house_00900")
    options = ExportOptions(format="messages", task="relation", conditions=("c",), split="1,0,0")
    with pytest.raises(ExportError, match=f"{house.name} .*eval_house_00900"):
        export_training_set(generated_release, tmp_path / "refused", options, exclude=[evaluation], check_release=False)
    report = export_training_set(generated_release, tmp_path / "out", options, exclude=[evaluation], drop_excluded=True, check_release=False)
    rows = [json.loads(line) for p in sorted((tmp_path / "out" / "messages").glob("*.jsonl")) for line in p.read_text().splitlines()]
    assert list(report.excluded) == [house.name] and rows and all(r["house_id"] != house.name for r in rows)


def test_an_export_of_one_task_is_not_resumed_as_another(generated_release, tmp_path):
    out = tmp_path / "out"
    export_training_set(generated_release, out, ExportOptions(format="messages", task="relation", conditions=("c",)), check_release=False)
    with pytest.raises(ExportError, match="made with task='relation', not 'point'"):
        export_training_set(generated_release, out, ExportOptions(format="messages", conditions=("c",)), check_release=False)


def test_a_point_export_records_its_options_as_before_tasks(generated_release, tmp_path):
    export_training_set(generated_release, tmp_path / "out", ExportOptions(format="messages", conditions=("c",)), check_release=False)
    recorded = json.loads((tmp_path / "out" / "export.json").read_text())["options"]
    assert "task" not in recorded and recorded["rationale"] == "s-cot"


def test_export_train_names_the_task_on_the_command_line(generated_release, tmp_path):
    from typer.testing import CliRunner

    from povagent.cli import app

    out = tmp_path / "cli"
    args = ["export-train", str(generated_release), "--out", str(out), "--format", "messages", "--task", "relation", "--conditions", "c", "--rationale", "none"]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output
    rows = [json.loads(line) for p in sorted((out / "messages").glob("*.jsonl")) for line in p.read_text().splitlines()]
    assert rows and all(set(json.loads(r["answer"])) == {"choice"} and r["conversations"][1]["value"] == r["answer"] for r in rows)
    assert json.loads((out / "export.json").read_text())["options"]["task"] == "relation"
