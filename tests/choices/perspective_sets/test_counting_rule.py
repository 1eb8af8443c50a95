"""One counting rule in every command: a reply naming no option is a wrong answer in every slice.

The ViewSpatial-Bench fixture (gold A, B, A, C; question 1 and 4 in the camera category, 2 in
scene simulation, 3 in object orientation) is answered "A" (right), a refusal, "B" (wrong) and
a refusal; ``run``, ``rescore`` and ``report`` must then give the same numbers, overall and per
category, with the refusals counted wrong and the response rate of each slice real.
"""

from __future__ import annotations

import json

import pytest
import yaml

from povagent.config.pipeline import load_pipeline
from povagent.run.runner import run_pipeline

CAMERA = "Camera perspective - Relative Direction"
SCENE = "Person perspective - Scene Simulation Relative Direction"
OBJECT = "Person perspective - Object View Orientation"
REPLIES = ("A", "I cannot tell from these pictures.", "B", "no idea")
#: accuracy and response rate, overall and per category, for the replies above
EXPECTED = {
    "overall": (1 / 4, 2 / 4),
    CAMERA: (1 / 2, 1 / 2),
    SCENE: (0.0, 0.0),
    OBJECT: (0.0, 1.0),
}


@pytest.fixture
def mixed_run(choice_pipeline, queued_backend, tmp_path):
    """A run of the ViewSpatial fixture answered by :data:`REPLIES`, in order."""
    path = choice_pipeline("viewspatial", backend="queued")
    data = yaml.safe_load(path.read_text()) | {"concurrency": 1, "parser": "viewspatial"}
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    queued_backend.queue(*REPLIES)
    return run_pipeline(load_pipeline(path))


def _numbers(metrics) -> dict[str, tuple[float, float]]:
    cells = {"overall": metrics.overall, **(metrics.per_category or {})}
    return {name: (cell["accuracy"].value, cell["response_rate"].value) for name, cell in cells.items()}


def test_a_reply_naming_no_option_is_wrong_in_its_category_in_the_run_summary(mixed_run):
    assert _numbers(mixed_run.summary.metrics["choice"]) == EXPECTED


def test_summary_json_counts_every_question_of_each_category(mixed_run):
    written = json.loads((mixed_run.run_dir / "summary.json").read_text())["metrics"]["choice"]["per_category"]
    assert {name: cell["accuracy"]["n"] for name, cell in written.items()} == {CAMERA: 2, SCENE: 1, OBJECT: 1}


def test_rescore_gives_the_run_s_numbers(mixed_run):
    from povagent.run.rescore import rescore_run

    again = rescore_run(mixed_run.run_dir, "viewspatial")
    assert _numbers(again.summary.metrics["choice"]) == EXPECTED


def test_the_report_gives_the_run_s_accuracies(mixed_run, tmp_path):
    from povagent.report.build import write_report

    result = write_report(mixed_run.run_dir, tmp_path / "report", gallery=False, n_boot=200)
    table = next(t for t in result.tables if t.key == "choice_accuracy_choice")
    (row,) = table.rows
    reported = {c.name: cell.value for c, cell in zip(table.columns, row.cells)}
    assert reported == {"All": EXPECTED["overall"][0], **{k: v[0] for k, v in EXPECTED.items() if k != "overall"}}


def test_the_console_table_shows_the_run_s_per_category_numbers(mixed_run):
    from povagent.cli.metrics_table import metric_cell, metrics_rows

    _, rows = metrics_rows(mixed_run.summary.metrics["choice"])
    shown = {row[0]: row[1:] for row in rows}
    cells = {"overall": mixed_run.summary.metrics["choice"].overall, **mixed_run.summary.metrics["choice"].per_category}
    for name, (accuracy, response) in EXPECTED.items():
        label = name if name == "overall" else f"category {name!r}"
        assert cells[name]["accuracy"].value == accuracy and cells[name]["response_rate"].value == response
        assert shown[label] == [metric_cell(cells[name]["accuracy"], "rate"), metric_cell(cells[name]["response_rate"], "rate")]


def test_a_choice_run_s_point_breakdown_claims_no_parse_error_and_no_response_rate(mixed_run):
    written = json.loads((mixed_run.run_dir / "summary.json").read_text())
    assert written["overall"]["n_parse_error"] == 0 and written["n_parse_error"] == 0
    assert written["overall"]["response_rate"] is None and written["overall"]["n_total"] == 0


def test_the_report_s_declared_metrics_give_the_run_s_numbers_per_category(mixed_run, tmp_path):
    from povagent.report.build import write_report

    write_report(mixed_run.run_dir, tmp_path / "report", gallery=False, n_boot=200)
    (system,) = (reported := json.loads((tmp_path / "report" / "summary.json").read_text())["metrics"]["choice"]).values()
    cells = {"overall": system["overall"], **system["per_category"]}
    assert {k: (c["accuracy"]["value"], c["response_rate"]["value"]) for k, c in cells.items()} == EXPECTED
    assert len(reported) == 1
