"""The report of multiple-choice runs: accuracy per category with CIs, paired differences,
the confusion of chosen vs gold labels, each table naming the rule that read it; and no pixel
table for a choice system beside a point run.

The runs are real: the ViewSpatial fixture (gold A, B, A, C; categories Camera Relative
Direction for questions 1 and 4, Scene Simulation for 2, Object View Orientation for 3)
answered by the ``oracle``, by a model always answering "A" and by one naming no option.
"""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from povagent.config.pipeline import load_pipeline
from povagent.report.build import write_report
from povagent.run.runner import run_pipeline

CAMERA = "Camera perspective - Relative Direction"
SCENE = "Person perspective - Scene Simulation Relative Direction"
OBJECT = "Person perspective - Object View Orientation"


def _run_systems(choice_pipeline, folder: Path, systems: tuple[tuple, ...]) -> Path:
    for label, backend, reply, *parser in systems:
        path = choice_pipeline("viewspatial", backend=backend, reply=reply)
        data = yaml.safe_load(path.read_text()) | {"label": label, "output": str(folder / label)} | ({"parser": parser[0]} if parser else {})
        path.write_text(yaml.safe_dump(data, sort_keys=False))
        run_pipeline(load_pipeline(path))
    return folder


@pytest.fixture
def runs_folder(tmp_path, choice_pipeline):
    """``runs_folder(*(label, backend, reply[, parser])) -> Path``: a folder of real choice runs on
    the ViewSpatial fixture, each run labelled (read by the set's rule unless a parser is named)."""
    return lambda *systems: _run_systems(choice_pipeline, tmp_path / "runs", systems)


def _module_report(module_choice_pipeline, tmp_path_factory, *systems: tuple):
    folder = tmp_path_factory.mktemp("choice-report")
    runs = _run_systems(module_choice_pipeline, folder / "runs", systems)
    return write_report(runs, folder / "report", gallery=False, n_boot=200)


@pytest.fixture(scope="module")
def oracle_and_always_a(module_choice_pipeline, tmp_path_factory):
    """The report of the oracle beside a model always answering "A": made once, read by the
    tests that look at those two systems."""
    return _module_report(module_choice_pipeline, tmp_path_factory, ("oracle", "oracle", None), ("always-a", "test-center", "A"))


@pytest.fixture(scope="module")
def always_a_and_silent(module_choice_pipeline, tmp_path_factory):
    """The report of the model always answering "A" beside one naming no option (made once)."""
    return _module_report(module_choice_pipeline, tmp_path_factory, ("always-a", "test-center", "A"), ("silent", "test-center", "no idea"))


def _table(result, key: str):
    return next(t for t in result.tables if t.key == key)


def _values(table, label: str) -> dict[str, float | None]:
    row = next(r for r in table.rows if r.label == label)
    return {c.name: cell.value for c, cell in zip(table.columns, row.cells)}


def test_the_accuracy_table_gives_each_systems_accuracy_per_category(oracle_and_always_a):
    result = oracle_and_always_a
    table = _table(result, "choice_accuracy_choice")
    assert _values(table, "oracle") == {CAMERA: 1.0, OBJECT: 1.0, SCENE: 1.0, "All": 1.0}
    # always "A": right on questions 1 and 3 (gold A), wrong on 2 (B) and 4 (C)
    assert _values(table, "always-a") == {CAMERA: 0.5, OBJECT: 1.0, SCENE: 0.0, "All": 0.5}
    overall = next(r for r in table.rows if r.label == "always-a").cells[-1]
    assert overall.lo is not None and overall.hi is not None and overall.lo <= 0.5 <= overall.hi


def test_a_question_answered_with_no_option_counts_as_wrong(always_a_and_silent):
    result = always_a_and_silent
    assert _values(_table(result, "choice_accuracy_choice"), "silent") == {CAMERA: 0.0, OBJECT: 0.0, SCENE: 0.0, "All": 0.0}


def test_the_paired_table_gives_the_difference_on_the_same_questions(oracle_and_always_a):
    result = oracle_and_always_a
    # systems in the collection's order (run folders by name): always-a is A, oracle B
    table = _table(result, "choice_paired_choice")
    values = _values(table, "oracle vs always-a")
    # right on the 2 of 4 questions always-a gets wrong: +1 twice, 0 twice; the sign test over those 2
    assert values == {"Questions": 4, "Accuracy A": 0.5, "Accuracy B": 1.0, "B - A": pytest.approx(0.5), "Sign test p": 0.5}
    # the row reads as its header says: "B vs A", each accuracy under its own system's letter
    assert table.row_header == "B vs A" and "B - A > 0 means B is better" in table.caption


def test_the_confusion_table_counts_chosen_against_gold_labels_with_non_answers_apart(always_a_and_silent):
    result = always_a_and_silent
    always_a = _table(result, "choice_confusion_choice_1")
    assert "always-a" in always_a.title
    assert {r.label: [c.value for c in r.cells] for r in always_a.rows} == {"A": [2, 0, 0, 0], "B": [1, 0, 0, 0], "C": [1, 0, 0, 0]}
    assert [c.name for c in always_a.columns] == ["A", "B", "C", "no option"]
    silent = _table(result, "choice_confusion_choice_2")
    assert {r.label: [c.value for c in r.cells] for r in silent.rows} == {"A": [0, 0, 0, 2], "B": [0, 0, 0, 1], "C": [0, 0, 0, 1]}


def test_every_choice_table_names_the_rule_that_read_it(oracle_and_always_a):
    from povagent.plugins import get_plugin_host

    result = oracle_and_always_a
    described = f"Read by `viewspatial-official` ({get_plugin_host().entry('parser', 'viewspatial-official').description})."
    choice = [t for t in result.tables if t.key.startswith("choice_")]
    assert len(choice) == 4 and all(described in t.caption for t in choice)
    assert "ZJU-REAL" in described


def test_systems_read_by_different_rules_have_each_rule_named(runs_folder, tmp_path):
    result = write_report(runs_folder(("always-a", "test-center", "A", "vlmevalkit-exact"), ("oracle", "oracle", None)),
                          tmp_path / "report", gallery=False, n_boot=200)  # fmt: skip
    caption = _table(result, "choice_accuracy_choice").caption
    assert "`vlmevalkit-exact` (" in caption and "for always-a" in caption
    assert "`viewspatial-official` (" in caption and "for oracle" in caption


def test_a_choice_run_beside_a_point_run_has_no_pixel_table(runs_folder, tmp_path, mini_root):
    folder = runs_folder(("oracle", "oracle", None))
    point = tmp_path / "point.yaml"
    point.write_text(yaml.safe_dump({"dataset": {"path": str(mini_root)}, "backend": "oracle", "strategy": "basic", "scorers": ["official"],
                                     "label": "pointer", "runs": 1, "concurrency": 2, "output": str(folder / "pointer")}))  # fmt: skip
    run_pipeline(load_pipeline(point))
    result = write_report(folder, tmp_path / "report", gallery=False, n_boot=200)
    pixel = [t for t in result.tables if any(c.kind == "l2" for c in t.columns)]
    # the point run, and the center guess the report computes on its set (both sets load)
    assert pixel and all(r.label.startswith(("pointer", "Center baseline")) for t in pixel for r in t.rows)
    assert [r.label for r in _table(result, "choice_accuracy_choice").rows] == ["oracle"]


def test_the_reports_summary_json_holds_the_choice_tables_numbers(runs_folder, tmp_path):
    import json

    result = write_report(runs_folder(("always-a", "test-center", "A"),), tmp_path / "report", gallery=False, n_boot=200)
    summary = json.loads((result.out / "summary.json").read_text(encoding="utf-8"))
    accuracy = summary["tables"]["choice_accuracy_choice"]
    assert accuracy["columns"] == [CAMERA, OBJECT, SCENE, "All"]
    assert [cell["value"] for cell in accuracy["rows"]["always-a"]] == [0.5, 1.0, 0.0, 0.5]
    confusion = summary["tables"]["choice_confusion_choice_1"]["rows"]
    assert {gold: [c["value"] for c in cells] for gold, cells in confusion.items()} == {"A": [2, 0, 0, 0], "B": [1, 0, 0, 0], "C": [1, 0, 0, 0]}


def test_a_set_without_conditions_is_plotted_overall_on_an_axis_from_0_to_1(oracle_and_always_a):
    import re

    result = oracle_and_always_a
    plots = sorted((result.out / "plots").glob("*.svg"))
    assert plots and not any("condition" in p.name for p in plots)
    svg = (result.out / "plots" / "metric_choice_accuracy.svg").read_text(encoding="utf-8")
    assert "by condition" not in svg
    ticks = [float(t) for t in re.findall(r'text-anchor="end">([0-9.]+)</text>', svg)]
    assert min(ticks) == 0.0 and max(ticks) == 1.0  # an accuracy, whose CI reaches 1, on [0, 1]


def test_two_labelled_systems_that_answered_alike_are_both_shown(runs_folder, tmp_path):
    result = write_report(runs_folder(("oracle", "oracle", None), ("oracle-again", "oracle", None)), tmp_path / "report", gallery=False, n_boot=200)
    assert [s.system for s in result.analysis.systems] == ["oracle", "oracle-again"]
    assert not any("shown once" in note for note in result.analysis.notes)
    assert [r.label for r in _table(result, "choice_accuracy_choice").rows] == ["oracle", "oracle-again"]
