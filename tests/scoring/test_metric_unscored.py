"""A mean over every row may say what a row its scorer did not score counts as (``unscored``):
VSI-Bench scores a reply its rule reads nothing in 0, so its MRA mean counts such a row as 0."""

from __future__ import annotations

from povagent.scoring.metrics import Metric, metric_value

SCORE = Metric("score", "higher", "mean", "score", "Score", "per question", over="all", unscored=0.0)


def test_a_row_the_scorer_did_not_score_counts_as_the_declared_value():
    assert metric_value(SCORE, None, answered=False) == 0.0
    assert metric_value(SCORE, {"answered": True, "score": 0.7}, answered=True) == 0.7


def test_without_a_declared_value_such_a_row_is_left_out_as_before():
    plain = Metric("score", "higher", "mean", "score", "Score", "per question", over="all")
    assert metric_value(plain, None, answered=False) is None


def test_the_declaration_round_trips_through_the_summary_and_is_said_only_when_set():
    assert Metric.declared("score", SCORE.describe()) == SCORE
    assert "unscored" not in Metric("m", "higher", "mean", "m", "M", "c").describe()
