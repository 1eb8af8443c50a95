"""The choice tables of a question no system's row scored: its gold label and category come from
the set the runs name, and when that set cannot be opened the tables say why in one line.

The runs are real: a two-question ViewSpatial-Bench file (gold C, category "Camera ..." for
question 0; gold B, "Person ..." for question 1), asked of ``always-c`` (question 0 only: it
scores that one) and of ``silent``, which names no option on either, so no row scores question 1.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
import yaml
from PIL import Image

from povagent.config.pipeline import load_pipeline
from povagent.report.build import write_report
from povagent.report.choice_tables import UNKNOWN
from povagent.run.runner import run_pipeline

CAMERA = "Camera perspective - Relative Direction"
PERSON = "Person perspective - Object View Orientation"
RECORDS = [
    {"question_type": CAMERA, "image_path": ["images/one.png"], "question": "Where is the lamp from the camera?",
     "answer": "C. front", "choices": "A. back\nB. right\nC. front\nD. left"},
    {"question_type": PERSON, "image_path": ["images/two.png"], "question": "Which way does the chair face for her?",
     "answer": "B. away from her", "choices": "A. towards her\nB. away from her\nC. to her left\nD. to her right"},
]  # fmt: skip


@pytest.fixture
def set_file(tmp_path) -> Path:
    """The two-question set, beside the tiny images it names."""
    folder = tmp_path / "set"
    (folder / "images").mkdir(parents=True)
    for shade, name in enumerate(("one", "two")):
        Image.new("RGB", (8, 6), (60 * shade, 40, 60)).save(folder / "images" / f"{name}.png")
    file = folder / "viewspatial.json"
    file.write_text(json.dumps(RECORDS), encoding="utf-8")
    return file


@pytest.fixture
def runs_folder(tmp_path, set_file, offline_plugin_file):
    """``runs_folder(*(label, reply, instances)) -> Path``: real runs of the ``test-center``
    backend giving that reply on the set (``instances``: the pipeline's selection)."""

    def make(*systems: tuple[str, str, dict]) -> Path:
        folder = tmp_path / "runs"
        for label, reply, instances in systems:
            config = tmp_path / f"{label}.yaml"
            config.write_text(yaml.safe_dump({
                "plugins": [str(offline_plugin_file)], "dataset": {"path": str(set_file), "format": "viewspatial"},
                "backend": {"name": "test-center", "options": {"reply": reply}}, "strategy": "choice", "scorers": ["choice"],
                "label": label, "runs": 1, "concurrency": 2, "timeout": 5, "output": str(folder / label),
                **({"instances": instances} if instances else {}),
            }))  # fmt: skip
            run_pipeline(load_pipeline(config))
        return folder

    return make


ALWAYS_C_ON_THE_FIRST = ("always-c", "C", {"limit": 1})
SILENT = ("silent", "no idea", {})


def _table(result, key: str):
    return next(t for t in result.tables if t.key == key)


def _confusion_rows(table) -> dict[str, list[int]]:
    return {r.label: [c.value for c in r.cells] for r in table.rows}


def test_a_question_no_row_scored_has_the_sets_gold_label_and_category(runs_folder, tmp_path):
    result = write_report(runs_folder(ALWAYS_C_ON_THE_FIRST, SILENT), tmp_path / "report", gallery=False, n_boot=200)
    silent = _table(result, "choice_confusion_choice_2")
    assert "silent" in silent.title
    assert [c.name for c in silent.columns] == ["B", "C", "no option"]
    assert _confusion_rows(silent) == {"B": [0, 0, 1], "C": [0, 0, 1]}
    accuracy = _table(result, "choice_accuracy_choice")
    assert [c.name for c in accuracy.columns] == [CAMERA, PERSON, "All"]
    assert "unknown" not in accuracy.caption


def test_a_set_that_cannot_be_opened_leaves_the_gold_unknown_and_says_why_in_one_line(runs_folder, set_file, tmp_path):
    folder = runs_folder(ALWAYS_C_ON_THE_FIRST, SILENT)
    shutil.rmtree(set_file.parent)
    result = write_report(folder, tmp_path / "report", gallery=False, n_boot=200)
    silent = _table(result, "choice_confusion_choice_2")
    assert _confusion_rows(silent) == {UNKNOWN: [0, 0, 1], "C": [0, 0, 1]}
    caption = _table(result, "choice_accuracy_choice").caption
    assert f"The gold label of 1 question is unknown because {set_file}: not found" in caption
    assert "\n" not in caption and "Traceback" not in caption


def test_a_set_named_by_several_runs_is_opened_once_per_report(runs_folder, set_file, tmp_path, monkeypatch):
    import povagent.dataset.evaluation_set as evaluation_set

    folder = runs_folder(ALWAYS_C_ON_THE_FIRST, SILENT, ("silent-too", "no option here", {}))
    opened: list[tuple[Path, str | None]] = []
    real = evaluation_set.open_evaluation_set
    monkeypatch.setattr(evaluation_set, "open_evaluation_set",
                        lambda root, **kw: opened.append((Path(root), kw.get("format"))) or real(root, **kw))  # fmt: skip
    result = write_report(folder, tmp_path / "report", gallery=False, n_boot=200)
    assert _confusion_rows(_table(result, "choice_confusion_choice_3")) == {"B": [0, 0, 1], "C": [0, 0, 1]}
    assert opened.count((set_file, "viewspatial")) == 1


def test_a_question_a_task_asks_has_the_gold_label_and_category_of_the_task(tmp_path, generated_release, offline_plugin_file):
    from collections import Counter

    from povagent.config.models import TaskSpec
    from povagent.dataset.loader import load_dataset
    from povagent.tasks.task_set import for_task

    folder = tmp_path / "runs"
    for label, backend, limit in (("oracle", {"name": "oracle"}, 1), ("silent", {"name": "test-center", "options": {"reply": "no idea"}}, 6)):
        config = tmp_path / f"{label}.yaml"
        config.write_text(yaml.safe_dump({
            "plugins": [str(offline_plugin_file)], "dataset": {"path": str(generated_release)}, "task": "relation",
            "backend": backend, "strategy": "choice", "scorers": ["choice"], "label": label, "runs": 1, "concurrency": 2,
            "timeout": 5, "instances": {"limit": limit}, "output": str(folder / label),
        }))  # fmt: skip
        run_pipeline(load_pipeline(config))
    asked = for_task(load_dataset(generated_release, check_images=False), TaskSpec(name="relation")).instances()[:6]
    result = write_report(folder, tmp_path / "report", gallery=False, n_boot=200)
    golds = Counter(i.question.gold for i in asked if i.question is not None)
    silent = _table(result, "choice_confusion_choice_2")
    assert {label: cells[-1] for label, cells in _confusion_rows(silent).items()} == golds
    categories = sorted({i.question.category for i in asked if i.question is not None})
    assert len(categories) > 1 and [c.name for c in _table(result, "choice_accuracy_choice").columns] == categories + ["All"]
