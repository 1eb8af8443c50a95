"""A metric over some rows only (``Metric.select``): a row counts when its pair id holds the
pattern, as MMSI-Bench's circular evaluation reports its vanilla accuracy over each question's
first copy; every other row, and a row with no pair id, does not count."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from povagent.scoring.metric_columns import metrics_breakdown
from povagent.scoring.metrics import Metric, MetricValues, row_metric_values, valued_row

FIRST = Metric("first_copy", "higher", "rate", "correct", "First copy", "first copies right", over="all", select=r"^\d{1,6}$")
DECLARED = {"mine": (FIRST,)}


def row(pair_id, correct: bool | None):
    """A row; ``correct=None``: an unreadable answer, which no scorer scored."""
    scores = {} if correct is None else {"mine": {"correct": correct, "answered": True}}
    return SimpleNamespace(status="parse_error" if correct is None else "answered", scores=scores, condition="", direction="", pair_id=pair_id, run=0)


def test_a_row_whose_pair_id_does_not_hold_the_pattern_does_not_count():
    assert row_metric_values(row("1000003", True), DECLARED) == {"mine": {"first_copy": None}}


def test_a_selected_row_counts_as_it_would_unselected_an_unreadable_answer_wrong():
    assert row_metric_values(row("3", True), DECLARED) == {"mine": {"first_copy": 1.0}}
    assert row_metric_values(row("3", None), DECLARED) == {"mine": {"first_copy": 0.0}}


def test_a_row_with_no_pair_id_does_not_count():
    assert MetricValues.of(row(None, True), DECLARED)["mine"]["first_copy"] is None


def test_the_overall_is_over_the_selected_rows_alone():
    rows = [row("1", True), row("1000001", False), row("2", False), row("1000002", True), row("3", True)]
    cell = metrics_breakdown([valued_row(r, DECLARED) for r in rows], DECLARED, n_boot=50)["mine"]["overall"]["first_copy"]
    assert cell["value"] == pytest.approx(2 / 3) and cell["n"] == 3


def test_a_selecting_metric_says_its_pattern_and_reads_back():
    assert FIRST.describe()["select"] == r"^\d{1,6}$"
    assert Metric.declared("first_copy", FIRST.describe()) == FIRST
    assert "select" not in Metric("plain", "higher", "rate", "correct", "Plain", "plain").describe()
