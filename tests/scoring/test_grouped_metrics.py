"""A metric over groups (3DSRBench's copies of a question): rows whose pair ids match once the
metric's ``group`` pattern is removed form a group, a hit only when every row of it is; and a
breakdown slices rows by the question's category when they have one."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from povagent.scoring.metric_columns import metrics_breakdown
from povagent.scoring.metrics import Metric, valued_row

ALL_RIGHT = Metric("all_right", "higher", "rate", "correct", "All copies right", "groups all right", over="all", group=r"-flip")
DECLARED = {"mine": (ALL_RIGHT,)}


def row(pair_id: str, correct: bool | None, category: str = "", run: int = 0):
    """A row of ``pair_id`` (its question's ``category`` recorded, as a row records it whatever the
    answer); ``correct=None``: an unreadable answer, which no scorer scored."""
    scores = {} if correct is None else {"mine": {"correct": correct, "answered": True, "category": category}}
    status = "parse_error" if correct is None else "answered"
    return SimpleNamespace(status=status, scores=scores, condition="", direction="", pair_id=pair_id, run=run, category=category)


def _overall(rows):
    return metrics_breakdown([valued_row(r, DECLARED) for r in rows], DECLARED, n_boot=50)["mine"]["overall"]["all_right"]


def test_a_group_is_right_only_when_every_row_of_it_is():
    cell = _overall([row("q1", True), row("q1-flip", False), row("q2", True), row("q2-flip", True)])
    assert cell["value"] == pytest.approx(1 / 2) and cell["n"] == 2


def test_the_group_is_the_pair_id_with_the_pattern_removed():
    cell = _overall([row("q1-2", True), row("q1-flip-2", True), row("q1", False)])
    assert cell["value"] == pytest.approx(1 / 2) and cell["n"] == 2  # {q1-2, q1-flip-2} right, {q1} wrong


def test_an_unreadable_answer_sinks_its_group():
    cell = _overall([row("q1", True), row("q1-flip", None)])
    assert cell["value"] == 0.0 and cell["n"] == 1


def test_the_same_group_in_two_runs_counts_once_per_run():
    cell = _overall([row("q1", True, run=0), row("q1", False, run=1)])
    assert cell["value"] == pytest.approx(1 / 2) and cell["n"] == 2


def test_a_grouped_metric_says_its_group_and_reads_back():
    assert ALL_RIGHT.describe()["group"] == "-flip"
    assert Metric.declared("all_right", ALL_RIGHT.describe()) == ALL_RIGHT


def test_rows_with_a_category_and_no_condition_break_down_by_category_only():
    rows = [row("q1", True, "height"), row("q2", False, "height"), row("q3", True, "location")]
    out = metrics_breakdown([valued_row(r, DECLARED) for r in rows], DECLARED, n_boot=50)["mine"]
    assert out["per_condition"] == {} and out["per_direction"] == {} and out["per_condition_direction"] == {}
    assert {k: v["all_right"]["value"] for k, v in out["per_category"].items()} == {"height": 0.5, "location": 1.0}


def test_rows_without_a_category_have_no_category_slices():
    out = metrics_breakdown([valued_row(row("q1", True), DECLARED)], DECLARED, n_boot=50)["mine"]
    assert "per_category" not in out
