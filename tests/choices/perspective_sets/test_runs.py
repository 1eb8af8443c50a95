"""A choice run scores each set end to end: the runner, the choice strategy, parser and scorer."""

from __future__ import annotations

import json

import pytest

from povagent.config.pipeline import load_pipeline
from povagent.results.rows import read_rows
from povagent.run.runner import run_pipeline

#: The fixtures' gold labels, in file order.
GOLD = {"viewspatial": "ABAC", "mindcube": "ACB", "3dsrbench": "ABBAAA"}


def _accuracy(result, scorer: str = "choice", metric: str = "accuracy") -> float:
    return result.summary.metrics[scorer].overall[metric].value


@pytest.mark.parametrize("format", sorted(GOLD))
def test_the_oracle_scores_every_question_of_a_set(choice_pipeline, format):
    result = run_pipeline(load_pipeline(choice_pipeline(format)))
    assert result.n_total == len(GOLD[format])
    assert _accuracy(result) == 1.0


@pytest.mark.parametrize("format", sorted(GOLD))
def test_always_answering_a_scores_the_share_of_gold_a(choice_pipeline, format):
    result = run_pipeline(load_pipeline(choice_pipeline(format, backend="test-center", reply="A")))
    assert _accuracy(result) == pytest.approx(GOLD[format].count("A") / len(GOLD[format]), abs=1e-12)


def test_a_choice_run_writes_no_direction_or_condition_and_breaks_down_by_category(choice_pipeline):
    result = run_pipeline(load_pipeline(choice_pipeline("mindcube", backend="test-center", reply="A")))
    rows = read_rows(result.run_dir / "results.jsonl")
    assert {(r.direction, r.condition) for r in rows} == {("", "")}
    metrics = result.summary.metrics["choice"]
    assert metrics.per_condition == {} and metrics.per_direction == {}
    assert {k: v["accuracy"].value for k, v in metrics.per_category.items()} == {"among": 1.0, "around": 0.0, "rotation": 0.0}


def test_3dsrbench_reports_its_four_accuracies_as_the_set_defines_them(choice_pipeline):
    # always "A": right on QUES0001, QUES0001-flip-1, QUES0002, QUES0002-flip; wrong on QUES0001-1, QUES0001-flip
    result = run_pipeline(load_pipeline(choice_pipeline("3dsrbench", backend="test-center", reply="A", scorers=("choice-3dsrbench",))))
    overall = result.summary.metrics["choice-3dsrbench"].overall
    assert overall["vanilla_accuracy"].value == pytest.approx(4 / 6)
    # pairs (Q1, Q1-flip) wrong, (Q1-1, Q1-flip-1) wrong, (Q2, Q2-flip) right
    assert overall["flip_accuracy"].value == pytest.approx(1 / 3) and overall["flip_accuracy"].n == 3
    # sets {Q1, Q1-1} wrong, {Q1-flip, Q1-flip-1} wrong, {Q2} right, {Q2-flip} right
    assert overall["circular_accuracy"].value == pytest.approx(2 / 4) and overall["circular_accuracy"].n == 4
    # questions Q1 wrong, Q2 right
    assert overall["flip_circular_accuracy"].value == pytest.approx(1 / 2) and overall["flip_circular_accuracy"].n == 2


def test_the_3dsrbench_oracle_scores_all_four_accuracies_perfect(choice_pipeline):
    result = run_pipeline(load_pipeline(choice_pipeline("3dsrbench", scorers=("choice-3dsrbench",))))
    overall = result.summary.metrics["choice-3dsrbench"].overall
    assert {name: cell.value for name, cell in overall.items()} == {
        "vanilla_accuracy": 1.0, "flip_accuracy": 1.0, "circular_accuracy": 1.0, "flip_circular_accuracy": 1.0, "response_rate": 1.0,
    }  # fmt: skip


def test_a_point_scorer_on_a_choice_set_is_refused_before_any_request(choice_pipeline):
    from povagent.errors import ConfigError

    with pytest.raises(ConfigError, match="needs a point ground truth"):
        run_pipeline(load_pipeline(choice_pipeline("viewspatial", scorers=("choice", "official"))))


def test_the_summary_json_of_a_choice_run_holds_the_category_slices(choice_pipeline):
    result = run_pipeline(load_pipeline(choice_pipeline("viewspatial")))
    written = json.loads((result.run_dir / "summary.json").read_text())
    assert set(written["metrics"]["choice"]["per_category"]) == {
        "Camera perspective - Relative Direction", "Person perspective - Object View Orientation",
        "Person perspective - Scene Simulation Relative Direction",
    }  # fmt: skip


def test_rescoring_a_3dsrbench_run_gives_its_four_accuracies_again(choice_pipeline):
    from povagent.run.rescore import rescore_run

    config = load_pipeline(choice_pipeline("3dsrbench", backend="test-center", reply="A", scorers=("choice-3dsrbench",)))
    result = run_pipeline(config)
    again = rescore_run(result.run_dir, "choice", plugins=config.plugins)
    assert again.summary.metrics["choice-3dsrbench"] == result.summary.metrics["choice-3dsrbench"]


def test_the_console_table_of_a_choice_run_has_a_row_per_category(choice_pipeline):
    from povagent.cli.metrics_table import metrics_rows

    result = run_pipeline(load_pipeline(choice_pipeline("mindcube", backend="test-center", reply="A")))
    _, rows = metrics_rows(result.summary.metrics["choice"])
    assert [row[0] for row in rows] == ["overall", "category 'among'", "category 'around'", "category 'rotation'"]


def test_a_report_of_a_choice_run_is_written(choice_pipeline):
    from typer.testing import CliRunner

    from povagent.cli import app

    result = run_pipeline(load_pipeline(choice_pipeline("viewspatial")))
    outcome = CliRunner().invoke(app, ["report", str(result.run_dir)])
    assert outcome.exit_code == 0, outcome.output
    assert (result.run_dir / "report" / "report.html").is_file()


def test_the_report_gives_3dsrbench_grouped_accuracies_as_the_run_summary_does(choice_pipeline):
    from typer.testing import CliRunner

    from povagent.cli import app

    result = run_pipeline(load_pipeline(choice_pipeline("3dsrbench", backend="test-center", reply="A", scorers=("choice-3dsrbench",))))
    outcome = CliRunner().invoke(app, ["report", str(result.run_dir)])
    assert outcome.exit_code == 0, outcome.output
    reported = json.loads((result.run_dir / "report" / "summary.json").read_text())["metrics"]["choice-3dsrbench"]
    (system,) = reported
    overall = result.summary.metrics["choice-3dsrbench"].overall
    for name in ("flip_accuracy", "circular_accuracy", "flip_circular_accuracy"):
        assert reported[system]["overall"][name]["value"] == pytest.approx(overall[name].value), name
        assert reported[system]["overall"][name]["n"] == overall[name].n, name
