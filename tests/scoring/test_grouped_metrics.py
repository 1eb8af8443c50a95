"""A metric over groups (3DSRBench's copies of a question): a group is a hit only when every
row of it is, and a breakdown slices rows by the question's category when they have one."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from povagent.scoring.metrics import Metric, metrics_breakdown, valued_row

ALL_RIGHT = Metric("all_right", "higher", "rate", "correct", "All copies right", "groups all right", over="all", group="set")
DECLARED = {"mine": (ALL_RIGHT,)}


def row(correct: bool, group: str | None, category: str = "", run: int = 0):
    fields = {"correct": correct, "answered": True, "category": category} | ({"set": group} if group is not None else {})
    return SimpleNamespace(status="answered", scores={"mine": fields}, condition="", direction="", run=run)


def _overall(rows):
    return metrics_breakdown([valued_row(r, DECLARED) for r in rows], DECLARED, n_boot=50)["mine"]["overall"]["all_right"]


def test_a_group_is_right_only_when_every_row_of_it_is():
    cell = _overall([row(True, "q1"), row(False, "q1"), row(True, "q2"), row(True, "q2")])
    assert cell["value"] == pytest.approx(1 / 2) and cell["n"] == 2


def test_a_row_without_a_group_counts_as_a_group_of_its_own():
    cell = _overall([row(True, None), row(False, None), row(True, "q1")])
    assert cell["value"] == pytest.approx(2 / 3) and cell["n"] == 3


def test_the_same_group_in_two_runs_counts_once_per_run():
    cell = _overall([row(True, "q1", run=0), row(False, "q1", run=1)])
    assert cell["value"] == pytest.approx(1 / 2) and cell["n"] == 2


def test_a_grouped_metric_says_its_group_field_and_reads_back():
    assert ALL_RIGHT.describe()["group"] == "set"
    assert Metric.declared("all_right", ALL_RIGHT.describe()) == ALL_RIGHT


def test_rows_with_a_category_and_no_condition_break_down_by_category_only():
    rows = [row(True, "q1", "height"), row(False, "q2", "height"), row(True, "q3", "location")]
    out = metrics_breakdown([valued_row(r, DECLARED) for r in rows], DECLARED, n_boot=50)["mine"]
    assert out["per_condition"] == {} and out["per_direction"] == {} and out["per_condition_direction"] == {}
    assert {k: v["all_right"]["value"] for k, v in out["per_category"].items()} == {"height": 0.5, "location": 1.0}


def test_rows_without_a_category_have_no_category_slices():
    out = metrics_breakdown([valued_row(row(True, "q1"), DECLARED)], DECLARED, n_boot=50)["mine"]
    assert "per_category" not in out
